// SPDX-License-Identifier: Apache-2.0
#include "panoptes/triangulation.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace panoptes {

double reprojection_error(const CameraModel& camera, const Eigen::Vector3d& point,
                          const Eigen::Vector2d& pixel) {
  const auto projected = camera.project(point);
  if (!projected) return std::numeric_limits<double>::infinity();
  return (*projected - pixel).norm();
}

std::optional<Triangulated> triangulate(const std::vector<PixelObservation>& observations,
                                        int refine_iterations) {
  if (observations.size() < 2) return std::nullopt;

  // Linear step: the point minimising the summed squared distance to every ray,
  // Σ (I − d dᵀ)(X − c) = 0.
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& obs : observations) {
    const Eigen::Vector3d d = obs.camera->pixel_to_world_ray(obs.pixel);
    const Eigen::Matrix3d M = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += M;
    b += M * obs.camera->center_world();
  }
  // Parallel rays make A rank-deficient: its smallest eigenvalue measures the angle between rays.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(A);
  if (eigen.eigenvalues()(0) < 1e-6) return std::nullopt;
  Eigen::Vector3d X = A.ldlt().solve(b);

  // Gauss–Newton on the reprojection error through the full camera models.
  for (int iteration = 0; iteration < refine_iterations; ++iteration) {
    Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Jtr = Eigen::Vector3d::Zero();
    for (const auto& obs : observations) {
      Eigen::Matrix<double, 2, 3> J;
      const auto projected = obs.camera->project(X, &J);
      if (!projected) return std::nullopt;
      const Eigen::Vector2d r = obs.pixel - *projected;
      JtJ += J.transpose() * J;
      Jtr += J.transpose() * r;
    }
    const Eigen::Vector3d step = JtJ.ldlt().solve(Jtr);
    if (!step.allFinite()) break;
    X += step;
    if (step.norm() < 1e-9) break;
  }

  Triangulated result;
  result.point = X;
  double sum2 = 0;
  for (const auto& obs : observations) {
    const double e = reprojection_error(*obs.camera, X, obs.pixel);
    if (!std::isfinite(e)) return std::nullopt;
    result.max_reprojection_px = std::max(result.max_reprojection_px, e);
    sum2 += e * e;
  }
  result.rms_reprojection_px = std::sqrt(sum2 / static_cast<double>(observations.size()));
  return result;
}

}  // namespace panoptes
