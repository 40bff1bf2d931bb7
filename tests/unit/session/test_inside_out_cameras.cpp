// SPDX-License-Identifier: Apache-2.0
// The estimator's inside-out mode (docs/inside_out.md): the head camera of
// deploy/scenes/inside_out.yaml through an EstimatorSession (the path offline and live modes
// share) publishes its rig's pose like a body's, from a cold start, within issue 21's figures; a
// moving camera without landmarks and unusable landmarks are refused naming the file.
#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/calibration_file.h"
#include "panoptes/errors.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/inside_out_cameras.h"
#include "panoptes/session/offline_replay.h"
#include "panoptes/simulator.h"

namespace panoptes::session {
namespace {

namespace fs = std::filesystem;

const fs::path kScene = fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "scenes" / "inside_out.yaml";
constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;

std::string config_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

TEST(InsideOutCameras, HeadsetPoseFromTheSessionMeetsTheAcceptance) {
  const Scene scene = Scene::load(kScene);
  EstimatorSession session(EstimatorConfig{});
  SystemCalibration calibration = scene.calibration();
  const auto moving = take_moving_cameras(calibration);
  ASSERT_EQ(moving.size(), 1u);
  EXPECT_TRUE(calibration.cameras.empty()) << "the moving camera must not reach the point tracker";
  session.inside_out().configure(scene.landmarks(), moving, "inside_out.yaml");
  session.tracker().set_calibration(calibration);

  const CameraSimulator camera(scene, "head");
  std::vector<FeatureFrame> frames;
  for (std::int64_t k = 0; camera.frame_time_ns(k) < 4 * kNsPerSecond; ++k) {
    frames.push_back(camera.features(k));
    frames.back().stamp_ns += kEpoch;
    frames.back().received_ns += kEpoch;
  }
  double position2 = 0, angle2 = 0;
  int poses = 0, wrong = 0;
  TimeNs first_pose_ns = -1;
  replay_frames(
      session, frames, {false, false}, [&](const FeatureFrame& frame, estimator::FrameOutcome outcome) {
        ASSERT_EQ(outcome, estimator::FrameOutcome::kProcessed);
        for (const PoseRecord& pose : session.current_poses()) {
          ASSERT_EQ(pose.body, "headset");
          EXPECT_EQ(pose.stamp_ns, frame.stamp_ns);
          const RigidTransform truth = scene.bodies_at(pose.stamp_ns - kEpoch).front().T_world_body;
          const double dp = (pose.p - truth.t).norm();
          const double da =
              Eigen::Quaterniond(pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z()).angularDistance(truth.q);
          if (dp > 0.02 || da > 5.0 * M_PI / 180.0) ++wrong;
          if (first_pose_ns < 0) first_pose_ns = pose.stamp_ns - kEpoch;
          if (pose.stamp_ns - kEpoch < 500'000'000) continue;  // the filter settling after its cold start
          position2 += dp * dp;
          angle2 += da * da;
          ++poses;
        }
      });
  const double position_rmse_mm = 1e3 * std::sqrt(position2 / std::max(poses, 1));
  const double angle_rmse_deg = std::sqrt(angle2 / std::max(poses, 1)) * 180.0 / M_PI;
  std::printf("poses %d, first at %.3f s, wrong %d; position RMSE %.3f mm, orientation RMSE %.4f deg\n",
              poses, ns_to_seconds(first_pose_ns), wrong, position_rmse_mm, angle_rmse_deg);
  EXPECT_GE(first_pose_ns, 0);
  EXPECT_LE(first_pose_ns, 200'000'000);
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(poses, 340);  // 3.5 s at 100 Hz, nearly every frame
  EXPECT_LE(position_rmse_mm, 1.0);
  EXPECT_LE(angle_rmse_deg, 0.05);
  ASSERT_EQ(session.inside_out().summary_lines().size(), 1u);
  EXPECT_NE(session.inside_out().summary_lines()[0].find("acquisitions 1"), std::string::npos)
      << session.inside_out().summary_lines()[0];
}

TEST(InsideOutCameras, SetUpRefusesAMovingCameraWithoutLandmarksAndBadLandmarks) {
  const Scene scene = Scene::load(kScene);
  SystemCalibration calibration = scene.calibration();
  InsideOutCameras cameras;
  const std::string without = config_error([&] { set_up_inside_out(cameras, calibration, "cal.yaml", ""); });
  EXPECT_NE(without.find("cal.yaml"), std::string::npos) << without;
  EXPECT_NE(without.find("camera 'head' is moving: true"), std::string::npos) << without;
  EXPECT_TRUE(cameras.empty());

  const fs::path collinear =
      fs::temp_directory_path() / ("panoptes_rail_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(collinear) << "landmarks:\n  - {name: rail, markers: [[0, 0, 3], [1, 0, 3], [2, 0, 3]]}\n";
  calibration = scene.calibration();
  const std::string bad =
      config_error([&] { set_up_inside_out(cameras, calibration, "cal.yaml", collinear.string()); });
  fs::remove(collinear);
  EXPECT_NE(bad.find(collinear.string()), std::string::npos) << bad;
  EXPECT_NE(bad.find("'rail': landmarks are collinear"), std::string::npos) << bad;

  calibration = scene.calibration();
  const std::string missing =
      config_error([&] { set_up_inside_out(cameras, calibration, "cal.yaml", "/nonexistent/room.yaml"); });
  EXPECT_NE(missing.find("/nonexistent/room.yaml"), std::string::npos) << missing;

  calibration = scene.calibration();
  set_up_inside_out(cameras, calibration, "cal.yaml", kScene.string());
  EXPECT_TRUE(cameras.handles("head"));
  EXPECT_TRUE(calibration.cameras.empty());
}

}  // namespace
}  // namespace panoptes::session
