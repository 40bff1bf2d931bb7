// SPDX-License-Identifier: Apache-2.0
// The filter layer's update (ekf.h): a hand-computed case, symmetry and positive definiteness, and
// equality of its P − K S Kᵀ form with the Joseph form on random problems.
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "panoptes/estimator/ekf.h"

namespace panoptes::estimator {
namespace {

template <int N>
Eigen::Matrix<double, N, N> random_spd(std::mt19937& rng, double scale) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix<double, N, N> L;
  for (int r = 0; r < N; ++r)
    for (int c = 0; c < N; ++c) L(r, c) = normal(rng);
  return scale * (L * L.transpose() + 1e-3 * Eigen::Matrix<double, N, N>::Identity());
}

template <int N, int M>
Eigen::Matrix<double, N, N> joseph_update(const Eigen::Matrix<double, N, N>& P,
                                          const Eigen::Matrix<double, M, N>& H,
                                          const Eigen::Matrix<double, M, M>& R) {
  const Eigen::Matrix<double, M, M> S = H * P * H.transpose() + R;
  const Eigen::Matrix<double, N, M> K = P * H.transpose() * S.inverse();
  const Eigen::Matrix<double, N, N> I_KH = Eigen::Matrix<double, N, N>::Identity() - K * H;
  return I_KH * P * I_KH.transpose() + K * R * K.transpose();
}

TEST(FilterLayer, UpdateMatchesAHandComputedCase) {
  // P = [[4, 2], [2, 3]], H = [1 0], R = 1: S = 5, K = [0.8, 0.4]ᵀ,
  // P⁺ = P − K S Kᵀ = [[0.8, 0.4], [0.4, 2.2]], δx = K r.
  Eigen::Matrix2d prior;
  prior << 4, 2, 2, 3;
  FilterCovariance<2> P(prior);
  const Eigen::Matrix<double, 1, 2> H(1.0, 0.0);
  const Eigen::Matrix<double, 1, 1> R(1.0);
  EXPECT_DOUBLE_EQ((P.innovation_covariance<1>(H, R)(0, 0)), 5.0);
  const Eigen::Vector2d dx = P.update<1>(H, R, Eigen::Matrix<double, 1, 1>(2.5));
  EXPECT_NEAR(dx(0), 2.0, 1e-15);
  EXPECT_NEAR(dx(1), 1.0, 1e-15);
  Eigen::Matrix2d expected;
  expected << 0.8, 0.4, 0.4, 2.2;
  EXPECT_LT((P.matrix() - expected).norm(), 1e-14);
}

TEST(FilterLayer, PropagateIsAPAtPlusQ) {
  Eigen::Matrix2d A, Q;
  A << 1, 0.5, 0, 1;
  Q << 0.1, 0.02, 0.02, 0.3;
  FilterCovariance<2> P(Eigen::Matrix2d::Identity());
  P.propagate(A, Q);
  Eigen::Matrix2d expected;
  expected << 1.25 + 0.1, 0.5 + 0.02, 0.5 + 0.02, 1.0 + 0.3;
  EXPECT_LT((P.matrix() - expected).norm(), 1e-15);
}

TEST(FilterLayer, ConstantVelocityPropagationIsAPAtPlusQ) {
  std::mt19937 rng(11);
  for (const double dt : {0.0003, 0.008, -0.004, 0.25}) {
    const Eigen::Matrix<double, 6, 6> prior = random_spd<6>(rng, 1e-4);
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Identity();
    A.block<3, 3>(0, 3) = dt * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 6, 6> Q = random_spd<6>(rng, 1e-6);
    FilterCovariance<6> general(prior), closed_form(prior);
    general.propagate(A, Q);
    closed_form.propagate_constant_velocity(dt, Q);
    EXPECT_LT((general.matrix() - closed_form.matrix()).norm(), 1e-12 * general.matrix().norm()) << dt;
    EXPECT_EQ(closed_form.matrix(), closed_form.matrix().transpose());
  }
}

TEST(FilterLayer, AssignedPriorIsSymmetrised) {
  Eigen::Matrix2d lopsided;
  lopsided << 1, 0.2, 0.4, 1;
  const FilterCovariance<2> P(lopsided);
  EXPECT_DOUBLE_EQ(P(0, 1), 0.3);
  EXPECT_DOUBLE_EQ(P(1, 0), 0.3);
}

// Chosen form against the Joseph form, and symmetry/positive definiteness after a long run of
// updates, for the point filter's and the body filter's sizes.
template <int N>
void check_against_joseph(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix<double, N, N> prior = random_spd<N>(rng, std::pow(10.0, trial % 7 - 4));
    FilterCovariance<N> P(prior);
    Eigen::Matrix<double, 2, N> H;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < N; ++c) H(r, c) = normal(rng) * 100.0;  // pixels per metre-ish
    const Eigen::Matrix2d R = random_spd<2>(rng, 0.01);
    const Eigen::Matrix<double, N, N> joseph = joseph_update<N, 2>(P.matrix(), H, R);
    P.template update<2>(H, R, Eigen::Vector2d(normal(rng), normal(rng)));
    const double scale = prior.norm();
    EXPECT_LT((P.matrix() - joseph).norm(), 1e-9 * scale) << "trial " << trial;
    EXPECT_EQ(P.matrix(), P.matrix().transpose());
  }
  // A long run: 2000 sequential updates, each followed by a prediction, keeps P positive definite.
  FilterCovariance<N> P(random_spd<N>(rng, 1.0));
  const Eigen::Matrix<double, N, N> Q = 1e-6 * Eigen::Matrix<double, N, N>::Identity();
  for (int k = 0; k < 2000; ++k) {
    Eigen::Matrix<double, 2, N> H;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < N; ++c) H(r, c) = normal(rng) * 500.0;
    P.template update<2>(H, 0.01 * Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
    P.propagate(Eigen::Matrix<double, N, N>::Identity(), Q);
    ASSERT_EQ(P.matrix(), P.matrix().transpose());
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(P.matrix());
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
}

