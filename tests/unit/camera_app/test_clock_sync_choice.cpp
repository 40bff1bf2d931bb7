// SPDX-License-Identifier: Apache-2.0
// Which cameras the live node synchronises in software: a PTP-timed camera's stamps are already on
// the common time base, so it gets no time-sync client (and no hold-until-synced).
#include <gtest/gtest.h>

#include "panoptes/camera/sources.h"
#include "panoptes/camera_app/live_camera.h"

namespace panoptes::camera_app {
namespace {

TEST(ClockSyncChoice, PtpTimedCamerasAndNoClockSyncSkipTheSoftwareSync) {
  LiveOptions options;
  camera::SourceInfo info;
  EXPECT_TRUE(uses_clock_sync(options, info));
  info.ptp_timed = true;
  EXPECT_FALSE(uses_clock_sync(options, info));
  info.ptp_timed = false;
  options.no_clock_sync = true;
  EXPECT_FALSE(uses_clock_sync(options, info));
}

}  // namespace
}  // namespace panoptes::camera_app
