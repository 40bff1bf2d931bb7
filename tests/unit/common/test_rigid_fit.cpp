// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cmath>
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

// The closed form (Horn's quaternion, its eigenvalue by Newton's method) against Eigen's SVD-based
// Umeyama where it is hardest: three points (a plane, rank 2), the layouts of a segment (a
// near-isosceles triangle), rotations near a half turn, points that fit badly or only mirrored,
// and nearly collinear points, where the closed form hands over to the SVD.
TEST(RigidFit, TheClosedFormMatchesUmeyamaOnHardSets) {
  std::mt19937 rng(37);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto check = [&](const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                         double tolerance, const char* what) {
    Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(from.size())),
        b(3, static_cast<Eigen::Index>(from.size()));
    for (std::size_t i = 0; i < from.size(); ++i) {
      a.col(static_cast<Eigen::Index>(i)) = from[i];
      b.col(static_cast<Eigen::Index>(i)) = to[i];
    }
    double rms = -1.0;
    const auto fitted = fit_rigid_transform(from, to, &rms);
    ASSERT_TRUE(fitted) << what;
    const Eigen::Matrix4d reference = Eigen::umeyama(a, b, false);
    double sum = 0.0;
    double reference_sum = 0.0;
    for (std::size_t i = 0; i < from.size(); ++i) {
      sum += (fitted->apply(from[i]) - to[i]).squaredNorm();
      reference_sum +=
          (reference.block<3, 3>(0, 0) * from[i] + reference.block<3, 1>(0, 3) - to[i]).squaredNorm();
    }
    EXPECT_NEAR(rms, std::sqrt(sum / static_cast<double>(from.size())), 1e-12) << what;
    if (tolerance > 0.0) {
      EXPECT_LT((fitted->rotation() - reference.block<3, 3>(0, 0)).norm(), tolerance) << what;
      EXPECT_LT((fitted->t - reference.block<3, 1>(0, 3)).norm(), tolerance) << what;
    } else {  // the rotation about the line is barely determined: as good a fit, not the same one
      EXPECT_LE(sum, reference_sum + 1e-15) << what;
    }
  };
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::Vector3d axis(normal(rng), normal(rng), normal(rng));
    const double angle = trial % 4 == 0 ? M_PI - 1e-6 * std::abs(normal(rng)) : 3.0 * normal(rng);
    const RigidTransform T{rotation(axis.normalized() * angle), {normal(rng), normal(rng), normal(rng)}};
    const double noise = trial % 3 == 0 ? 0.0 : (trial % 3 == 1 ? 0.001 : 0.05);
    std::vector<Eigen::Vector3d> from, to;
    const int count = 3 + trial % 4;
    for (int i = 0; i < count; ++i) {
      from.push_back(0.1 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
      to.push_back(T.apply(from.back()) + noise * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
    }
    check(from, to, 1e-8, "random");
    // The shank's triangle (Upper-Front 86.6 mm, Rear-Front 90.5 mm) with two names exchanged: it
    // fits mirrored, within millimetres.
    std::vector<Eigen::Vector3d> shank{
        {-0.009, 0.0326, -0.0108}, {0.0402, -0.0244, 0.032}, {-0.0312, -0.0082, -0.0213}};
    std::vector<Eigen::Vector3d> seen;
    for (const auto& p : shank) seen.push_back(T.apply(p));
    std::swap(seen[0], seen[2]);
    check(shank, seen, 1e-8, "exchanged triangle");
    // Nearly collinear: 1 µm off a 0.3 m line.
    std::vector<Eigen::Vector3d> line;
    for (int i = 0; i < 4; ++i)
      line.push_back(Eigen::Vector3d(0.1 * i, 0, 0) +
                     1e-6 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
    std::vector<Eigen::Vector3d> moved;
    for (const auto& p : line) moved.push_back(T.apply(p));
    check(line, moved, 0.0, "nearly collinear");
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
