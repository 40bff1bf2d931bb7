// SPDX-License-Identifier: Apache-2.0
// A bumped camera (camera key `bump`, issue 36): its true pose turns and shifts at `at`, in its own
// frame, while the calibration keeps the pose from before.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "panoptes/errors.h"
#include "panoptes/simulator.h"

namespace panoptes {
namespace {

std::string scene_with(const std::string& bump) {
  return "cameras:\n"
         "  - id: c0\n"
         "    width: 640\n"
         "    height: 480\n"
         "    K: [500, 500, 320, 240]\n"
         "    look_at: {eye: [3, 0, 1], target: [0, 0, 1]}\n" +
         bump +
         "markers:\n"
         "  - name: m\n"
         "    path: {type: static, position: [0, 0, 1]}\n";
}

TEST(CameraBump, ThePoseTurnsAndShiftsAtTheGivenTimeAndTheCalibrationDoesNot) {
  const Scene scene = Scene::from_yaml_string(
      scene_with("    bump: {at: 2.0, rotation: [0, 0.01, 0], translation: [0.005, 0, 0]}\n"));
  const RigidTransform before = scene.camera_pose_at(0, 1'999'999'999);
  const RigidTransform after = scene.camera_pose_at(0, 2'000'000'000);
  const RigidTransform calibrated = *scene.calibration().cameras[0].T_world_cam;
  EXPECT_TRUE(before.q.isApprox(calibrated.q));
  EXPECT_TRUE(before.t.isApprox(calibrated.t));
  EXPECT_NEAR(before.q.angularDistance(after.q), 0.01, 1e-12);
  // The shift is along the camera's own x axis.
  EXPECT_TRUE((after.t - before.t).isApprox(before.q * Eigen::Vector3d(0.005, 0, 0), 1e-12));
  // The marker's image moves by about f × 0.01 rad.
  const CameraSimulator simulator(scene, "c0");
  const auto first = simulator.features(0);
  const auto late = simulator.features(simulator.frames_in(2'000'000'000, 3'000'000'000).first);
  ASSERT_EQ(first.blobs.size(), 1u);
  ASSERT_EQ(late.blobs.size(), 1u);
  EXPECT_NEAR(std::hypot(late.blobs[0].x - first.blobs[0].x, late.blobs[0].y - first.blobs[0].y), 5.0, 1.0);
}

TEST(CameraBump, BadKeysAreNamed) {
  EXPECT_THROW(Scene::from_yaml_string(scene_with("    bump: {at: -1}\n")), ConfigError);
  EXPECT_THROW(Scene::from_yaml_string(scene_with("    bump: {at: 1, turn: [0, 0, 1]}\n")), ConfigError);
}

}  // namespace
}  // namespace panoptes
