// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Eigenvalues>

#include "panoptes/covariance_bound.h"

namespace panoptes {
namespace {

Eigen::Matrix3d with_eigenvalues(const Eigen::Vector3d& values, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  const Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  return R * values.asDiagonal() * R.transpose();
}

// The answer of an eigen-solve, on covariances of every shape a track has (round, a long thin
// ellipsoid along one camera's ray, flat), scaled from micrometres to metres, on either side of
// the bound, and on matrices that are not semidefinite.
TEST(CovarianceBound, AgreesWithTheEigenSolveAwayFromTheBoundary) {
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> log_scale(-12, 0);
  std::uniform_real_distribution<double> unit(0, 1);
  int above = 0, below = 0;
  for (int i = 0; i < 200000; ++i) {
    const double scale = std::pow(10.0, log_scale(rng));
    Eigen::Vector3d values(unit(rng), std::pow(unit(rng), 4), std::pow(unit(rng), 8));
    if (i % 10 == 0) values(2) = -0.1 * unit(rng);  // not semidefinite
    values *= scale;
    const Eigen::Matrix3d P = with_eigenvalues(values, rng);
    const double largest =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(P, Eigen::EigenvaluesOnly).eigenvalues()(2);
    const double bound = scale * 2.0 * unit(rng);
    if (std::abs(largest - bound) < 1e-9 * scale) continue;  // rounding decides on the boundary
    const bool expected = largest <= bound;
    (expected ? below : above) += 1;
    ASSERT_EQ(largest_eigenvalue_at_most(P, bound), expected)
        << "largest eigenvalue " << largest << ", bound " << bound << ", P\n"
        << P;
  }
  EXPECT_GT(above, 50000);
  EXPECT_GT(below, 50000);
}

TEST(CovarianceBound, EdgeCases) {
  EXPECT_TRUE(largest_eigenvalue_at_most(Eigen::Matrix3d::Zero(), 0.0));
  EXPECT_TRUE(largest_eigenvalue_at_most(Eigen::Matrix3d::Identity(), 1.0));
  EXPECT_FALSE(largest_eigenvalue_at_most(Eigen::Matrix3d::Identity(), 0.999));
  // A semidefinite P (eigenvalues 1.8, 0, 0) whose 1.6·I − P has every diagonal entry (1) and
  // every 2 × 2 principal minor (1 − 0.36) positive: only the determinant says no.
  Eigen::Matrix3d P;
  P << 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6, 0.6;
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(P).eigenvalues()(2);
  EXPECT_NEAR(largest, 1.8, 1e-12);
  EXPECT_FALSE(largest_eigenvalue_at_most(P, 1.6));
  EXPECT_TRUE(largest_eigenvalue_at_most(P, 1.8 * (1 + 1e-9)));
}

}  // namespace
}  // namespace panoptes
