// SPDX-License-Identifier: Apache-2.0
// Synthetic calibrated cameras for estimator tests.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/camera_model.h"
#include "panoptes/geometry.h"

namespace panoptes::estimator {

inline CameraIntrinsics test_intrinsics(bool distorted) {
  CameraIntrinsics intrinsics;
  intrinsics.width = 1280;
  intrinsics.height = 1024;
  intrinsics.fx = 1000;
  intrinsics.fy = 1000;
  intrinsics.cx = 639.5;
  intrinsics.cy = 511.5;
  if (distorted) intrinsics.distortion = {-0.12, 0.05, 0.001, -0.0005, -0.01};
  return intrinsics;
}

// `count` cameras on a circle of `radius` at `height`, looking at (0, 0, 1).
inline std::vector<CameraCalibration> make_ring_calibration(int count, double radius, double height,
                                                            bool distorted = false) {
  std::vector<CameraCalibration> cameras;
  for (int i = 0; i < count; ++i) {
    const double angle = 2.0 * M_PI * i / count + 0.3;
    CameraCalibration camera;
    camera.id = "cam" + std::to_string(i);
    camera.intrinsics = test_intrinsics(distorted);
    camera.T_world_cam = look_at(Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), height),
                                 Eigen::Vector3d(0, 0, 1));
    cameras.push_back(camera);
  }
  return cameras;
}

inline std::vector<CameraModel> make_ring_cameras(int count, double radius, double height,
                                                  bool distorted = false) {
  std::vector<CameraModel> models;
  for (const auto& camera : make_ring_calibration(count, radius, height, distorted))
    models.push_back(camera.model());
  return models;
}

}  // namespace panoptes::estimator
