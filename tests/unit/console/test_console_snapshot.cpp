// SPDX-License-Identifier: Apache-2.0
// ConsoleState's output byte for byte: a state with every kind of record (two cameras with info,
// status, features, windows, a preview and a calibration; the estimator; tracks of every status;
// a body; a tracking and an ambiguous chain with a grab; bad chain samples; a recorder that
// recorded and records again; a capture's coverage; commands applied, rejected and unanswered).
// data/snapshot_golden.txt is what the single-mutex ConsoleState (before the per-area models)
// wrote for the same calls, plus the body details' `stamp_ns` (added for issue 37) and, for issue
// 32, each camera's `status_age_s` and a received rate that counts frame intervals (100 fps for
// 101 frames 10 ms apart, where the first frame was counted too), and for issue 34 the estimator's
// camera health (its "cameras_live", "cameras_lost", "lost", "refused", "tracks_coasting",
// "tracks_unobserved"; a camera usage's "state", "since_last_frame_s", "refused_frames"): the page
// and /api/state see no other change.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "panoptes/console/console_state.h"

namespace panoptes::console {
namespace {

std::string golden() {
  const std::string path = std::string(PANOPTES_SOURCE_DIR) + "/tests/unit/console/data/snapshot_golden.txt";
  std::ifstream file(path, std::ios::binary);
  EXPECT_TRUE(file) << path;
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// The calls, and every output that does not depend on the wall clock.
std::string outputs() {
  constexpr TimeNs t0 = 1'700'000'000'000'000'000;
  ConsoleState state;
  std::ostringstream out;
  CameraInfoRecord info;
  info.model = "sim";
  info.backend = "sim";
  info.nominal_rate_hz = 100;
  info.geometry.width = 640;
  info.geometry.height = 480;
  info.geometry.K = {500, 501, 320, 240};
  state.on_info("cam0", info, t0);
  info.geometry.has_pose = true;
  info.geometry.T_world_cam.position = {1, 2, 3};
  state.on_info("cam1", info, t0);
  CameraStatusRecord status;
  status.fps = 99.44;
  status.frames = 1000;
  status.drops_queue = 2;
  status.detect_p99_ms = 0.12345;
  status.threshold = 200;
  status.exposure_us = 800;
  status.gain_db = 3;
  status.clock_offset_ns = 123456;
  status.clock_drift_ppm = 1.234;
  status.counters["command_set_threshold"] = 1;
  state.on_status("cam0", status, t0);
  state.on_command_sent({1, 10, "cam0", "set_threshold", 0, 0, t0});
  state.on_command_sent({1, 11, "cam0", "set_gain", 0, 0, t0});
  state.on_command_sent({2, 12, "cam0", "restart", 0, 0, t0});
  status.counters["command_set_threshold"] = 2;
  status.counters["bad_command"] = 1;
  status.last_error = "set_gain: not supported";
  status.drops_queue = 5;
  state.on_status("cam0", status, t0 + 500'000'000);
  for (int i = 0; i < 150; ++i)
    state.on_features(
        "cam0", {i + 1, t0 + static_cast<TimeNs>(i) * 10'000'000, {{10.123f, 20.456f, 5.55f}, {300, 200, 7}}},
        t0 + static_cast<TimeNs>(i) * 10'000'000 + 2'000'000);
  state.on_features("cam1", {5, t0, {{1, 2, 3}}}, t0 + 1'400'000'000);
  state.on_predictions("cam0", {{100.04F, 200.0F, 6.0F, 7.5F}}, t0 + 1'450'000'000);
  state.on_preview("cam1", t0 + 3, 2, 1, std::string("\x01\x02", 2));
  std::map<std::string, CameraGeometry> calibrated;
  CameraGeometry g;
  g.width = 640;
  g.height = 480;
  g.has_pose = true;
  g.T_world_cam.orientation = {0, 0, 1, 0};
  calibrated["cam1"] = g;
  state.on_calibration(calibrated);
  EstimatorRecord estimator{3, 1, 12.345, 0.6789, {{"cam0", {0.91234, 3.4567}}}};
  state.on_estimator(estimator, t0 + 1'000'000'000);
  std::vector<TrackPoint> tracks(3);
  for (int i = 0; i < 3; ++i) {
    tracks[i].id = 40 + i;
    tracks[i].position = {0.12345 * i, 1.0, 2.00005};
    tracks[i].status = static_cast<TrackStatus>(i);
    tracks[i].velocity = {0.3, 0.4, 0};
    tracks[i].covariance = {1e-6, 0, 0, 4e-6, 0, 9e-6};
    tracks[i].cameras = 3;
  }
  state.on_tracks(tracks, t0 + 1'200'000'000);
  state.on_tracks(tracks, t0 + 1'400'000'000);
  BodyRecord body{"head",    {{0.1, 0.2, 0.3}, {0, 0, 0.7071, 0.7071}}, 0.95f, {0.1, 0, 0},
                  {0, 0, 1}, {0.001, 0.002, 0.003, 0.01, 0.02, 0.03},   t0};
  state.on_body(body, t0 + 1'300'000'000);
  state.on_body(body, t0 + 1'450'000'000);
  ChainFrameRecord frame;
  ChainRecord finger;
  finger.name = "finger";
  finger.chain_id = 1;
  finger.status = ChainStatus::kTracking;
  finger.stamp_ns = t0 + 1'400'000'000;
  finger.angles = {0.1, 0.2};
  finger.markers = {{0, 0, 0}, {0.01, 0, 0}, {0.02, 0.000049, 0}, {0.03, 0, 0}};
  finger.marker_valid = {true, true, false, true};
  finger.tip = {0.04, 0, 0};
  finger.predicted_tip = {0.041, 0, 0};
  finger.prediction_horizon_ns = 80'000'000;
  finger.grabbing = true;
  ChainRecord lost = finger;
  lost.name = "thumb";
  lost.chain_id = 2;
  lost.status = ChainStatus::kAmbiguous;
  frame.chains = {finger, lost};
  ChainEventRecord grab{"finger", ChainEventKind::kGrab, t0, {0.04, 0, 0}, 0.5};
  frame.events = {grab};
  state.on_chains(frame, t0 + 1'400'000'000);
  ChainFrameRecord bad = frame;
  bad.chains[0].status = static_cast<ChainStatus>(7);
  state.on_chains(bad, t0 + 1'410'000'000);
  ChainFrameRecord bad_event = frame;
  bad_event.events[0].kind = static_cast<ChainEventKind>(3);
  state.on_chains(bad_event, t0 + 1'420'000'000);
  RecorderRecord idle;
  state.on_recorder_status("studio", idle, t0);
  state.on_recorder_command_sent({1, 5, "studio", true, t0});
  RecorderRecord recording{true, "/data/take_1.mcap", 3, 100, 4096, 50.55, "", {}};
  state.on_recorder_status("studio", recording, t0 + 100'000'000);
  RecorderRecord stopped{false, "/data/take_1.mcap", 3, 300, 8192, 0, "", {{"id_outside_partition", 7}}};
  state.on_recorder_status("studio", stopped, t0 + 1'100'000'000);
  state.on_recorder_status("studio", recording, t0 + 1'200'000'000);
  state.start_coverage(t0 + 1'000'000'000);
  state.add_coverage_frame("cam0", {{10, 10, 1}, {630, 470, 1}});
  state.add_coverage_frame("cam0", {});
  state.add_coverage_frame("camX", {{5, 5, 1}});
  state.set_calibration_job(R"({"step":"capture","log":["a"]})", R"({"step":"capture","report":1})");
  const TimeNs now = t0 + 1'500'000'000;
  out << state.snapshot(now, true).dump() << "\n";
  out << state.snapshot(now, false).dump() << "\n";
  for (const char* kind : {"track", "body", "chain", "planet"})
    for (const char* key : {"40", "42", "head", "finger", "thumb", "none"})
      out << kind << " " << key << " " << state.details(kind, key, now).dump() << "\n";
  for (const auto& o : state.take_outcomes(now))
    out << o.client << " " << o.request << " " << to_string(o.result) << " " << o.reason << "\n";
  for (const auto& o : state.take_outcomes(now + 5'000'000'000))
    out << o.client << " " << o.request << " " << to_string(o.result) << " " << o.reason << "\n";
  out << state.calibration_job() << " " << *state.preview_pgm("cam1") << " " << state.knows_camera("cam1")
      << state.knows_recorder("studio") << state.image_size("cam0")->first << "\n";
  return out.str();
}

TEST(ConsoleSnapshot, IsByteForByteWhatTheSingleMutexStateWrote) {
  const std::string expected = golden();
  const std::string actual = outputs();
  // Line by line first, so that a failure names the part that changed.
  std::istringstream expected_lines(expected);
  std::istringstream actual_lines(actual);
  std::string want;
  std::string got;
  for (int line = 1; std::getline(expected_lines, want); ++line) {
    ASSERT_TRUE(std::getline(actual_lines, got)) << "line " << line << " missing";
    EXPECT_EQ(got, want) << "line " << line;
  }
  EXPECT_EQ(actual, expected);
}

}  // namespace
}  // namespace panoptes::console
