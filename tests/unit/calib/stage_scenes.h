// SPDX-License-Identifier: Apache-2.0
// Small synthetic scenes for the wand solver's stage tests: cameras on a ring with known poses, a
// wand at known positions, and exact (or noisy) pixels as each stage takes them.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "panoptes/calib/bundle_adjustment.h"
#include "panoptes/calib/two_view.h"
#include "panoptes/calib/wand_samples.h"
#include "panoptes/geometry.h"

namespace panoptes::calib::testing {

struct StageScene {
  std::vector<CameraCalibration> cameras;  // the truth: T_world_cam set
  WandDefinition wand{{0.0, 0.18, 0.5}};
  std::vector<std::vector<Eigen::Vector3d>> wand_markers;  // per instant, world, in wand order
};

inline CameraIntrinsics stage_intrinsics() {
  CameraIntrinsics k;
  k.width = 1280;
  k.height = 1024;
  k.fx = k.fy = 800;
  k.cx = 639.5;
  k.cy = 511.5;
  return k;
}

// `count` cameras on a circle of radius 3 m at 2.5 m height, looking at (0, 0, 1); the wand at
// `instants` random places within +-0.6 m of that point, turned at random.
inline StageScene ring_stage_scene(int count, int instants, unsigned seed = 3) {
  StageScene scene;
  for (int c = 0; c < count; ++c) {
    const double angle = 2 * M_PI * c / count + 0.3;
    CameraCalibration camera;
    camera.id = "cam" + std::to_string(c);
    camera.intrinsics = stage_intrinsics();
    camera.T_world_cam =
        look_at(Eigen::Vector3d(3 * std::cos(angle), 3 * std::sin(angle), 2.5 + 0.1 * (c % 2)),
                Eigen::Vector3d(0, 0, 1));
    scene.cameras.push_back(camera);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int s = 0; s < instants; ++s) {
    const Eigen::Vector3d centre =
        Eigen::Vector3d(0, 0, 1) + 0.6 * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
    const Eigen::Vector3d direction = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)).normalized();
    std::vector<Eigen::Vector3d> markers;
    for (double position : scene.wand.positions)
      markers.push_back(centre + (position - 0.5 * scene.wand.length()) * direction);
    scene.wand_markers.push_back(markers);
  }
  return scene;
}

// The wand's pixels in camera `c` at instant `s` (+ Gaussian noise of `noise_px`), or empty if a
// marker is behind the camera or outside its image.
inline std::vector<Eigen::Vector2d> stage_pixels(const StageScene& scene, std::size_t c, std::size_t s,
                                                 double noise_px = 0.0, std::mt19937* rng = nullptr) {
  const CameraModel model = scene.cameras[c].model();
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& X : scene.wand_markers[s]) {
    const auto pixel = model.project(X);
    if (!pixel || !model.in_image(*pixel)) return {};
    pixels.push_back(noise_px > 0 && rng != nullptr
                         ? Eigen::Vector2d(*pixel + Eigen::Vector2d(noise(*rng), noise(*rng)))
                         : *pixel);
  }
  return pixels;
}

// A constant track segment at `pixels` (a synchronised camera's frame at the instant).
inline TrackSegment still_segment(const std::vector<Eigen::Vector2d>& pixels) {
  TrackSegment segment;
  segment.h_s = 0.01;
  segment.p0 = segment.p1 = pixels;
  segment.m0.assign(pixels.size(), Eigen::Vector2d::Zero());
  segment.m1 = segment.m0;
  return segment;
}

// Every instant as the stages see it: an observation per camera that sees the whole wand.
inline std::vector<WandInstant> stage_instants(const StageScene& scene, double noise_px = 0.0,
                                               unsigned seed = 5) {
  std::mt19937 rng(seed);
  std::vector<WandInstant> instants;
  for (std::size_t s = 0; s < scene.wand_markers.size(); ++s) {
    WandInstant instant;
    instant.t_ns = static_cast<TimeNs>(s) * 10'000'000;
    for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
      const auto pixels = stage_pixels(scene, c, s, noise_px, &rng);
      if (!pixels.empty())
        instant.observations.push_back({static_cast<int>(c), still_segment(pixels), 0.0, true});
    }
    if (instant.observations.size() >= 2) instants.push_back(std::move(instant));
  }
  return instants;
}

// The pose of camera b relative to camera a, as the two-view stage states it.
inline RelativePose true_relative_pose(const StageScene& scene, std::size_t a, std::size_t b) {
  const RigidTransform T_a_b = scene.cameras[a].T_world_cam->inverse() * *scene.cameras[b].T_world_cam;
  return {T_a_b.rotation(), T_a_b.t};
}

inline double rotation_error_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / M_PI;
}

}  // namespace panoptes::calib::testing
