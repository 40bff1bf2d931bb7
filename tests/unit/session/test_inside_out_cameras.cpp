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

struct SessionRun {
  double position_rmse_mm = 0, angle_rmse_deg = 0;
  int poses = 0, wrong = 0;
  TimeNs first_pose_ns = -1;
  std::string summary;
};

// 4 s of the scene through an EstimatorSession: the head camera's frames, and with `fixed` also the
// fixed pair's, fused through the markers on the headset. Poses after 0.5 s are judged.
SessionRun run_session(const Scene& scene, bool fixed) {
  EstimatorSession session(EstimatorConfig{});
  SystemCalibration calibration = scene.calibration();
  const auto moving = take_moving_cameras(calibration);
  EXPECT_EQ(moving.size(), 1u);
  EXPECT_EQ(calibration.cameras.size(), 2u) << "the moving camera must not reach the point tracker";
  session.inside_out().configure(scene.landmarks(), moving, "inside_out.yaml");
  if (fixed) session.inside_out().set_outside_in(calibration, scene.rig_markers(), "inside_out.yaml");
  session.tracker().set_calibration(calibration);

  std::vector<FeatureFrame> frames;
  for (const auto& config : scene.cameras()) {
    if (!fixed && !config.calibration.moving) continue;
    const CameraSimulator camera(scene, config.calibration.id);
    for (std::int64_t k = 0; camera.frame_time_ns(k) < 4 * kNsPerSecond; ++k) {
      frames.push_back(camera.features(k));
      frames.back().stamp_ns += kEpoch;
      frames.back().received_ns += kEpoch;
    }
  }
  sort_by_stamp(frames);
  SessionRun run;
  double position2 = 0, angle2 = 0;
  replay_frames(session, frames, {false, false}, [&](const FeatureFrame& frame, estimator::FrameOutcome) {
    for (const PoseRecord& pose : session.current_poses()) {
      EXPECT_EQ(pose.body, "headset");
      EXPECT_EQ(pose.stamp_ns, frame.stamp_ns);
      const RigidTransform truth = scene.bodies_at(pose.stamp_ns - kEpoch).front().T_world_body;
      const double dp = (pose.p - truth.t).norm();
      const double da =
          Eigen::Quaterniond(pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z()).angularDistance(truth.q);
      if (dp > 0.02 || da > 5.0 * M_PI / 180.0) ++run.wrong;
      if (run.first_pose_ns < 0) run.first_pose_ns = pose.stamp_ns - kEpoch;
      if (pose.stamp_ns - kEpoch < 500'000'000) continue;  // the filter settling after its cold start
      position2 += dp * dp;
      angle2 += da * da;
      ++run.poses;
    }
  });
  run.position_rmse_mm = 1e3 * std::sqrt(position2 / std::max(run.poses, 1));
  run.angle_rmse_deg = std::sqrt(angle2 / std::max(run.poses, 1)) * 180.0 / M_PI;
  const auto lines = session.inside_out().summary_lines();
  run.summary = lines.empty() ? "" : lines.front();
  std::printf(
      "%s: poses %d, first at %.3f s, wrong %d; position RMSE %.3f mm, orientation RMSE %.4f deg\n%s\n",
      fixed ? "fused" : "inside-out alone", run.poses, ns_to_seconds(run.first_pose_ns), run.wrong,
      run.position_rmse_mm, run.angle_rmse_deg, run.summary.c_str());
  return run;
}

TEST(InsideOutCameras, HeadsetPoseFromTheSessionMeetsTheAcceptance) {
  const SessionRun run = run_session(Scene::load(kScene), false);
  EXPECT_GE(run.first_pose_ns, 0);
  EXPECT_LE(run.first_pose_ns, 200'000'000);
  EXPECT_EQ(run.wrong, 0);
  EXPECT_GE(run.poses, 340);  // 3.5 s at 100 Hz, nearly every frame
  EXPECT_LE(run.position_rmse_mm, 1.0);
  EXPECT_LE(run.angle_rmse_deg, 0.05);
  EXPECT_NE(run.summary.find("acquisitions 1"), std::string::npos) << run.summary;
  EXPECT_EQ(run.summary.find("outside-in"), std::string::npos) << run.summary;
}

// Issue 21: a fixed outside-in pair also seeing the headset's markers; the fused pose is better.
TEST(InsideOutCameras, FixedCamerasSeeingTheHeadsetImproveItsPose) {
  const Scene scene = Scene::load(kScene);
  const SessionRun alone = run_session(scene, false);
  const SessionRun fused = run_session(scene, true);
  EXPECT_EQ(fused.wrong, 0);
  EXPECT_GE(fused.poses, 2 * 340);  // after every frame that updated it, of three cameras
  EXPECT_NE(fused.summary.find("outside-in marker updates"), std::string::npos) << fused.summary;
  EXPECT_LT(fused.position_rmse_mm, 0.8 * alone.position_rmse_mm);
  EXPECT_LT(fused.angle_rmse_deg, alone.angle_rmse_deg);
}

// A frame whose landmarks cannot be matched (here: none seen) leaves only a prediction, which is
// never published; the next frame that updates the filter is.
TEST(InsideOutCameras, NoPoseAfterAFrameThatDidNotUpdate) {
  const Scene scene = Scene::load(kScene);
  SystemCalibration calibration = scene.calibration();
  InsideOutCameras cameras;
  cameras.configure(scene.landmarks(), take_moving_cameras(calibration), "inside_out.yaml");
  const CameraSimulator camera(scene, "head");
  for (std::int64_t k = 0; k < 10; ++k)
    ASSERT_EQ(cameras.process(camera.features(k)), estimator::FrameOutcome::kProcessed);
  ASSERT_EQ(cameras.poses_at(camera.frame_time_ns(9), 0).size(), 1u);
  FeatureFrame blank = camera.features(10);
  blank.blobs.clear();
  cameras.process(blank);
  EXPECT_TRUE(cameras.poses_at(blank.stamp_ns, 0).empty());
  cameras.process(camera.features(11));
  ASSERT_EQ(cameras.poses_at(camera.frame_time_ns(11), 0).size(), 1u);
  const RigidTransform truth = scene.bodies_at(camera.frame_time_ns(11)).front().T_world_body;
  EXPECT_LT((cameras.poses_at(camera.frame_time_ns(11), 0).front().p - truth.t).norm(), 0.005);
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
  EXPECT_EQ(calibration.cameras.size(), 2u);  // the fixed pair stays
}

}  // namespace
}  // namespace panoptes::session
