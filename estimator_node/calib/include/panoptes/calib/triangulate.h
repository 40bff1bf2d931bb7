// SPDX-License-Identifier: Apache-2.0
// One point from calibrated cameras, as the wand solver's stages and the world-frame tools
// triangulate the wand's markers.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"

namespace panoptes::calib {

// Triangulates one point seen by calibrated cameras (panoptes/triangulation.h: linear, then
// Gauss-Newton on the pixel error). nullopt with fewer than two rays, (near) parallel rays or a
// point behind a camera.
std::optional<Eigen::Vector3d> triangulate(const std::vector<CameraModel>& models,
                                           const std::vector<Eigen::Vector2d>& pixels);

}  // namespace panoptes::calib
