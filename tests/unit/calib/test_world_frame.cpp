// SPDX-License-Identifier: Apache-2.0
// `calibrate world --wand-floor`: the world frame from the calibration wand laid on the floor at
// several places (world_frame.h, wand_floor_frame). The 8-camera wide-lens room records the wand
// resting and sliding on the floor z = 0; the cameras are given in an unknown frame (a rigid
// transform of the truth, or a similarity for an unscaled calibration) and the step must recover
// the true floor, origin and x axis.
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib_scenes.h"
#include "panoptes/calib/world_frame.h"

namespace panoptes::calib::testing {
namespace {

constexpr double kMarkerRadius = 0.007;  // the simulator's default: marker centres 7 mm up

// A rest of the wand's centre at (x, y, z) with heading `yaw` (rad about z).
struct Rest {
  double x, y, z, yaw;
};

// The wand (0, 0.18, 0.5 m: body markers at x = -0.25, -0.07, 0.25) rests 1.5 s at each place and
// slides (turning) to the next in 1 s.
SceneSpec floor_scene(const std::vector<Rest>& rests) {
  SceneSpec spec = room8();
  std::ostringstream points, quaternions, times;
  points.precision(12);
  quaternions.precision(12);
  double t = 0;
  for (std::size_t i = 0; i < rests.size(); ++i) {
    const auto& r = rests[i];
    for (int k = 0; k < 2; ++k) {
      const char* separator = (i == 0 && k == 0) ? "" : ", ";
      points << separator << "[" << r.x << ", " << r.y << ", " << r.z << "]";
      quaternions << separator << "[0, 0, " << std::sin(r.yaw / 2) << ", " << std::cos(r.yaw / 2) << "]";
      times << separator << t;
      t += k == 0 ? 1.5 : 1.0;
    }
  }
  spec.duration_s = t - 1.0;
  spec.wand_path = "{type: waypoints, points: [" + points.str() + "], times: [" + times.str() + "]}";
  spec.wand_rotation = "{type: waypoints, q: [" + quaternions.str() + "], times: [" + times.str() + "]}";
  return spec;
}

std::vector<Rest> on_the_floor(double z = kMarkerRadius) {
  return {{0.3, -0.2, z, 0.3},
          {-0.8, 0.5, z, 1.2},
          {0.9, 0.8, z, -0.6},
          {-0.5, -0.9, z, 2.0},
          {0.7, -1.0, z, 0.9}};
}

struct Recording {
  SystemCalibration truth;
  std::vector<FeatureFrame> frames;
};

Recording record(const SceneSpec& spec) {
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  Recording recording;
  for (std::size_t c = 0; c < scene.cameras().size(); ++c) {
    recording.truth.cameras.push_back(scene.cameras()[c].calibration);
    const auto frames = simulate_frames(scene, c);
    recording.frames.insert(recording.frames.end(), frames.begin(), frames.end());
  }
  return recording;
}

// The cameras in an arbitrary frame: p_old = T_old_true(p_true) / metres_per_unit.
RigidTransform unknown_frame() {
  RigidTransform T_old_true;
  T_old_true.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 1).normalized()));
  T_old_true.t = Eigen::Vector3d(0.4, -1.3, 0.9);
  return T_old_true;
}

SystemCalibration moved(const SystemCalibration& truth, const RigidTransform& T_old_true,
                        double metres_per_unit) {
  SystemCalibration calibration = truth;
  for (auto& camera : calibration.cameras) {
    camera.T_world_cam = T_old_true * *camera.T_world_cam;
    camera.T_world_cam->t /= metres_per_unit;
  }
  return calibration;
}

const WandDefinition kWand{{0, 0.18, 0.5}};

