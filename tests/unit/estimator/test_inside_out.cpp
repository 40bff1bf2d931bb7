// SPDX-License-Identifier: Apache-2.0
// Inside-out tracking (issue 21 item 3, seed 000 §6.2): the landmark measurement's Jacobian, and a
// head-mounted 1280 × 1024 camera (f = 800 px, 0.1 px noise, 100 Hz) walking a circle in a
// 6 × 6 × 3 m room and turning at up to 3 rad/s, tracked from 20 landmarks in 5 constellations
// (on the ceiling) from a cold start (seeded). Bad constellations are refused by name.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "panoptes/estimator/inside_out.h"

namespace panoptes::estimator {
namespace {

// 1280 × 1024, focal length `f` px, centred, no distortion.
CameraIntrinsics sxga(double f) {
  CameraIntrinsics K;
  K.width = 1280;
  K.height = 1024;
  K.fx = K.fy = f;
  K.cx = 639.5;
  K.cy = 511.5;
  return K;
}

CameraModel head_camera() {
  return CameraModel(sxga(800.0), RigidTransform{});  // the rig is the camera (T_rig_cam = identity)
}

// The head at time t: a 1.5 m circle at 1.2 m/s, 1.7 m high with a bob, looking towards the room's
// middle and 40° up, the yaw swinging ±0.3 rad at 7 rad/s (turn rate up to 2.9 rad/s).
RigidTransform head_pose(double t) {
  const double omega = 0.8, yaw = omega * t + M_PI + 0.3 * std::sin(7.0 * t), pitch = 40.0 * M_PI / 180.0;
  const Eigen::Vector3d position(1.5 * std::cos(omega * t), 1.5 * std::sin(omega * t),
                                 1.7 + 0.02 * std::sin(11.0 * t));
  const Eigen::Vector3d forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                                std::sin(pitch));
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d R_world_cam;
  R_world_cam << right, down, forward;
  return {Eigen::Quaterniond(R_world_cam), position};
}

std::vector<Constellation> room_landmarks(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> spread(-0.6, 0.6), relief(-0.04, 0.04);
  std::vector<Constellation> constellations;
  const std::vector<std::pair<Eigen::Vector3d, int>> centres = {{{1.4, 1.4, 3.0}, 2},
                                                                {{-1.4, 1.4, 3.0}, 2},
                                                                {{-1.4, -1.4, 3.0}, 2},
                                                                {{1.4, -1.4, 3.0}, 2},
                                                                {{0.0, 0.0, 3.0}, 2}};
  for (std::size_t c = 0; c < centres.size(); ++c) {
    const auto& [centre, normal_axis] = centres[c];
    Constellation constellation;
    constellation.name = "c" + std::to_string(c);
    for (int i = 0; i < 4; ++i) {
      Eigen::Vector3d offset(spread(rng), spread(rng), spread(rng));
      offset[normal_axis] = relief(rng);  // nearly flat on its ceiling or wall
      constellation.landmarks.push_back(centre + offset);
    }
    constellations.push_back(constellation);
  }
  return constellations;
}

TEST(InsideOut, LandmarkJacobianMatchesNumericalDifferentiation) {
  const CameraModel camera = head_camera();
  const RigidTransform T_world_rig = head_pose(0.7);
  const Eigen::Vector3d landmark = T_world_rig.apply(Eigen::Vector3d(0.3, -0.2, 2.5));
  const auto analytic = landmark_pixel(T_world_rig, landmark, camera);
  ASSERT_TRUE(analytic);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    RigidTransform plus = T_world_rig, minus = T_world_rig;
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    step[k % 3] = h;
    if (k < 3) {
      plus.t += step;
      minus.t -= step;
    } else {  // body-frame rotation error: R exp(δθ)
      plus.q = T_world_rig.q * rotation_vector_to_quaternion(step);
      minus.q = T_world_rig.q * rotation_vector_to_quaternion(-step);
    }
    const Eigen::Vector2d numeric =
        (landmark_pixel(plus, landmark, camera)->pixel - landmark_pixel(minus, landmark, camera)->pixel) /
        (2 * h);
    EXPECT_LT((analytic->J.col(k) - numeric).norm(), 1e-4 * (1.0 + numeric.norm())) << "column " << k;
  }
}

