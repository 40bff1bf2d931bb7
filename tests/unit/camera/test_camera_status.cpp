// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "panoptes/camera/camera_status.h"

namespace panoptes::camera {
namespace {

StatusInputs typical_inputs() {
  StatusInputs inputs;
  inputs.camera_id = "cam3";
  inputs.stamp_ns = 123;
  inputs.period_s = 1.25;
  inputs.frames = 1000;
  inputs.frames_in_period = 150;
  inputs.guided_frames = 40;
  inputs.queue_drops = 2;
  inputs.queue_depth = 1;
  inputs.source_counters = {{"timeout", 3}, {"incomplete", 4}};
  inputs.node_counters = {{"bad_frame", 1}, {"timeout", 1}};
  inputs.command_counters = {{"command_preview", 2}};
  inputs.detect_p50_ms = 0.4;
  inputs.detect_p99_ms = 1.5;
  inputs.threshold = 200;
  inputs.exposure_us = 800;
  inputs.gain_db = 3;
  inputs.source_last_error = "frame 9 incomplete";
  return inputs;
}

TEST(StatusAssembly, MergesCountersAndDerivesRatesAndSourceDrops) {
  const CameraStatusReport report = assemble_status(typical_inputs());
  EXPECT_EQ(report.camera_id, "cam3");
  EXPECT_EQ(report.stamp_ns, 123);
  EXPECT_DOUBLE_EQ(report.fps, 120.0);  // 150 frames in 1.25 s
  EXPECT_EQ(report.frames, 1000u);
  EXPECT_EQ(report.drops_source, 7u);  // the source's own counters only
  EXPECT_EQ(report.drops_queue, 2u);
  EXPECT_EQ(report.queue_depth, 1u);
  EXPECT_EQ(report.threshold, 200);
  EXPECT_DOUBLE_EQ(report.detect_p99_ms, 1.5);
  const CounterMap expected{{"bad_frame", 1},      {"command_preview", 2}, {"drops_queue", 2},
                            {"guided_frames", 40}, {"incomplete", 4},      {"timeout", 4}};
  EXPECT_EQ(report.counters, expected);
  EXPECT_EQ(report.last_error, "frame 9 incomplete");
  EXPECT_EQ(report.clock_offset_ns, 0);
}

TEST(StatusAssembly, TheNodesOwnErrorWinsOverTheSources) {
  StatusInputs inputs = typical_inputs();
  inputs.node_last_error = "command #3 rejected";
  EXPECT_EQ(assemble_status(inputs).last_error, "command #3 rejected");
}

TEST(StatusAssembly, APtpTimedCameraIsMarkedAndItsMarkIsNoDrop) {
  StatusInputs inputs = typical_inputs();
  EXPECT_EQ(assemble_status(inputs).counters.count("ptp_timed"), 0u);
  const std::uint64_t drops = assemble_status(inputs).drops_source;
  inputs.ptp_timed = true;
  const CameraStatusReport report = assemble_status(inputs);
  EXPECT_EQ(report.counters.at("ptp_timed"), 1u);
  EXPECT_EQ(report.drops_source, drops);
}

TEST(StatusAssembly, ClockSyncCountersOnlyWithAClientAndOffsetOnlyWhenSynchronised) {
  StatusInputs inputs = typical_inputs();
  inputs.injected_losses = 5;
  ClockSyncFigures sync;
  sync.offset_ns = 777;
  sync.drift_ppm = 12;
  sync.held = 30;
  sync.unsynchronised = 4;
  sync.lost = 1;
  inputs.clock_sync = sync;
  CameraStatusReport report = assemble_status(inputs);
  EXPECT_EQ(report.clock_offset_ns, 0);  // not synchronised yet
  EXPECT_EQ(report.counters.at("sync_held"), 30u);
  EXPECT_EQ(report.counters.at("unsynchronised"), 4u);
  EXPECT_EQ(report.counters.at("sync_lost"), 1u);
  EXPECT_EQ(report.counters.at("sync_resets"), 0u);
  EXPECT_EQ(report.counters.count("sync_hold_overflow"), 0u);  // only when it happened
  EXPECT_EQ(report.counters.at("injected_losses"), 5u);

  inputs.clock_sync->synchronised = true;
  inputs.clock_sync->hold_overflow = 9;
  report = assemble_status(inputs);
  EXPECT_EQ(report.clock_offset_ns, 777);
  EXPECT_DOUBLE_EQ(report.clock_drift_ppm, 12.0);
  EXPECT_EQ(report.counters.at("sync_hold_overflow"), 9u);

  const CameraStatusReport without = assemble_status(typical_inputs());
  EXPECT_EQ(without.counters.count("sync_held"), 0u);
  EXPECT_EQ(without.counters.count("injected_losses"), 0u);
}

TEST(StatusAssembly, FinalCountersAndTheirLogLine) {
  EXPECT_EQ(counters_line({}), "none");
  const CounterMap all = final_counters({{"timeout", 2}}, {{"bad_frame", 1}, {"timeout", 1}}, {}, 0);
  EXPECT_EQ(counters_line(all), "bad_frame=1 timeout=3");
  EXPECT_EQ(counters_line(final_counters({}, {}, {{"bad_command", 1}}, 4)),
            "bad_command=1 injected_losses=4");
}

TEST(Percentiles, NearestRankRoundedDownAndClear) {
  Percentiles values;
  EXPECT_EQ(values.at(0.5), 0.0);
  for (int v = 100; v >= 1; --v) values.add(v);
  EXPECT_EQ(values.at(0.0), 1.0);
  EXPECT_EQ(values.at(0.5), 50.0);  // rank floor(0.5 · 99) = 49
  EXPECT_EQ(values.at(0.99), 99.0);
  EXPECT_EQ(values.at(1.0), 100.0);
  values.clear();
  EXPECT_EQ(values.size(), 0u);
  EXPECT_EQ(values.at(0.99), 0.0);
}

}  // namespace
}  // namespace panoptes::camera