// The recovered frame against the true one: the first rest's first marker on the floor is the
// origin, x runs along the wand there, z is up.
void expect_true_frame(const WandFloorResult& result, const RigidTransform& T_old_true,
                       double metres_per_unit, const Rest& first) {
  ASSERT_TRUE(result.T_new_old) << result.error;
  const Eigen::Vector3d along(std::cos(first.yaw), std::sin(first.yaw), 0);
  const Eigen::Vector3d origin_true = Eigen::Vector3d(first.x, first.y, 0) - 0.25 * along;
  const auto to_new = [&](const Eigen::Vector3d& p_true) {
    return (result.scale * result.T_new_old->apply(T_old_true.apply(p_true) / metres_per_unit)).eval();
  };
  const Eigen::Vector3d origin = to_new(origin_true);
  const Eigen::Vector3d z_axis = to_new(origin_true + Eigen::Vector3d::UnitZ()) - origin;
  const Eigen::Vector3d x_axis = to_new(origin_true + along) - origin;
  const double z_error_deg =
      std::acos(std::clamp(z_axis.normalized().z(), -1.0, 1.0)) * 180 / std::numbers::pi;
  const double x_error_deg =
      std::acos(std::clamp(x_axis.normalized().x(), -1.0, 1.0)) * 180 / std::numbers::pi;
  std::printf("[wand floor] origin error %.3f mm, z error %.4f deg, x error %.4f deg, scale error %.4f%%\n",
              origin.norm() * 1e3, z_error_deg, x_error_deg, (z_axis.norm() - 1) * 100);
  EXPECT_LT(origin.norm(), 0.001);
  EXPECT_LT(z_error_deg, 0.05);
  EXPECT_LT(x_error_deg, 0.2);  // from the 0.5 m wand at one rest only
  EXPECT_NEAR(z_axis.norm(), 1.0, 1e-3) << "metric scale";
}

TEST(WandFloor, RecoversTheFloorOriginAndAxesFromFivePlacements) {
  const Recording recording = record(floor_scene(on_the_floor()));
  const RigidTransform T_old_true = unknown_frame();
  WandFloorOptions options;
  options.floor_offset_m = kMarkerRadius;
  const WandFloorResult result =
      wand_floor_frame(moved(recording.truth, T_old_true, 1.0), recording.frames, kWand, false, options);
  std::printf("%s", wand_floor_summary(result).c_str());
  expect_true_frame(result, T_old_true, 1.0, on_the_floor().front());
  EXPECT_EQ(result.placements.size(), 5u);
  EXPECT_GT(result.floor_instants, result.instants * 9 / 10) << "sliding on the floor is on the plane too";
  EXPECT_LT(result.plane_rms_mm, 0.5) << "about the triangulation noise of 0.1 px";
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
  // The true tilt of the old frame's z: the angle of the unknown rotation's z axis.
  const double tilt =
      std::acos((T_old_true.rotation().transpose() * Eigen::Vector3d::UnitZ()).z()) * 180 / std::numbers::pi;
  EXPECT_NEAR(result.tilt_deg, tilt, 0.05);
  // Every placement's marker centres lie kMarkerRadius above the new floor.
  for (const auto& placement : result.placements)
    for (const auto& marker : placement.markers) EXPECT_NEAR(marker.z(), kMarkerRadius, 0.001);
}

TEST(WandFloor, UnscaledCalibrationIsScaledByTheWandsLength) {
  const Recording recording = record(floor_scene(on_the_floor()));
  const RigidTransform T_old_true = unknown_frame();
  const double metres_per_unit = 2.7;
  WandFloorOptions options;
  options.floor_offset_m = kMarkerRadius;
  const WandFloorResult result = wand_floor_frame(moved(recording.truth, T_old_true, metres_per_unit),
                                                  recording.frames, kWand, true, options);
  EXPECT_TRUE(result.scaled_by_wand);
  EXPECT_NEAR(result.scale / metres_per_unit, 1.0, 2e-4);
  expect_true_frame(result, T_old_true, metres_per_unit, on_the_floor().front());
}

