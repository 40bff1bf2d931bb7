// SPDX-License-Identifier: Apache-2.0
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "panoptes/camera_model.h"
#include "panoptes/geometry.h"

namespace panoptes {
namespace {

// Every term non-zero and strong enough to matter, yet monotonic over the whole image (stronger
// barrel distortion folds the image corners over, where no undistortion is defined).
CameraIntrinsics distorted_intrinsics() {
  CameraIntrinsics intrinsics;
  intrinsics.width = 1280;
  intrinsics.height = 1024;
  intrinsics.fx = 812.5;
  intrinsics.fy = 808.25;
  intrinsics.cx = 637.75;
  intrinsics.cy = 515.5;
  intrinsics.distortion = {-0.12, 0.03, 1.2e-3, -8e-4, -0.004};
  return intrinsics;
}

cv::Mat camera_matrix(const CameraIntrinsics& in) {
  return (cv::Mat_<double>(3, 3) << in.fx, 0, in.cx, 0, in.fy, in.cy, 0, 0, 1);
}

cv::Mat distortion_coefficients(const CameraIntrinsics& in) {
  const auto& d = in.distortion;
  return (cv::Mat_<double>(1, 5) << d[0], d[1], d[2], d[3], d[4]);
}

struct Scene {
  CameraModel camera;
  std::vector<Eigen::Vector3d> points_world;
};

// Cameras around the origin looking at it, with world points inside the field of view.
std::vector<Scene> random_scenes(unsigned seed, int scene_count, int points_per_scene) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Scene> scenes;
  for (int s = 0; s < scene_count; ++s) {
    const Eigen::Vector3d eye(4.0 * unit(rng), 4.0 * unit(rng), 2.0 + 1.5 * unit(rng));
    const Eigen::Vector3d target(0.3 * unit(rng), 0.3 * unit(rng), 0.5 * unit(rng));
    const Eigen::Vector3d up =
        (Eigen::Vector3d::UnitZ() + 0.3 * Eigen::Vector3d(unit(rng), unit(rng), 0)).normalized();
    Scene scene{CameraModel(distorted_intrinsics(), look_at(eye, target, up)), {}};
    while (static_cast<int>(scene.points_world.size()) < points_per_scene) {
      // Normalised coordinates up to ~0.6 stay where this distortion is monotonic.
      const Eigen::Vector3d p_cam(0.6 * unit(rng), 0.5 * unit(rng), 1.0);
      const double depth = 1.0 + 4.0 * (unit(rng) + 1.0);
      const Eigen::Vector3d p_world = scene.camera.T_world_cam().apply(depth * p_cam);
      const auto pixel = scene.camera.project(p_world);
      if (pixel && scene.camera.in_image(*pixel)) scene.points_world.push_back(p_world);
    }
    scenes.push_back(std::move(scene));
  }
  return scenes;
}

TEST(CameraModel, ProjectMatchesOpenCvProjectPoints) {
  int compared = 0;
  for (const Scene& scene : random_scenes(11, 8, 40)) {
    const auto& T_cam_world = scene.camera.T_cam_world();
    const Eigen::Matrix3d R = T_cam_world.rotation();
    cv::Mat R_cv(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R_cv.at<double>(r, c) = R(r, c);
    cv::Mat rvec;
    cv::Rodrigues(R_cv, rvec);
    const cv::Mat tvec = (cv::Mat_<double>(3, 1) << T_cam_world.t.x(), T_cam_world.t.y(), T_cam_world.t.z());
    std::vector<cv::Point3d> object_points;
    for (const auto& p : scene.points_world) object_points.emplace_back(p.x(), p.y(), p.z());
    std::vector<cv::Point2d> image_points;
    cv::projectPoints(object_points, rvec, tvec, camera_matrix(scene.camera.intrinsics()),
                      distortion_coefficients(scene.camera.intrinsics()), image_points);
    for (std::size_t i = 0; i < object_points.size(); ++i) {
      const auto pixel = scene.camera.project(scene.points_world[i]);
      ASSERT_TRUE(pixel.has_value());
      EXPECT_NEAR(pixel->x(), image_points[i].x, 1e-9);
      EXPECT_NEAR(pixel->y(), image_points[i].y, 1e-9);
      ++compared;
    }
  }
  EXPECT_EQ(compared, 8 * 40);
}

TEST(CameraModel, UndistortMatchesOpenCvUndistortPoints) {
  const CameraModel camera(distorted_intrinsics(), RigidTransform{});
  const auto& in = camera.intrinsics();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, in.width - 1.0);
  std::uniform_real_distribution<double> v(0.0, in.height - 1.0);
  // The corners are where distortion is strongest and a solver is most likely to fail.
  std::vector<cv::Point2d> pixels = {
      {-0.5, -0.5}, {in.width - 0.5, -0.5}, {-0.5, in.height - 0.5}, {in.width - 0.5, in.height - 0.5}};
  pixels.reserve(pixels.size() + 200);
  for (int i = 0; i < 200; ++i) pixels.emplace_back(u(rng), v(rng));
  std::vector<cv::Point2d> reference;
  // The default undistortPoints stops after 5 fixed-point iterations; ask it to converge fully.
  cv::undistortPoints(pixels, reference, camera_matrix(in), distortion_coefficients(in), cv::noArray(),
                      cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 1000, 1e-14));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const Eigen::Vector2d xn = camera.pixel_to_normalized(Eigen::Vector2d(pixels[i].x, pixels[i].y));
    // Compare in pixels (scaled by f) so the tolerance means the same as for projection.
    EXPECT_NEAR(xn.x() * in.fx, reference[i].x * in.fx, 1e-6) << "pixel " << i;
    EXPECT_NEAR(xn.y() * in.fy, reference[i].y * in.fy, 1e-6) << "pixel " << i;
  }
}