TEST(InsideOut, HeadMountedCameraTracksFromColdStart) {
  const CameraModel camera = head_camera();
  const auto constellations = room_landmarks(21);
  InsideOutTracker tracker(constellations, camera);
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, 0.1);
  double position_error2 = 0, angle_error2 = 0, first_pose_s = -1;
  int tracked = 0, frames = 0, wrong_acquisitions = 0;
  const TimeNs period = 10'000'000;
  for (TimeNs stamp = 0; stamp < 20'000'000'000; stamp += period, ++frames) {
    const double t = static_cast<double>(stamp) * 1e-9;
    const RigidTransform truth = head_pose(t);
    std::vector<Eigen::Vector2d> pixels;
    for (const auto& constellation : constellations)
      for (const auto& landmark : constellation.landmarks) {
        const auto projected = landmark_pixel(truth, landmark, camera);
        if (projected && camera.in_image(projected->pixel))
          pixels.push_back(projected->pixel + Eigen::Vector2d(noise(rng), noise(rng)));
      }
    const auto started = std::chrono::steady_clock::now();
    const auto pose = tracker.add_frame(stamp, pixels);
    if (stamp == 0)
      std::printf(
          "cold start from %zu blobs: %.2f ms\n", pixels.size(),
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count());
    if (!pose || pose->landmarks == 0) continue;
    const double position_error = (pose->T_world_rig.t - truth.t).norm();
    const double angle_error = pose->T_world_rig.q.angularDistance(truth.q);
    if (pose->acquired && (position_error > 0.02 || angle_error > 1.0 * M_PI / 180.0)) ++wrong_acquisitions;
    if (first_pose_s < 0) first_pose_s = t;
    if (pose->acquired) continue;  // accuracy of the filter, not of the first P3P guess
    position_error2 += position_error * position_error;
    angle_error2 += angle_error * angle_error;
    ++tracked;
  }
  const double position_rmse_mm = 1e3 * std::sqrt(position_error2 / std::max(tracked, 1));
  const double angle_rmse_deg = std::sqrt(angle_error2 / std::max(tracked, 1)) * 180.0 / M_PI;
  const auto& counters = tracker.counters();
  std::printf(
      "frames %d, tracked with landmarks %d (%.1f%%), first pose at %.3f s, acquisitions %llu (wrong %d), "
      "lost %llu\n",
      frames, tracked, 100.0 * tracked / frames, first_pose_s,
      static_cast<unsigned long long>(counters.acquisitions), wrong_acquisitions,
      static_cast<unsigned long long>(counters.lost));
  std::printf("position RMSE %.3f mm, orientation RMSE %.4f deg\n", position_rmse_mm, angle_rmse_deg);
  EXPECT_GE(first_pose_s, 0.0);
  EXPECT_LE(first_pose_s, 0.2);
  EXPECT_EQ(wrong_acquisitions, 0);
  EXPECT_GE(tracked, frames * 8 / 10);
  EXPECT_LE(position_rmse_mm, 1.0);
  EXPECT_LE(angle_rmse_deg, 0.05);
}

struct FusionRun {
  double position_rmse_mm = 0, angle_rmse_deg = 0;
  int poses = 0;
  std::uint64_t outside_in_updates = 0;
};

