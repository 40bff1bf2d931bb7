// SPDX-License-Identifier: Apache-2.0
// Multi-view triangulation of a point from pixel observations in calibrated cameras: the one
// triangulation of the estimator (initiator, synchronous baseline) and the calibration.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"

namespace panoptes {

struct PixelObservation {
  const CameraModel* camera = nullptr;
  Eigen::Vector2d pixel;
};

struct Triangulated {
  Eigen::Vector3d point;
  double max_reprojection_px = 0;  // worst reprojection error over the observations
  double rms_reprojection_px = 0;
};

// Linear least squares on undistorted rays (the point nearest to all rays), then Gauss–Newton on
// the reprojection error through each camera's full model. nullopt if fewer than two observations,
// the rays are (near) parallel, or the point ends up behind a camera.
std::optional<Triangulated> triangulate(const std::vector<PixelObservation>& observations,
                                        int refine_iterations = 5);

// Reprojection error (px) of a point in a camera; +inf if behind it.
double reprojection_error(const CameraModel& camera, const Eigen::Vector3d& point,
                          const Eigen::Vector2d& pixel);

}  // namespace panoptes