TEST(CameraModel, UndistortInvertsDistort) {
  const CameraModel camera(distorted_intrinsics(), RigidTransform{});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-0.7, 0.7);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector2d xn(unit(rng), unit(rng) * 0.8);
    const Eigen::Vector2d recovered = camera.undistort(camera.distort(xn));
    EXPECT_LT((recovered - xn).norm(), 1e-11) << xn.transpose();
  }
}

TEST(CameraModel, ZeroDistortionIsPinhole) {
  CameraIntrinsics in = distorted_intrinsics();
  in.distortion = {};
  const CameraModel camera(in, RigidTransform{});
  const Eigen::Vector2d xn(0.31, -0.22);
  Eigen::Matrix2d J;
  EXPECT_EQ(camera.distort(xn, &J), xn);
  EXPECT_EQ(J, Eigen::Matrix2d::Identity());
  EXPECT_EQ(camera.undistort(xn), xn);
  const auto pixel = camera.project_camera_point(Eigen::Vector3d(0.62, -0.44, 2.0));
  ASSERT_TRUE(pixel.has_value());
  EXPECT_NEAR(pixel->x(), in.fx * 0.31 + in.cx, 1e-12);
  EXPECT_NEAR(pixel->y(), in.fy * -0.22 + in.cy, 1e-12);
}

TEST(CameraModel, DistortJacobianMatchesNumerical) {
  const CameraModel camera(distorted_intrinsics(), RigidTransform{});
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(-0.7, 0.7);
  const double h = 1e-6;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector2d xn(unit(rng), unit(rng));
    Eigen::Matrix2d J;
    camera.distort(xn, &J);
    Eigen::Matrix2d J_numerical;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d delta = Eigen::Vector2d::Zero();
      delta[k] = h;
      J_numerical.col(k) = (camera.distort(xn + delta) - camera.distort(xn - delta)) / (2 * h);
    }
    EXPECT_LT((J - J_numerical).norm(), 1e-8) << "J\n" << J << "\nnumerical\n" << J_numerical;
  }
}

