// SPDX-License-Identifier: Apache-2.0
// The synchronous snapshot solve of a rigid body's pose: every camera observes the body at the same
// instant, the marker correspondences are known, and Gauss–Newton minimises the sum of squared
// reprojection errors over all (camera, marker) observations, with no motion model and no memory.
// It is the reference the body filter is measured against (issue 16; docs/bodies.md,
// "Measurements"), as SyncBaseline is for points: for comparisons, not for production.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"
#include "panoptes/geometry.h"

namespace panoptes::estimator {

// One marker's centroid in one camera.
struct SnapshotObservation {
  std::size_t camera = 0;  // index into the cameras given to solve_snapshot_pose
  std::size_t marker = 0;  // index into the body's markers
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
};

struct SnapshotOptions {
  int max_iterations = 20;
  double step_tolerance = 1e-9;  // stop when |δp| (m) and |δθ| (rad) both fall below this
  std::size_t min_observations = 3;
};

struct SnapshotPose {
  RigidTransform T_world_body;
  int iterations = 0;
  bool converged = false;
  double rms_px = 0.0;  // reprojection error at the solution
  std::size_t observations = 0;
};

// Gauss–Newton on (p, δθ) with p_world = p + R exp(δθ) m, δθ folded into the rotation after every
// step; a step that raises the cost is halved (up to 10 times). Nullopt with fewer than
// `min_observations` observations, when a marker falls behind a camera, or when the normal
// equations are singular (e.g. all observations of one marker).
std::optional<SnapshotPose> solve_snapshot_pose(const std::vector<Eigen::Vector3d>& markers,
                                                const std::vector<CameraModel>& cameras,
                                                const std::vector<SnapshotObservation>& observations,
                                                const RigidTransform& initial,
                                                const SnapshotOptions& options = {});

}  // namespace panoptes::estimator
