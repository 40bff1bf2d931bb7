// SPDX-License-Identifier: Apache-2.0
// Least-squares rotations and rigid transforms from point correspondences (Kabsch / Umeyama,
// without scale: nothing in Panoptes fits a similarity). Used by body identification, the
// monocular LED marker, and the calibration's alignments.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "panoptes/geometry.h"

namespace panoptes {

// The rotation nearest to M in the Frobenius norm (the polar factor, with the reflection fixed):
// U diag(1, 1, det(U Vᵀ)) Vᵀ from M's SVD.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M);

// Least-squares rigid transform T (no scale) with T·from[i] ≈ to[i]: the nearest rotation to the
// cross-covariance of the centred points (Umeyama 1991, "Least-squares estimation of
// transformation parameters between two point patterns", with c = 1), found in closed form
// (Horn's quaternion; the SVD for nearly collinear points). Needs ≥ 3 points not all
// collinear; `rms` receives the RMS residual. nullopt for fewer points, mismatched sizes or
// collinear points (the rotation about their line is undetermined).
std::optional<RigidTransform> fit_rigid_transform(const std::vector<Eigen::Vector3d>& from,
                                                  const std::vector<Eigen::Vector3d>& to,
                                                  double* rms = nullptr);

}  // namespace panoptes
