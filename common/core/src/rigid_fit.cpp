// SPDX-License-Identifier: Apache-2.0
#include "panoptes/rigid_fit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>
#include <Eigen/SVD>

namespace panoptes {

namespace {

Eigen::Matrix3d rotation_from_svd(const Eigen::JacobiSVD<Eigen::Matrix3d>& svd) {
  Eigen::Matrix3d U = svd.matrixU();
  if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(2) = -U.col(2);  // no reflection
  return U * svd.matrixV().transpose();
}

}  // namespace

Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M) {
  return rotation_from_svd(Eigen::JacobiSVD<Eigen::Matrix3d>(M, Eigen::ComputeFullU | Eigen::ComputeFullV));
}

std::optional<RigidTransform> fit_rigid_transform(const std::vector<Eigen::Vector3d>& from,
                                                  const std::vector<Eigen::Vector3d>& to, double* rms) {
  const std::size_t n = from.size();
  if (n < 3 || to.size() != n) return std::nullopt;
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero(), mean_to = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_from += from[i];
    mean_to += to[i];
  }
  mean_from /= static_cast<double>(n);
  mean_to /= static_cast<double>(n);
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) cross += (to[i] - mean_to) * (from[i] - mean_from).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d& singular = svd.singularValues();
  if (!(singular(1) > 1e-12 * std::max(1.0, singular(0)))) return std::nullopt;
  const Eigen::Matrix3d R = rotation_from_svd(svd);
  RigidTransform T;
  T.q = Eigen::Quaterniond(R).normalized();
  T.t = mean_to - R * mean_from;
  if (rms != nullptr) {
    double sum = 0;
    for (std::size_t i = 0; i < n; ++i) sum += (T.apply(from[i]) - to[i]).squaredNorm();
    *rms = std::sqrt(sum / static_cast<double>(n));
  }
  return T;
}

}  // namespace panoptes
