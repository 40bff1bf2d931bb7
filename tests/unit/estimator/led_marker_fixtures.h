// SPDX-License-Identifier: Apache-2.0
// Shared by the 7-LED marker tests and bench_led_marker: the seed 004 prototype marker and the
// camera it was measured with, and a marker pose built from tilt, azimuth and roll.
#pragma once

#include <array>
#include <cmath>

#include <Eigen/Geometry>

#include "panoptes/geometry.h"

namespace panoptes::led_marker_fixtures {

constexpr double kFocal = 1600.0;  // px: 2048 x 2048 sensor, 5.5 um pixels, 9 mm lens (seed 004 §4.1)

// The seed's prototype marker (Table 1, rounded to an ideal layout): d03 = 114.2 mm, CR ~ 3.99.
// m1, m2 move the two inner LEDs of the dominant line (other cross-ratios, other marker ids).
inline std::array<Eigen::Vector3d, 7> paper_leds(double m1 = 0.0759, double m2 = 0.0379) {
  return {Eigen::Vector3d(0.1142, 0, 0),
          Eigen::Vector3d(m1, 0, 0),
          Eigen::Vector3d(m2, 0, 0),
          Eigen::Vector3d(0, 0, 0),
          Eigen::Vector3d(0, -0.038, 0),
          Eigen::Vector3d(0, 0.038, 0),
          Eigen::Vector3d(-0.0383, 0.0, -0.0112)};
}

// Marker at (x, y, z) in the camera, tilted by `tilt` about a horizontal axis at `azimuth`, after
// a roll about its own normal.
inline RigidTransform marker_pose(double x, double y, double z, double tilt, double azimuth, double roll) {
  RigidTransform T;
  T.q = Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(azimuth), std::sin(azimuth), 0)) *
        Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ());
  T.t = Eigen::Vector3d(x, y, z);
  return T;
}

}  // namespace panoptes::led_marker_fixtures