TEST(FilterLayer, UpdateEqualsTheJosephFormOnRandomPointFilterCases) {
  check_against_joseph<6>(11);
}
TEST(FilterLayer, UpdateEqualsTheJosephFormOnRandomBodyFilterCases) {
  check_against_joseph<15>(12);
}

// The prediction skips A's zero 3 x 3 blocks and the pixel update reuses the measurement's H P and
// S: both must give what the dense formulas give, with the zero blocks where the body filter has
// them and with none at all.
TEST(FilterLayer, BlockSparsePredictionEqualsTheDenseProduct) {
  constexpr int kN = 18;
  std::mt19937 rng(21);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Matrix<double, kN, kN> A;
    for (int r = 0; r < kN; ++r)
      for (int c = 0; c < kN; ++c) A(r, c) = normal(rng);
    if (trial % 2 == 0) {  // the body transition's pattern: block upper triangular within p/v/a and θ/ω/α
      for (Eigen::Index i = 0; i < 6; ++i)
        for (Eigen::Index j = 0; j < 6; ++j)
          if (j < i || i / 3 != j / 3) A.block<3, 3>(3 * i, 3 * j).setZero();
    }
    const Eigen::Matrix<double, kN, kN> prior = random_spd<kN>(rng, 1.0);
    const Eigen::Matrix<double, kN, kN> Q = random_spd<kN>(rng, 1e-3);
    FilterCovariance<kN> P(prior);
    P.propagate(A, Q);
    const Eigen::Matrix<double, kN, kN> dense = A * prior * A.transpose() + Q;
    EXPECT_LT((P.matrix() - dense).norm(), 1e-12 * dense.norm()) << "trial " << trial;
    EXPECT_EQ(P.matrix(), P.matrix().transpose());
  }
}

TEST(FilterLayer, PixelUpdateEqualsTheGeneralUpdate) {
  constexpr int kN = 18;
  std::mt19937 rng(22);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix<double, kN, kN> prior = random_spd<kN>(rng, std::pow(10.0, trial % 5 - 3));
    Eigen::Matrix<double, 2, kN> H = Eigen::Matrix<double, 2, kN>::Zero();
    for (int r = 0; r < 2; ++r)  // a marker's Jacobian: position and rotation columns only
      for (int c : {0, 1, 2, 9, 10, 11}) H(r, c) = normal(rng) * 300.0;
    const double sigma = 0.2;
    const Eigen::Vector2d z(normal(rng), normal(rng));
    FilterCovariance<kN> reused(prior), general(prior);
    const PixelMeasurement<kN> measurement = reused.pixel_measurement(Eigen::Vector2d::Zero(), H, sigma);
    const auto dx_reused = reused.update(measurement, z);
    const auto dx_general = general.update<2>(H, sigma * sigma * Eigen::Matrix2d::Identity(), z);
    EXPECT_LT((dx_reused - dx_general).norm(), 1e-9 * (1.0 + dx_general.norm())) << "trial " << trial;
    EXPECT_LT((reused.matrix() - general.matrix()).norm(), 1e-9 * prior.norm()) << "trial " << trial;
  }
}

TEST(FilterLayer, MahalanobisOfTheInnovation) {
  Eigen::Matrix2d S_inverse;
  S_inverse << 0.5, 0, 0, 0.25;
  EXPECT_DOUBLE_EQ(mahalanobis2<2>(S_inverse, Eigen::Vector2d(2, 4)), 2.0 + 4.0);
}

}  // namespace
}  // namespace panoptes::estimator