TEST(WandFloor, TwoMarkerBarWhoseEndsLookAlike) {
  // The first rest's end nearer the middle of the room is the origin: the -0.25 m end here.
  SceneSpec spec = floor_scene(on_the_floor());
  spec.wand_markers = "[[-0.25, 0, 0], [0.25, 0, 0]]";
  const Recording recording = record(spec);
  const RigidTransform T_old_true = unknown_frame();
  WandFloorOptions options;
  options.floor_offset_m = kMarkerRadius;
  const WandFloorResult result = wand_floor_frame(moved(recording.truth, T_old_true, 1.0), recording.frames,
                                                  WandDefinition{{0, 0.5}}, false, options);
  EXPECT_EQ(result.placements.size(), 5u);
  EXPECT_GT(result.floor_instants, result.instants * 9 / 10);
  expect_true_frame(result, T_old_true, 1.0, on_the_floor().front());
}

TEST(WandFloor, PlacementsAlongOneLineAreRefused) {
  // The wand laid end to end along x: every position on one line, the floor's roll unknown.
  const std::vector<Rest> rests{{-1.0, 0.1, kMarkerRadius, 0},
                                {-0.3, 0.1, kMarkerRadius, 0},
                                {0.4, 0.1, kMarkerRadius, 0},
                                {1.0, 0.1, kMarkerRadius, 0}};
  const Recording recording = record(floor_scene(rests));
  const WandFloorResult result = wand_floor_frame(recording.truth, recording.frames, kWand, false);
  EXPECT_FALSE(result.T_new_old);
  EXPECT_NE(result.error.find("on one line"), std::string::npos) << result.error;
}

TEST(WandFloor, WandHeldInTheAirAtVaryingHeightsIsRefused) {
  std::vector<Rest> rests = on_the_floor();
  const double heights[] = {0.6, 1.1, 0.3, 1.4, 0.9};
  for (std::size_t i = 0; i < rests.size(); ++i) rests[i].z = heights[i];
  const Recording recording = record(floor_scene(rests));
  const WandFloorResult result = wand_floor_frame(recording.truth, recording.frames, kWand, false);
  std::printf("%s", wand_floor_summary(result).c_str());
  EXPECT_FALSE(result.T_new_old);
  EXPECT_NE(result.error.find("off the floor plane"), std::string::npos) << result.error;
}

TEST(WandFloor, OnePlacementOnAMatWarnsOfThePlaneRms) {
  // The third placement 12 mm up (a mat): within the refusal limit, but the RMS says so.
  std::vector<Rest> rests = on_the_floor();
  rests[2].z += 0.012;
  const Recording recording = record(floor_scene(rests));
  const WandFloorResult result = wand_floor_frame(recording.truth, recording.frames, kWand, false);
  std::printf("%s", wand_floor_summary(result).c_str());
  ASSERT_TRUE(result.T_new_old) << result.error;
  EXPECT_GT(result.plane_rms_mm, 2.0);
  ASSERT_EQ(result.warnings.size(), 2u);
  EXPECT_NE(result.warnings[0].find("placement 3"), std::string::npos) << result.warnings[0];
  EXPECT_NE(result.warnings[1].find("plane RMS"), std::string::npos) << result.warnings[1];
  EXPECT_NEAR(result.placements[2].height_mm, 12.0, 0.5);
  EXPECT_LT(result.tilt_deg, 0.02) << "the mat is left out of the fit";
}

TEST(WandFloor, TooFewFramesAndSingleLightAreRefused) {
  const Recording recording = record(floor_scene(on_the_floor()));
  const std::vector<FeatureFrame> few(recording.frames.begin(), recording.frames.begin() + 80);
  const WandFloorResult result = wand_floor_frame(recording.truth, few, kWand, false);
  EXPECT_FALSE(result.T_new_old);
  EXPECT_NE(result.error.find("too few wand instants"), std::string::npos) << result.error;
  const WandFloorResult single =
      wand_floor_frame(recording.truth, recording.frames, WandDefinition{{0}}, true);
  EXPECT_FALSE(single.T_new_old);
  EXPECT_NE(single.error.find("two or more markers"), std::string::npos) << single.error;
}

}  // namespace
}  // namespace panoptes::calib::testing
