// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "panoptes/estimator/point_ekf.h"
#include "panoptes/triangulation.h"
#include "test_cameras.h"

namespace panoptes::estimator {
namespace {

TEST(PointEkf, ProcessNoiseComposesExactly) {
  // Q(a + b) = A(b) Q(a) A(b)ᵀ + Q(b): predicting in two steps equals one step (seed 003 A.48).
  const double sigma2 = 3.7;
  const double a = 0.013, b = 0.0071;
  const Matrix6d two_steps =
      transition_matrix(b) * process_noise(a, sigma2) * transition_matrix(b).transpose() +
      process_noise(b, sigma2);
  EXPECT_LT((two_steps - process_noise(a + b, sigma2)).norm(), 1e-15);
}

TEST(PointEkf, ProcessNoiseMatchesSeedFormula) {
  const Matrix6d Q = process_noise(0.5, 2.0);
  EXPECT_DOUBLE_EQ(Q(0, 0), 2.0 * 0.125 / 3.0);
  EXPECT_DOUBLE_EQ(Q(0, 3), 2.0 * 0.25 / 2.0);
  EXPECT_DOUBLE_EQ(Q(3, 3), 2.0 * 0.5);
  EXPECT_DOUBLE_EQ(Q(0, 1), 0.0);
}

// The acceleration input moves the mean for its horizon and then lets the velocity be, and leaves
// the covariance to the constant-velocity model: predicting in two steps equals one step.
TEST(PointEkf, AccelerationInputActsForItsHorizonOnly) {
  PointState state;
  state.x << 1.0, 2.0, 3.0, 10.0, 0.0, -1.0;
  state.P = FilterCovariance<6>::diagonal((Vector6d() << 1e-4, 1e-4, 1e-4, 1.0, 1.0, 1.0).finished());
  state.acceleration = Eigen::Vector3d(-400.0, 0.0, 50.0);
  state.acceleration_horizon_s = 0.01;
  PointState no_input = state;
  no_input.acceleration.setZero();

  // Within the horizon: p + v t + a t²/2, v + a t.
  const PointState at5 = predicted(state, 5'000'000, 30.0);
  const Eigen::Vector3d expected5 = Eigen::Vector3d(1.0, 2.0, 3.0) +
                                    0.005 * Eigen::Vector3d(10.0, 0.0, -1.0) +
                                    0.5 * 0.005 * 0.005 * state.acceleration;
  EXPECT_LT((at5.position() - expected5).norm(), 1e-12);
  EXPECT_LT((at5.velocity() - (Eigen::Vector3d(10.0, 0.0, -1.0) + 0.005 * state.acceleration)).norm(), 1e-12);
  EXPECT_NEAR(at5.acceleration_horizon_s, 0.005, 1e-15);
  EXPECT_EQ(at5.P.matrix(), predicted(no_input, 5'000'000, 30.0).P.matrix());

  // Beyond it: accelerated for 10 ms, then constant velocity; two steps equal one.
  const PointState at25 = predicted(state, 25'000'000, 30.0);
  const Eigen::Vector3d v10 = Eigen::Vector3d(10.0, 0.0, -1.0) + 0.01 * state.acceleration;
  const Eigen::Vector3d expected25 = Eigen::Vector3d(1.0, 2.0, 3.0) +
                                     0.01 * Eigen::Vector3d(10.0, 0.0, -1.0) +
                                     0.5 * 0.01 * 0.01 * state.acceleration + 0.015 * v10;
  EXPECT_LT((at25.position() - expected25).norm(), 1e-12);
  EXPECT_LT((at25.velocity() - v10).norm(), 1e-12);
  EXPECT_LT((predicted(at5, 25'000'000, 30.0).position() - expected25).norm(), 1e-12);
  EXPECT_LT((position_after(state, 0.025) - expected25).norm(), 1e-12);
}

TEST(PointEkf, TracksConstantVelocityTargetWithAsynchronousCameras) {
  const auto cameras = make_ring_cameras(4, 3.0, 1.2);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  const Eigen::Vector3d p0(-0.5, 0.2, 0.8);
  const Eigen::Vector3d v(0.8, -0.3, 0.2);

  PointState state;
  state.x.head<3>() = p0 + Eigen::Vector3d(0.01, -0.01, 0.01);  // a rough start, as after initiation
  state.P = FilterCovariance<6>::diagonal((Vector6d() << 1e-4, 1e-4, 1e-4, 4.0, 4.0, 4.0).finished());
  state.stamp_ns = 0;

  // Four cameras at 100 Hz with different phases: one frame every 2.5 ms, one camera at a time.
  double sum2 = 0;
  int samples = 0;
  double nis_sum = 0;
  const double sigma2 = 0.01;  // a constant-velocity target: little process noise is right
  for (int k = 1; k <= 400; ++k) {
    const TimeNs t = k * 2'500'000LL;
    const CameraModel& camera = cameras[static_cast<std::size_t>(k % 4)];
    const Eigen::Vector3d truth = p0 + v * ns_to_seconds(t);
    predict(state, t, sigma2);
    const auto projection = project_point(state, camera, 0.1);
    ASSERT_TRUE(projection);
    const Eigen::Vector2d z = *camera.project(truth) + Eigen::Vector2d(noise(rng), noise(rng));
    EXPECT_LT(mahalanobis2(*projection, z), 18.4) << "measurement outside the verify region at k=" << k;
    nis_sum += mahalanobis2(*projection, z);
    update(state, *projection, z, 0.1);
    if (k > 200) {
      sum2 += (state.position() - truth).squaredNorm();
      ++samples;
    }
  }
  const double rmse = std::sqrt(sum2 / samples);
  std::printf("constant-velocity target: position RMSE %.3f mm, final velocity error %.1f mm/s\n", rmse * 1e3,
              (state.velocity() - v).norm() * 1e3);
  // Consistency: the normalised innovation squared averages to its 2 degrees of freedom when the
  // filter's R and P describe the real errors, and the error matches the covariance.
  const double mean_nis = nis_sum / 400;
  const double predicted_rmse = std::sqrt(state.P.matrix().block<3, 3>(0, 0).trace());
  std::printf("mean NIS %.2f (expect 2), predicted position RMSE %.3f mm\n", mean_nis, predicted_rmse * 1e3);
  EXPECT_GT(mean_nis, 1.5);
  EXPECT_LT(mean_nis, 2.5);
  EXPECT_LT(rmse, 2.0 * predicted_rmse);
  EXPECT_LT(rmse, 0.4e-3);
  EXPECT_LT((state.velocity() - v).norm(), 0.03);
  // The covariance stays symmetric positive definite (ekf.h's update form, symmetrised).
  EXPECT_LT((state.P.matrix() - state.P.matrix().transpose()).norm(), 1e-15);
  EXPECT_GT(state.P.matrix().ldlt().vectorD().minCoeff(), 0.0);
}

TEST(PointEkf, UpdateMovesTowardMeasurementAndShrinksCovariance) {
  const auto cameras = make_ring_cameras(2, 3.0, 1.0);
  PointState state;
  state.x.head<3>() = Eigen::Vector3d(0, 0, 1);
  state.P = FilterCovariance<6>(1e-2 * Matrix6d::Identity());
  const Eigen::Vector3d truth(0.01, 0, 1);
  const auto projection = project_point(state, cameras[0], 0.5);
  ASSERT_TRUE(projection);
  const Eigen::Vector2d z = *cameras[0].project(truth);
  const double before = (*cameras[0].project(state.position()) - z).norm();
  const double trace_before = state.P.matrix().trace();
  update(state, *projection, z, 0.5);
  EXPECT_LT((*cameras[0].project(state.position()) - z).norm(), 0.1 * before);
  EXPECT_LT(state.P.matrix().trace(), trace_before);
}

TEST(Triangulation, RecoversPointThroughDistortedCameras) {
  const auto cameras = make_ring_cameras(3, 3.0, 1.5, /*distorted=*/true);
  const Eigen::Vector3d point(0.3, -0.2, 1.1);
  std::vector<PixelObservation> observations;
  for (const auto& camera : cameras) observations.push_back({&camera, *camera.project(point)});
  const auto result = triangulate(observations);
  ASSERT_TRUE(result);
  EXPECT_LT((result->point - point).norm(), 1e-9);
  EXPECT_LT(result->max_reprojection_px, 1e-6);
}

TEST(Triangulation, RejectsSingleObservationAndParallelRays) {
  const auto cameras = make_ring_cameras(2, 3.0, 1.0);
  const Eigen::Vector3d point(0, 0, 1);
  EXPECT_FALSE(triangulate({{cameras.data(), *cameras[0].project(point)}}));
  // The same ray twice is parallel.
  EXPECT_FALSE(triangulate(
      {{cameras.data(), *cameras[0].project(point)}, {cameras.data(), *cameras[0].project(point)}}));
}

}  // namespace
}  // namespace panoptes::estimator
