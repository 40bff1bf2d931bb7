// SPDX-License-Identifier: Apache-2.0
// Image-to-surface mappings: a calibrated camera's plane mapping inverts the projection exactly
// (with lens distortion), a homography fitted to four clicked corners agrees with it, Jacobians
// match numerical differentiation, and degenerate inputs are refused with a reason.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "surface_scene.h"

namespace panoptes::surface {
namespace {

using testing::camera_facing;
using testing::wall;

std::string error_of(auto&& call) {
  try {
    call();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ImageToSurface, PlaneMappingInvertsTheProjectionWithDistortion) {
  const SurfacePlane plane = wall(3.0, 1.0);
  const CameraModel camera = camera_facing({1.0, -2.0, 0.6}, {1.0, 0.0, 0.5}, 1400.0, -0.12);
  const ImageToSurface mapping = ImageToSurface::from_plane(camera, plane);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> s(0.4, 1.6), t(0.05, 0.95);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d st(s(rng), t(rng));
    const auto pixel = camera.project(plane.at(st));
    ASSERT_TRUE(pixel);
    const auto back = mapping.map(*pixel);
    ASSERT_TRUE(back);
    EXPECT_LT((*back - st).norm(), 1e-7) << st.transpose();
  }
}

TEST(ImageToSurface, JacobianMatchesNumericalDifferentiation) {
  const SurfacePlane plane = wall(3.0, 1.0);
  const CameraModel camera = camera_facing({1.0, -2.0, 0.6}, {1.2, 0.0, 0.5}, 1400.0, -0.12);
  const std::vector<ImageToSurface> mappings = {
      ImageToSurface::from_plane(camera, plane),
      ImageToSurface::from_homography(
          (Eigen::Matrix3d() << 1e-3, 2e-5, 0.1, -3e-5, 1.1e-3, 0.2, 1e-6, 2e-6, 1.0).finished())};
  for (const auto& mapping : mappings)
    for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(300, 200), Eigen::Vector2d(900, 700)}) {
      Eigen::Matrix2d J;
      const auto st = mapping.map(pixel, &J);
      ASSERT_TRUE(st);
      for (int k = 0; k < 2; ++k) {
        const double h = 1e-3;
        Eigen::Vector2d plus = pixel, minus = pixel;
        plus[k] += h;
        minus[k] -= h;
        const Eigen::Vector2d numeric = (*mapping.map(plus) - *mapping.map(minus)) / (2 * h);
        EXPECT_LT((J.col(k) - numeric).norm(), 1e-6 * (1.0 + numeric.norm())) << k;
      }
    }
}

TEST(ImageToSurface, FourClickedCornersGiveThePlaneHomography) {
  const SurfacePlane plane = wall(3.0, 1.0);
  const CameraModel camera = camera_facing({1.5, -2.5, 0.3}, {1.5, 0.0, 0.5}, 1000.0);
  std::vector<Eigen::Vector2d> pixels, surface;
  for (const Eigen::Vector2d& st : {Eigen::Vector2d(0.2, 0.1), Eigen::Vector2d(2.8, 0.1),
                                    Eigen::Vector2d(2.8, 0.9), Eigen::Vector2d(0.2, 0.9)}) {
    pixels.push_back(*camera.project(plane.at(st)));
    surface.push_back(st);
  }
  const ImageToSurface clicked = ImageToSurface::from_homography(fit_homography(pixels, surface));
  const ImageToSurface calibrated = ImageToSurface::from_plane(camera, plane);
  for (const Eigen::Vector2d& pixel :
       {Eigen::Vector2d(100, 300), Eigen::Vector2d(640, 512), Eigen::Vector2d(1100, 800)})
    EXPECT_LT((*clicked.map(pixel) - *calibrated.map(pixel)).norm(), 1e-9);
}

TEST(ImageToSurface, DegenerateInputsAreRefusedWithTheReason) {
  const std::vector<Eigen::Vector2d> pixels = {{0, 0}, {100, 0}, {200, 0}, {0, 100}};
  const std::vector<Eigen::Vector2d> surface = {{0, 0}, {1, 0}, {2, 0}, {0, 1}};
  EXPECT_NE(error_of([&] { fit_homography(pixels, surface); }).find("collinear"), std::string::npos);
  EXPECT_NE(error_of([&] {
              fit_homography(std::span(pixels).first(3), std::span(surface).first(3));
            }).find("at least 4"),
            std::string::npos);
  EXPECT_NE(error_of([&] { ImageToSurface::from_homography(Eigen::Matrix3d::Zero()); }).find("singular"),
            std::string::npos);
  const SurfacePlane plane = wall(3.0, 1.0);
  // The camera looks away from the wall: the wall is behind it.
  const CameraModel away = camera_facing({1.0, -2.0, 0.5}, {1.0, -4.0, 0.5}, 1000.0);
  EXPECT_NE(error_of([&] { ImageToSurface::from_plane(away, plane); }).find("behind"), std::string::npos);
  // A camera in the wall's plane sees it edge-on.
  const CameraModel edge_on = camera_facing({-1.0, 0.0, 0.5}, {1.0, 0.0, 0.5}, 1000.0);
  EXPECT_NE(error_of([&] { ImageToSurface::from_plane(edge_on, plane); }).find("edge-on"), std::string::npos);
}

TEST(ImageToSurface, PixelsAboveTheHorizonDoNotMap) {
  // A camera low in front of a floor-like plane: the upper image rows see the sky.
  SurfacePlane floor;
  floor.u_axis = Eigen::Vector3d::UnitX();
  floor.v_axis = Eigen::Vector3d::UnitY();
  floor.size = Eigen::Vector2d(10, 10);
  const CameraModel camera = camera_facing({5.0, -1.0, 0.3}, {5.0, 5.0, 0.3}, 800.0);
  const ImageToSurface mapping = ImageToSurface::from_plane(camera, floor);
  EXPECT_FALSE(mapping.map({640, 100}));  // above the horizon
  EXPECT_TRUE(mapping.map({640, 1000}));  // the floor near the camera
}

}  // namespace
}  // namespace panoptes::surface
