// SPDX-License-Identifier: Apache-2.0
// A bumped camera's pose again from tracks the other cameras determine (camera_resection.h; issue
// 36 item 3): a 1280 x 1024 camera 4 m from a walk-sized cloud of markers (1 s of 25 monitored
// frames, 30 markers each, a fifth hidden per frame, 2 false blobs per frame, 0.15 px centroid
// noise), bumped by 0.5, 2 and 5 degrees about an axis across the image plane and by 5 mm; the pose
// is recovered from the old pose and the samples alone.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/estimator/camera_resection.h"

namespace panoptes::estimator {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

CameraIntrinsics intrinsics() {
  CameraIntrinsics k;
  k.width = 1280;
  k.height = 1024;
  k.fx = 1000.0;
  k.fy = 1000.4;
  k.cx = 641.3;
  k.cy = 509.8;
  k.distortion = {-0.08, 0.05, 0.0002, 0.0004, -0.01};
  return k;
}

RigidTransform bumped(const RigidTransform& T_world_cam, double degrees, double millimetres) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, 0.5).normalized();  // camera frame
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(degrees * kDegree, axis));
  RigidTransform T = T_world_cam;
  T.q = (T_world_cam.q * turn).normalized();
  T.t = T_world_cam.t + T_world_cam.q * (millimetres * 1e-3 * Eigen::Vector3d(0.6, -0.8, 0.0));
  return T;
}

std::vector<ResectionSample> samples_of(const CameraModel& truth, std::uint64_t seed, int frames = 25,
                                        int markers = 30) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> x(-1.0, 1.0), y(-0.5, 0.5), z(0.1, 1.8), unit(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1280.0), v(0.0, 1024.0);
  std::normal_distribution<double> noise(0.0, 0.15);
  std::vector<ResectionSample> samples;
  for (int f = 0; f < frames; ++f) {
    ResectionSample sample;
    for (int m = 0; m < markers; ++m) {
      const Eigen::Vector3d point(x(random), y(random), z(random));
      sample.points_world.push_back(point);
      const auto pixel = truth.project(point);
      if (!pixel || !truth.in_image(*pixel) || unit(random) < 0.2) continue;  // hidden from this camera
      sample.blobs.push_back(*pixel + Eigen::Vector2d(noise(random), noise(random)));
    }
    for (int k = 0; k < 2; ++k) sample.blobs.emplace_back(u(random), v(random));
    samples.push_back(std::move(sample));
  }
  return samples;
}

double rotation_error_deg(const RigidTransform& a, const RigidTransform& b) {
  return Eigen::AngleAxisd(a.q * b.q.conjugate()).angle() / kDegree;
}

TEST(CameraResection, BumpedCameraIsRecoveredFromTheTracks) {
  const RigidTransform before = look_at(Eigen::Vector3d(4.0, 1.2, 2.5), Eigen::Vector3d(0.0, 0.0, 0.9));
  const CameraModel old_model(intrinsics(), before);
  for (const double degrees : {0.5, 2.0, 5.0}) {
    const RigidTransform after = bumped(before, degrees, 5.0);
    const CameraModel truth(intrinsics(), after);
    const ResectionResult r = resect_camera(old_model, samples_of(truth, 7));
    std::printf(
        "%.1f deg bump: ok %d (%s), shift (%.1f, %.1f) px, %zu inliers of %zu predictions, rms %.3f px, "
        "sigma %.4f deg %.2f mm, error %.4f deg %.2f mm\n",
        degrees, r.ok ? 1 : 0, r.reason.c_str(), r.shift_px.x(), r.shift_px.y(), r.inliers, r.candidates,
        r.rms_px, r.rotation_sigma_deg, r.translation_sigma_mm, rotation_error_deg(r.T_world_cam, after),
        1e3 * (r.T_world_cam.t - after.t).norm());
    ASSERT_TRUE(r.ok) << degrees << " deg: " << r.reason;
    EXPECT_LT(rotation_error_deg(r.T_world_cam, after), 0.01) << degrees << " deg";
    EXPECT_LT(1e3 * (r.T_world_cam.t - after.t).norm(), 5.0) << degrees << " deg";
    EXPECT_NEAR(r.rotation_change_deg, degrees, 0.05);
    EXPECT_LT(r.rms_px, 0.3);
  }
}

TEST(CameraResection, AnUnmovedCameraStaysWhereItWas) {
  const RigidTransform pose = look_at(Eigen::Vector3d(-3.0, 2.5, 2.8), Eigen::Vector3d(0.0, 0.0, 0.9));
  const CameraModel model(intrinsics(), pose);
  const ResectionResult r = resect_camera(model, samples_of(model, 11));
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT(r.rotation_change_deg, 0.01);
  EXPECT_LT(r.translation_change_mm, 5.0);
  EXPECT_LT(r.shift_px.norm(), 4.0);
}

// A pose found but implausibly far from the old one (beyond the bounds) is refused, with the reason.
TEST(CameraResection, AnImplausiblyLargeChangeIsRefused) {
  const RigidTransform before = look_at(Eigen::Vector3d(4.0, 1.2, 2.5), Eigen::Vector3d(0.0, 0.0, 0.9));
  const CameraModel old_model(intrinsics(), before);
  const CameraModel truth(intrinsics(), bumped(before, 5.0, 5.0));
  ResectionOptions options;
  options.max_rotation_change_deg = 2.0;
  const ResectionResult turned = resect_camera(old_model, samples_of(truth, 7), options);
  EXPECT_FALSE(turned.ok);
  EXPECT_NE(turned.reason.find("implausible: it would turn the camera by 5.00 deg"), std::string::npos)
      << turned.reason;
  EXPECT_LT(rotation_error_deg(turned.T_world_cam, before), 1e-12) << "a refused result keeps the old pose";
  options = ResectionOptions{};
  options.max_translation_change_mm = 3.0;
  const ResectionResult moved = resect_camera(old_model, samples_of(truth, 7), options);
  EXPECT_FALSE(moved.ok);
  EXPECT_NE(moved.reason.find("move it by 5."), std::string::npos) << moved.reason;
  EXPECT_TRUE(resect_camera(old_model, samples_of(truth, 7)).ok) << "within the default bounds";
}

// Too little to go on: a few markers, or blobs that are all clutter. Never a pose from nothing.
TEST(CameraResection, TooLittleEvidenceIsRefusedWithTheReason) {
  const RigidTransform before = look_at(Eigen::Vector3d(4.0, 1.2, 2.5), Eigen::Vector3d(0.0, 0.0, 0.9));
  const CameraModel old_model(intrinsics(), before);
  const CameraModel truth(intrinsics(), bumped(before, 2.0, 5.0));
  const ResectionResult few = resect_camera(old_model, samples_of(truth, 3, 2, 8));
  EXPECT_FALSE(few.ok);
  EXPECT_FALSE(few.reason.empty());
  EXPECT_LT(rotation_error_deg(few.T_world_cam, before), 1e-12) << "a refused result keeps the old pose";
  std::vector<ResectionSample> clutter = samples_of(truth, 5);
  std::mt19937_64 random(9);
  std::uniform_real_distribution<double> u(0.0, 1280.0), v(0.0, 1024.0);
  for (auto& sample : clutter)
    for (auto& blob : sample.blobs) blob = Eigen::Vector2d(u(random), v(random));
  const ResectionResult none = resect_camera(old_model, clutter);
  EXPECT_FALSE(none.ok) << "clutter alone gave a pose";
  EXPECT_FALSE(none.reason.empty());
}

}  // namespace
}  // namespace panoptes::estimator
