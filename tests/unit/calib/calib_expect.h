// SPDX-License-Identifier: Apache-2.0
// The goals of issue 6's 8-camera room acceptance, shared by the calibration tests (GoogleTest; the
// benchmark uses calib_scenes.h only).
#pragma once

#include <cmath>

#include <gtest/gtest.h>

#include "calib_scenes.h"

namespace panoptes::calib::testing {

// Every camera calibrated, raw RMS <= 0.11 px per axis, positions <= 1 mm and rotations <= 0.02 deg
// after a rigid alignment, wand-length mean error <= 0.05 mm.
inline void expect_room_goals(const Measured& m, int cameras = 8) {
  ASSERT_TRUE(m.result.ok());
  EXPECT_EQ(m.result.calibrated_count(), cameras);
  EXPECT_LE(m.result.raw_rms_axis_px, 0.11);
  EXPECT_LE(m.max_position_error_mm, 1.0);
  EXPECT_LE(m.max_rotation_error_deg, 0.02);
  EXPECT_LE(std::abs(m.result.lengths.mean_error_mm), 0.05);
}

}  // namespace panoptes::calib::testing
