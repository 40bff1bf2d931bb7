// SPDX-License-Identifier: Apache-2.0
// The perspective-three-point problem: the poses of a calibrated camera that sees three known
// points along three given rays. Grunert's formulation (the one Haralick et al. 1994 review):
// with the distances along the rays s₂ = u s₁, s₃ = v s₁, the three law-of-cosines equations
// reduce to u linear in v and a quartic in v; each positive real root gives one pose (at most
// four), completed by the rigid fit of the three points. Used by inside-out tracking to find a
// moving camera's pose from landmarks without a prior.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "panoptes/geometry.h"

namespace panoptes {

// `bearings`: unit rays in the camera frame towards the points `points_world`. Returns every
// T_cam_world that puts the three points on their rays in front of the camera (0 to 4). Empty
// for collinear points or degenerate rays.
std::vector<RigidTransform> solve_p3p(const std::array<Eigen::Vector3d, 3>& bearings,
                                      const std::array<Eigen::Vector3d, 3>& points_world);

}  // namespace panoptes
