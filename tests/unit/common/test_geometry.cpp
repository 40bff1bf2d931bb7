// SPDX-License-Identifier: Apache-2.0
#include <random>

#include <gtest/gtest.h>

#include "panoptes/camera_model.h"
#include "panoptes/geometry.h"

namespace panoptes {
namespace {

CameraIntrinsics test_intrinsics() {
  CameraIntrinsics intrinsics;
  intrinsics.width = 1280;
  intrinsics.height = 1024;
  intrinsics.fx = 900;
  intrinsics.fy = 905;
  intrinsics.cx = 641.5;
  intrinsics.cy = 509.25;
  intrinsics.distortion = {-0.2, 0.05, 1e-3, -5e-4, -0.01};
  return intrinsics;
}

void expect_rotation(const Eigen::Matrix3d& R) {
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST(Geometry, RigidTransformComposeAndInverse) {
  RigidTransform T_a_b{Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
                       Eigen::Vector3d(0.5, -1, 2)};
  RigidTransform T_b_c{Eigen::Quaterniond(Eigen::AngleAxisd(-1.2, Eigen::Vector3d(0, 1, 1).normalized())),
                       Eigen::Vector3d(3, 0.25, -0.5)};
  const Eigen::Vector3d p_c(0.3, -0.2, 4.0);
  EXPECT_LT(((T_a_b * T_b_c).apply(p_c) - T_a_b.apply(T_b_c.apply(p_c))).norm(), 1e-12);
  EXPECT_LT((T_a_b.inverse().apply(T_a_b.apply(p_c)) - p_c).norm(), 1e-12);
}

TEST(Geometry, LookAtAxesFollowOpenCvConvention) {
  // Looking along world +x with z up: image right is world -y, image down is world -z.
  const RigidTransform T_world_cam = look_at(Eigen::Vector3d(-5, 0, 1), Eigen::Vector3d(0, 0, 1));
  const Eigen::Matrix3d R = T_world_cam.rotation();
  expect_rotation(R);
  EXPECT_LT((R.col(0) - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  EXPECT_LT((R.col(1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((R.col(2) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((T_world_cam.t - Eigen::Vector3d(-5, 0, 1)).norm(), 1e-15);
}

TEST(Geometry, LookAtPutsTargetAtPrincipalPointAndUpAtTop) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-4.0, 4.0);
  const CameraIntrinsics intrinsics = test_intrinsics();
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d eye(coordinate(rng), coordinate(rng), 2.0 + std::abs(coordinate(rng)));
    const Eigen::Vector3d target(coordinate(rng) * 0.25, coordinate(rng) * 0.25, 0.5);
    const RigidTransform T_world_cam = look_at(eye, target);
    expect_rotation(T_world_cam.rotation());
    const CameraModel camera(intrinsics, T_world_cam);
    const auto pixel = camera.project(target);
    ASSERT_TRUE(pixel.has_value());
    EXPECT_NEAR(pixel->x(), intrinsics.cx, 1e-9);
    EXPECT_NEAR(pixel->y(), intrinsics.cy, 1e-9);
    // A point straight above the target must appear above it in the image (smaller row).
    const auto above = camera.project(target + Eigen::Vector3d(0, 0, 0.1));
    ASSERT_TRUE(above.has_value());
    EXPECT_LT(above->y(), intrinsics.cy);
  }
}

TEST(Geometry, LookAtAlongUpStillGivesARotation) {
  const Eigen::Vector3d eye(0, 0, 5);
  const Eigen::Vector3d target(0, 0, 0);
  const RigidTransform T_world_cam = look_at(eye, target);
  const Eigen::Matrix3d R = T_world_cam.rotation();
  ASSERT_TRUE(R.allFinite());
  expect_rotation(R);
  EXPECT_LT((R.col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

TEST(Geometry, LookAtRejectsCoincidentEyeAndTarget) {
  EXPECT_THROW(look_at(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 2, 3)), std::invalid_argument);
}

}  // namespace
}  // namespace panoptes
