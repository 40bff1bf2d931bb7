// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <random>

#include <Eigen/LU>

#include "panoptes/rigid_fit.h"

namespace panoptes {
namespace {

Eigen::Quaterniond rotation(const Eigen::Vector3d& r) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(r.norm(), r.normalized()));
}

TEST(RigidFit, KabschRecoversARigidTransformAndRejectsDegenerateInput) {
  const std::vector<Eigen::Vector3d> from = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.2, 0}, {0.05, 0.05, 0.1}};
  const RigidTransform T{rotation(Eigen::Vector3d(1.0, -2.0, 0.5)), {1, 2, 3}};
  std::vector<Eigen::Vector3d> to;
  for (const auto& p : from) to.push_back(T.apply(p));
  double rms = 1;
  const auto fitted = fit_rigid_transform(from, to, &rms);
  ASSERT_TRUE(fitted);
  EXPECT_LT(rms, 1e-12);
  EXPECT_LT(fitted->q.angularDistance(T.q), 1e-9);
  EXPECT_LT((fitted->t - T.t).norm(), 1e-12);
  EXPECT_FALSE(fit_rigid_transform({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}));
  EXPECT_FALSE(fit_rigid_transform({{0, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {1, 0, 0}}));
  EXPECT_FALSE(fit_rigid_transform(from, {to[0], to[1], to[2]}));
}

TEST(RigidFit, MatchesEigenUmeyamaOnNoisyPoints) {
  std::mt19937 rng(8);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const RigidTransform T{rotation(Eigen::Vector3d(normal(rng), normal(rng), normal(rng))),
                           {normal(rng), normal(rng), normal(rng)}};
    std::vector<Eigen::Vector3d> from, to;
    Eigen::Matrix3Xd a(3, 12), b(3, 12);
    for (int i = 0; i < 12; ++i) {
      from.emplace_back(normal(rng), normal(rng), normal(rng));
      to.push_back(T.apply(from.back()) + 0.01 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
      a.col(i) = from.back();
      b.col(i) = to.back();
    }
    const auto fitted = fit_rigid_transform(from, to);
    ASSERT_TRUE(fitted);
    const Eigen::Matrix4d reference = Eigen::umeyama(a, b, false);
    EXPECT_LT((fitted->rotation() - reference.block<3, 3>(0, 0)).norm(), 1e-9);
    EXPECT_LT((fitted->t - reference.block<3, 1>(0, 3)).norm(), 1e-9);
  }
}

TEST(RigidFit, NearestRotationIsARotationAndFixesReflections) {
  const Eigen::Matrix3d R = rotation(Eigen::Vector3d(0.3, -0.2, 0.9)).toRotationMatrix();
  EXPECT_LT((nearest_rotation(R) - R).norm(), 1e-12);
  EXPECT_LT((nearest_rotation(2.5 * R) - R).norm(), 1e-12);
  Eigen::Matrix3d mirrored = R;
  mirrored.col(0) *= -1.0;  // det −1: the nearest rotation is not the mirror
  const Eigen::Matrix3d fixed = nearest_rotation(mirrored);
  EXPECT_NEAR(fixed.determinant(), 1.0, 1e-12);
  EXPECT_LT((fixed * fixed.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

}  // namespace
}  // namespace panoptes
