// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/body_snapshot.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "panoptes/estimator/body_ekf.h"

namespace panoptes::estimator {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Sum of squared reprojection errors at `pose`, and (when asked) the normal equations JᵀJ, Jᵀr.
std::optional<double> cost(const std::vector<Eigen::Vector3d>& markers,
                           const std::vector<CameraModel>& cameras,
                           const std::vector<SnapshotObservation>& observations, const RigidTransform& pose,
                           Matrix6d* JtJ = nullptr, Vector6d* Jtr = nullptr) {
  double sum = 0.0;
  if (JtJ) JtJ->setZero();
  if (Jtr) Jtr->setZero();
  for (const SnapshotObservation& o : observations) {
    const auto projected = marker_pixel(pose, markers[o.marker], cameras[o.camera]);
    if (!projected) return std::nullopt;
    const Eigen::Vector2d r = o.pixel - projected->pixel;
    sum += r.squaredNorm();
    if (JtJ) JtJ->noalias() += projected->J.transpose() * projected->J;
    if (Jtr) Jtr->noalias() += projected->J.transpose() * r;
  }
  return sum;
}

RigidTransform moved(const RigidTransform& pose, const Vector6d& step) {
  return {(pose.q * rotation_vector_to_quaternion(step.tail<3>())).normalized(), pose.t + step.head<3>()};
}

}  // namespace

std::optional<SnapshotPose> solve_snapshot_pose(const std::vector<Eigen::Vector3d>& markers,
                                                const std::vector<CameraModel>& cameras,
                                                const std::vector<SnapshotObservation>& observations,
                                                const RigidTransform& initial,
                                                const SnapshotOptions& options) {
  if (observations.size() < options.min_observations) return std::nullopt;
  SnapshotPose result;
  result.T_world_body = initial;
  result.observations = observations.size();
  Matrix6d JtJ;
  Vector6d Jtr;
  auto current = cost(markers, cameras, observations, initial, &JtJ, &Jtr);
  if (!current) return std::nullopt;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    result.iterations = iteration;
    const Eigen::LDLT<Matrix6d> ldlt(JtJ);
    if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff())
      return std::nullopt;
    Vector6d step = ldlt.solve(Jtr);
    std::optional<double> next;
    for (int halving = 0; halving <= 10; ++halving, step *= 0.5) {
      next = cost(markers, cameras, observations, moved(result.T_world_body, step));
      if (next && *next <= *current) break;
    }
    if (!next || *next > *current) {  // no step lowers the cost: at the minimum (to rounding)
      result.converged = true;
      break;
    }
    result.T_world_body = moved(result.T_world_body, step);
    current = cost(markers, cameras, observations, result.T_world_body, &JtJ, &Jtr);
    if (!current) return std::nullopt;
    if (step.head<3>().norm() < options.step_tolerance && step.tail<3>().norm() < options.step_tolerance) {
      result.converged = true;
      break;
    }
  }
  result.rms_px = std::sqrt(*current / static_cast<double>(observations.size()));
  return result;
}

}  // namespace panoptes::estimator
