// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "panoptes/camera/camera_status.h"
#include "panoptes/camera_app/status_message.h"

namespace panoptes::camera_app {
namespace {

TEST(StatusMessage, EveryFieldOfTheReportReachesTheMessage) {
  camera::CameraStatusReport report;
  report.camera_id = "cam2";
  report.stamp_ns = 11;
  report.fps = 239.5;
  report.frames = 12;
  report.drops_queue = 13;
  report.drops_source = 14;
  report.detect_p50_ms = 0.25;
  report.detect_p99_ms = 1.75;
  report.queue_depth = 3;
  report.threshold = 64;
  report.exposure_us = 500;
  report.gain_db = 6;
  report.clock_offset_ns = -15;
  report.clock_drift_ppm = 2.5;
  report.last_error = "frame 3 has no pixels";
  report.counters = {{"bad_frame", 2}, {"drops_queue", 13}};
  const msg::CameraStatus status = to_message(report);
  EXPECT_EQ(status.camera_id(), "cam2");
  EXPECT_EQ(status.stamp_ns(), 11);
  EXPECT_DOUBLE_EQ(status.fps(), 239.5);
  EXPECT_EQ(status.frames(), 12u);
  EXPECT_EQ(status.drops_queue(), 13u);
  EXPECT_EQ(status.drops_source(), 14u);
  EXPECT_DOUBLE_EQ(status.detect_p50_ms(), 0.25);
  EXPECT_DOUBLE_EQ(status.detect_p99_ms(), 1.75);
  EXPECT_EQ(status.queue_depth(), 3u);
  EXPECT_EQ(status.threshold(), 64);
  EXPECT_DOUBLE_EQ(status.exposure_us(), 500);
  EXPECT_DOUBLE_EQ(status.gain_db(), 6);
  EXPECT_EQ(status.clock_offset_ns(), -15);
  EXPECT_DOUBLE_EQ(status.clock_drift_ppm(), 2.5);
  EXPECT_EQ(status.last_error(), "frame 3 has no pixels");
  ASSERT_EQ(status.counters().size(), 2u);
  EXPECT_EQ(status.counters()[0].name(), "bad_frame");
  EXPECT_EQ(status.counters()[0].value(), 2u);
  EXPECT_EQ(status.counters()[1].name(), "drops_queue");
  EXPECT_EQ(status.counters()[1].value(), 13u);
}

}  // namespace
}  // namespace panoptes::camera_app
