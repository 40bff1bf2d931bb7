// SPDX-License-Identifier: Apache-2.0
// The one distortion model (distortion.h) evaluated on doubles and on Ceres Jets: the same values
// as CameraModel, and the Jets' derivatives equal CameraModel's hand-written Jacobian.
#include <gtest/gtest.h>

#include <ceres/jet.h>

#include "panoptes/camera_model.h"
#include "panoptes/distortion.h"

namespace panoptes {
namespace {

TEST(Distortion, DoubleAndJetEvaluationsAgreeWithTheCameraModel) {
  CameraIntrinsics intrinsics;
  intrinsics.distortion = {-0.12, 0.03, 1.2e-3, -8e-4, -0.004};
  const CameraModel camera(intrinsics, RigidTransform{});
  using Jet = ceres::Jet<double, 2>;
  Jet coefficients[5];
  for (int i = 0; i < 5; ++i) coefficients[i] = Jet(intrinsics.distortion[static_cast<std::size_t>(i)]);
  for (const Eigen::Vector2d& xn : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.31, -0.22),
                                    Eigen::Vector2d(-0.6, 0.45), Eigen::Vector2d(0.05, 0.7)}) {
    Eigen::Matrix2d J;
    const Eigen::Vector2d expected = camera.distort(xn, &J);
    const Eigen::Vector2d value = distort_normalized<double>(xn.x(), xn.y(), intrinsics.distortion.data());
    EXPECT_EQ(value, expected);  // the camera model evaluates this very expression
    const Eigen::Matrix<Jet, 2, 1> jet =
        distort_normalized<Jet>(Jet(xn.x(), 0), Jet(xn.y(), 1), coefficients);
    for (int r = 0; r < 2; ++r) {
      EXPECT_DOUBLE_EQ(jet[r].a, expected[r]);
      for (int c = 0; c < 2; ++c) EXPECT_NEAR(jet[r].v[c], J(r, c), 1e-12) << r << c;
    }
  }
}

TEST(Distortion, ZeroCoefficientsLeaveThePointUnchanged) {
  const double zero[5] = {0, 0, 0, 0, 0};
  const Eigen::Vector2d value = distort_normalized<double>(0.4, -0.3, zero);
  EXPECT_EQ(value, Eigen::Vector2d(0.4, -0.3));
}

}  // namespace
}  // namespace panoptes