// The head of HeadMountedCameraTracksFromColdStart also carries four markers (rig frame, on top of
// the head: −y is up in the camera frame) that a fixed outside-in pair sees. `use_head` false: the
// head camera's first frame only (the cold start), then the fixed cameras alone.
FusionRun run_fusion(bool use_head, bool use_fixed) {
  const CameraModel camera = head_camera();
  const auto constellations = room_landmarks(21);
  const std::vector<Eigen::Vector3d> headset = {
      {0.07, -0.10, -0.05}, {-0.08, -0.11, -0.03}, {0.01, -0.14, -0.12}, {-0.03, -0.08, 0.04}};
  const CameraIntrinsics K = sxga(1400.0);
  const std::vector<CameraModel> fixed = {
      CameraModel(K, look_at({3.6, 0.8, 2.6}, {0.0, 0.0, 1.6}, Eigen::Vector3d::UnitZ())),
      CameraModel(K, look_at({-0.8, 3.6, 2.6}, {0.0, 0.0, 1.6}, Eigen::Vector3d::UnitZ()))};
  InsideOutTracker tracker(constellations, camera);
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, 0.1);
  const auto observe = [&](const std::vector<Eigen::Vector3d>& points, const auto& project) {
    std::vector<Eigen::Vector2d> pixels;
    for (const auto& point : points)
      if (const auto pixel = project(point); pixel)
        pixels.push_back(*pixel + Eigen::Vector2d(noise(rng), noise(rng)));
    return pixels;
  };
  std::vector<Eigen::Vector3d> landmarks;
  for (const auto& c : constellations)
    landmarks.insert(landmarks.end(), c.landmarks.begin(), c.landmarks.end());
  FusionRun run;
  double p2 = 0, a2 = 0;
  const TimeNs period = 10'000'000;
  for (TimeNs stamp = 0; stamp < 10'000'000'000; stamp += period) {
    const RigidTransform truth = head_pose(static_cast<double>(stamp) * 1e-9);
    for (std::size_t c = 0; use_fixed && stamp > 0 && c < fixed.size(); ++c) {
      // Asynchronous, between the head camera's frames; each run is judged after its head frame.
      const TimeNs at = stamp - period + 3'000'000 * static_cast<TimeNs>(c + 1);
      const RigidTransform head_then = head_pose(static_cast<double>(at) * 1e-9);
      tracker.add_outside_in_frame(
          at, fixed[c], headset,
          observe(headset, [&](const Eigen::Vector3d& m) -> std::optional<Eigen::Vector2d> {
            auto pixel = fixed[c].project(head_then.apply(m));
            if (!pixel || !fixed[c].in_image(*pixel)) return std::nullopt;
            return pixel;
          }));
    }
    if (use_head || stamp == 0) {
      tracker.add_frame(stamp,
                        observe(landmarks, [&](const Eigen::Vector3d& l) -> std::optional<Eigen::Vector2d> {
                          const auto projected = landmark_pixel(truth, l, camera);
                          if (!projected || !camera.in_image(projected->pixel)) return std::nullopt;
                          return projected->pixel;
                        }));
    }
    if (!tracker.state() || stamp < 500'000'000) continue;  // settled after its cold start
    const BodyState& state = *tracker.state();
    const RigidTransform truth_then = head_pose(static_cast<double>(state.stamp_ns) * 1e-9);
    p2 += (state.p - truth_then.t).squaredNorm();
    a2 += std::pow(state.q.angularDistance(truth_then.q), 2);
    ++run.poses;
  }
  run.position_rmse_mm = 1e3 * std::sqrt(p2 / std::max(run.poses, 1));
  run.angle_rmse_deg = std::sqrt(a2 / std::max(run.poses, 1)) * 180.0 / M_PI;
  run.outside_in_updates = tracker.counters().outside_in_updates;
  return run;
}

// Issue 21: with one fixed outside-in pair also seeing the headset, the fused pose is better than
// either alone (all three through the same filter, seeded).
TEST(InsideOut, FusedWithAnOutsideInPairBeatsEitherAlone) {
  const FusionRun inside_out = run_fusion(true, false);
  const FusionRun outside_in = run_fusion(false, true);
  const FusionRun fused = run_fusion(true, true);
  for (const auto& [name, run] :
       {std::pair{"inside-out", inside_out}, {"outside-in", outside_in}, {"fused", fused}})
    std::printf(
        "%-10s position RMSE %.3f mm, orientation RMSE %.4f deg (%d poses, %llu outside-in updates)\n", name,
        run.position_rmse_mm, run.angle_rmse_deg, run.poses,
        static_cast<unsigned long long>(run.outside_in_updates));
  EXPECT_EQ(inside_out.outside_in_updates, 0u);
  EXPECT_GT(outside_in.outside_in_updates, 1000u);
  EXPECT_GE(outside_in.poses, 900);
  EXPECT_LT(fused.position_rmse_mm, inside_out.position_rmse_mm);
  EXPECT_LT(fused.position_rmse_mm, outside_in.position_rmse_mm);
  EXPECT_LT(fused.angle_rmse_deg, inside_out.angle_rmse_deg);
  EXPECT_LT(fused.angle_rmse_deg, outside_in.angle_rmse_deg);
}

TEST(InsideOut, BadConstellationsAreRefusedByName) {
  const CameraModel camera = head_camera();
  const auto error_of = [&](std::vector<Constellation> constellations) -> std::string {
    try {
      InsideOutTracker tracker(std::move(constellations), camera);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of({}).find("no landmark constellation"), std::string::npos);
  EXPECT_NE(error_of({{"door", {Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(1, 0, 3)}}})
                .find("'door': needs at least 3"),
            std::string::npos);
  EXPECT_NE(
      error_of({{"rail", {Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(1, 0, 3), Eigen::Vector3d(2, 0, 3)}}})
          .find("'rail': landmarks are collinear"),
      std::string::npos);
}

}  // namespace
}  // namespace panoptes::estimator
