// SPDX-License-Identifier: Apache-2.0
// A camera carried by a rig (inside-out tracking, docs/inside_out.md): its pose is the rig's times
// its mount, its features show the scene's landmarks where that moving pose projects them, the
// rig's truth is listed with the bodies', and the calibration marks the camera as moving.
#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/calibration_file.h"
#include "panoptes/config.h"
#include "panoptes/simulator.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;

const fs::path kScene = fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "scenes" / "inside_out.yaml";

TEST(MovingCamera, InsideOutSceneCarriesTheHeadCameraOnItsRig) {
  const Scene scene = Scene::load(kScene);
  ASSERT_EQ(scene.cameras().size(), 3u);  // the head camera and a fixed pair
  const CameraCalibration& head = scene.cameras()[0].calibration;
  EXPECT_FALSE(scene.cameras()[1].calibration.moving);
  EXPECT_TRUE(head.moving);
  EXPECT_EQ(head.rig, "headset");
  EXPECT_EQ(scene.rig_names(), (std::vector<std::string>{"headset"}));
  ASSERT_EQ(scene.landmarks().size(), 5u);
  std::size_t landmarks = 0;
  for (const auto& group : scene.landmarks()) landmarks += group.points.size();
  EXPECT_EQ(landmarks, 20u);
  EXPECT_EQ(scene.marker_names().front(), "ceiling0/0");
  EXPECT_EQ(scene.marker_names().back(), "headset/3");  // the rig's own markers come last
  ASSERT_EQ(scene.rig_markers().count("headset"), 1u);
  EXPECT_EQ(scene.rig_markers().at("headset").size(), 4u);

  // The rig walks the 1.5 m circle 1.7 m high at 1.2 m/s, heading swinging at up to 2.9 rad/s.
  double max_turn_rate = 0.0;
  for (TimeNs t = 0; t < 5 * kNsPerSecond; t += 10 * kNsPerMillisecond) {
    const auto bodies = scene.bodies_at(t);
    ASSERT_EQ(bodies.size(), 1u);
    const RigidTransform& rig = bodies[0].T_world_body;
    EXPECT_NEAR(rig.t.head<2>().norm(), 1.5, 1e-9);
    EXPECT_NEAR(rig.t.z(), 1.7, 1e-9);
    const RigidTransform later = scene.bodies_at(t + kNsPerMillisecond)[0].T_world_body;
    EXPECT_NEAR((later.t - rig.t).norm() / 1e-3, 1.2, 0.01);
    max_turn_rate = std::max(max_turn_rate, later.q.angularDistance(rig.q) / 1e-3);
    // The camera looks 40 degrees up: its optical axis in the world.
    const Eigen::Vector3d axis = scene.camera_pose_at(0, t).q * Eigen::Vector3d::UnitZ();
    EXPECT_NEAR(std::asin(axis.z()) * 180.0 / M_PI, 40.0, 1e-6);
    EXPECT_TRUE(scene.camera_pose_at(0, t).t.isApprox(rig.t, 1e-12));
    // The rig's markers move with it.
    const auto markers = scene.markers_at(t);
    EXPECT_TRUE(markers.back().p.isApprox(rig.apply(scene.rig_markers().at("headset").back()), 1e-12));
  }
  EXPECT_NEAR(max_turn_rate, 2.9, 0.05);
}

TEST(MovingCamera, FeaturesFollowTheMovingPose) {
  const Scene scene = Scene::load(kScene);
  const CameraSimulator camera(scene, "head");
  const CameraIntrinsics& intrinsics = scene.cameras()[0].calibration.intrinsics;
  int seen = 0;
  for (std::int64_t k = 0; k < 300; k += 37) {
    const FeatureFrame frame = camera.features(k);
    const CameraModel model(intrinsics, scene.camera_pose_at(0, camera.frame_time_ns(k)));
    const auto markers = scene.markers_at(camera.frame_time_ns(k));
    const auto visible = camera.visible_markers(k);
    ASSERT_EQ(frame.blobs.size(), visible.size());
    EXPECT_GE(visible.size(), 4u) << "frame " << k;
    for (std::size_t i = 0; i < visible.size(); ++i) {
      EXPECT_EQ(markers[static_cast<std::size_t>(visible[i])].name.rfind("ceiling", 0), 0u)
          << "the head camera sees only landmarks, never the markers on its own rig";
      const auto pixel = model.project(markers[static_cast<std::size_t>(visible[i])].p);
      ASSERT_TRUE(pixel);
      // Centroid noise is 0.1 px: 1 px is far beyond it, and far below a fixed camera's error.
      EXPECT_LT((*pixel - Eigen::Vector2d(frame.blobs[i].x, frame.blobs[i].y)).norm(), 1.0);
      ++seen;
    }
  }
  EXPECT_GT(seen, 20);
  // The fixed pair sees the headset's markers.
  const CameraSimulator fixed(scene, "fixed0");
  int headset_seen = 0;
  for (std::int64_t k = 0; k < 1000; k += 50)
    for (int index : fixed.visible_markers(k))
      headset_seen += scene.marker_names()[static_cast<std::size_t>(index)].rfind("headset/", 0) == 0 ? 1 : 0;
  EXPECT_GE(headset_seen, 60);  // of 80
}

TEST(MovingCamera, CalibrationMarksTheCameraMovingAndNamesItsRig) {
  const Scene scene = Scene::load(kScene);
  const std::string yaml = calibration_to_yaml(scene.calibration());
  EXPECT_NE(yaml.find("moving: true"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("rig: \"headset\""), std::string::npos) << yaml;
  const fs::path path =
      fs::temp_directory_path() / ("panoptes_moving_" + std::to_string(::getpid()) + ".yaml");
  save_calibration(scene.calibration(), path);
  const SystemCalibration loaded = load_calibration(path);
  fs::remove(path);
  ASSERT_EQ(loaded.cameras.size(), 3u);
  EXPECT_TRUE(loaded.cameras[0].moving);
  EXPECT_EQ(loaded.cameras[0].rig, "headset");
}

TEST(MovingCamera, RigErrorsNameTheKey) {
  const std::string camera = R"(
cameras:
  - id: head
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    rig: {path: {type: static, position: [0, 0, 1]}, turn: 3}
markers:
  - {path: {type: static, position: [0, 0, 3]}}
)";
  try {
    Scene::from_yaml_string(camera, ".", "rig.yaml");
    FAIL() << "an unknown rig key was accepted";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("rig.yaml: cameras[0].rig.turn"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace panoptes
