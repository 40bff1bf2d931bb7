// SPDX-License-Identifier: Apache-2.0
// `calibrate world`'s scale check: known lengths (an L-frame's arms, the wand laid on the floor)
// as the calibration measures them, against their true values; a warning beyond a tolerance.
// docs/calibration.md, "Scale check".
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/geometry.h"

namespace panoptes::calib {

// Default relative tolerance of the scale check (1000 ppm: 0.5 mm on a 0.5 m arm).
inline constexpr double kScaleTolerance = 0.001;

struct ScaleCheck {
  int lengths = 0;
  double scale_error_ppm = 0;  // least-squares measured / known - 1, in parts per million
  double max_error_mm = 0;     // the largest measured - known of one length (signed)
  bool exceeded = false;       // |scale error| above the tolerance
};

// measured_m[i] against known_m[i] (the same count, known > 0): scale = sum(m k) / sum(k^2).
ScaleCheck check_scale(const std::vector<double>& measured_m, const std::vector<double>& known_m,
                       double tolerance = kScaleTolerance);

// One line: "scale check (<what>): ... ppm ... within/WARNING ...".
std::string scale_check_summary(const ScaleCheck& check, const std::string& what,
                                double tolerance = kScaleTolerance);

// The L-frame's arms as the calibration measures them: with `T_new_old` from lframe_frame, the
// markers nearest (x_arm, 0, 0) and (0, y_arm, 0) in the new frame, their distances from the one
// nearest the origin. Empty if `points` has fewer than 3.
std::vector<double> lframe_arm_lengths(const std::vector<Eigen::Vector3d>& points,
                                       const RigidTransform& T_new_old, double x_arm_m, double y_arm_m);

}  // namespace panoptes::calib