TEST(CameraModel, ProjectJacobiansMatchNumerical) {
  const double h = 1e-6;
  for (const Scene& scene : random_scenes(23, 5, 20)) {
    for (const Eigen::Vector3d& p_world : scene.points_world) {
      Eigen::Matrix<double, 2, 3> J_world;
      ASSERT_TRUE(scene.camera.project(p_world, &J_world).has_value());
      const Eigen::Vector3d p_cam = scene.camera.T_cam_world().apply(p_world);
      Eigen::Matrix<double, 2, 3> J_cam;
      ASSERT_TRUE(scene.camera.project_camera_point(p_cam, &J_cam).has_value());

      Eigen::Matrix<double, 2, 3> J_world_numerical;
      Eigen::Matrix<double, 2, 3> J_cam_numerical;
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d delta = Eigen::Vector3d::Zero();
        delta[k] = h;
        J_world_numerical.col(k) =
            (*scene.camera.project(p_world + delta) - *scene.camera.project(p_world - delta)) / (2 * h);
        J_cam_numerical.col(k) = (*scene.camera.project_camera_point(p_cam + delta) -
                                  *scene.camera.project_camera_point(p_cam - delta)) /
                                 (2 * h);
      }
      // Entries are ~100-1000 px/m; central differences are good to ~1e-6 relative here.
      EXPECT_LT((J_cam - J_cam_numerical).norm(), 1e-5 * J_cam.norm()) << "J_cam\n"
                                                                       << J_cam << "\nnumerical\n"
                                                                       << J_cam_numerical;
      EXPECT_LT((J_world - J_world_numerical).norm(), 1e-5 * J_world.norm()) << "J_world\n"
                                                                             << J_world << "\nnumerical\n"
                                                                             << J_world_numerical;
    }
  }
}

TEST(CameraModel, PixelToWorldRayPointsAtProjectedPoint) {
  for (const Scene& scene : random_scenes(31, 5, 30)) {
    for (const Eigen::Vector3d& p_world : scene.points_world) {
      const auto pixel = scene.camera.project(p_world);
      ASSERT_TRUE(pixel.has_value());
      const Eigen::Vector3d ray = scene.camera.pixel_to_world_ray(*pixel);
      EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
      const Eigen::Vector3d expected = (p_world - scene.camera.center_world()).normalized();
      EXPECT_LT((ray - expected).norm(), 1e-9)
          << "ray " << ray.transpose() << " expected " << expected.transpose();
    }
  }
}

TEST(CameraModel, PointsBehindOrOnTheCameraPlaneDoNotProject) {
  const CameraModel camera(distorted_intrinsics(), RigidTransform{});
  Eigen::Matrix<double, 2, 3> J;
  EXPECT_FALSE(camera.project_camera_point(Eigen::Vector3d(0.1, 0.2, -1.0), &J).has_value());
  EXPECT_FALSE(camera.project_camera_point(Eigen::Vector3d(0.1, 0.2, 0.0)).has_value());
  EXPECT_FALSE(camera.project_camera_point(Eigen::Vector3d(0.1, 0.2, 1e-10)).has_value());
  EXPECT_TRUE(camera.project_camera_point(Eigen::Vector3d(0.1, 0.2, 1e-3)).has_value());
  // The world-frame overload applies the pose first: a camera at z=2 looking down +z cannot see z=1.
  const CameraModel moved(distorted_intrinsics(),
                          RigidTransform{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 2)});
  EXPECT_FALSE(moved.project(Eigen::Vector3d(0, 0, 1)).has_value());
  EXPECT_TRUE(moved.project(Eigen::Vector3d(0, 0, 3)).has_value());
}

TEST(CameraModel, InImageUsesPixelCentreConvention) {
  const CameraModel camera(distorted_intrinsics(), RigidTransform{});
  EXPECT_TRUE(camera.in_image(Eigen::Vector2d(-0.5, -0.5)));
  EXPECT_TRUE(camera.in_image(Eigen::Vector2d(1279.49, 1023.49)));
  EXPECT_FALSE(camera.in_image(Eigen::Vector2d(-0.51, 100)));
  EXPECT_FALSE(camera.in_image(Eigen::Vector2d(100, 1023.5)));
  EXPECT_FALSE(camera.in_image(Eigen::Vector2d(1279.5, 100)));
  EXPECT_TRUE(camera.in_image(Eigen::Vector2d(-5.0, 100), 5.0));
  EXPECT_FALSE(camera.in_image(Eigen::Vector2d(-5.0, 100), 4.0));
}

TEST(CameraModel, NonUnitQuaternionIsNormalised) {
  RigidTransform T_world_cam = look_at(Eigen::Vector3d(3, 1, 2), Eigen::Vector3d::Zero());
  const RigidTransform unit_pose = T_world_cam;
  T_world_cam.q.coeffs() *= 2.0;
  const CameraModel scaled(distorted_intrinsics(), T_world_cam);
  const CameraModel reference(distorted_intrinsics(), unit_pose);
  const Eigen::Vector3d p(0.1, -0.2, 0.3);
  EXPECT_LT((*scaled.project(p) - *reference.project(p)).norm(), 1e-9);
}

}  // namespace
}  // namespace panoptes
