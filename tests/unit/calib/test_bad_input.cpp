// SPDX-License-Identifier: Apache-2.0
// Bad calibration input: each problem is named with the cameras it concerns, and the cameras that
// can still be calibrated are.
#include <gtest/gtest.h>

#include "calib_scenes.h"

namespace panoptes::calib::testing {
namespace {

const WandDefinition kWand{{0.0, 0.18, 0.5}};

struct Data {
  std::vector<CameraCalibration> cameras;
  std::vector<CameraWandTrack> tracks;
};

// Eight room cameras, 8 s of wand; camera 7 looks at the ceiling and never sees the wand.
const Data& data() {
  static const Data cached = [] {
    SceneSpec spec = room8();
    spec.duration_s = 8;
    spec.cameras[7].target = spec.cameras[7].eye + Eigen::Vector3d(0.1, 0.1, 1.0);
    const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
    Data d;
    std::vector<CameraIntrinsics> intrinsics;
    for (const auto& config : scene.cameras()) {
      CameraCalibration camera = config.calibration;
      camera.T_world_cam.reset();
      d.cameras.push_back(camera);
      intrinsics.push_back(camera.intrinsics);
    }
    d.tracks = simulate_tracks(scene, kWand, intrinsics);
    return d;
  }();
  return cached;
}

bool has_error(const SolveResult& result, const std::string& camera, const std::string& text) {
  for (const auto& e : result.errors)
    if (e.find(camera) != std::string::npos && e.find(text) != std::string::npos) return true;
  return false;
}

TEST(BadInput, CameraThatNeverSawTheWandIsNamedOthersCalibrated) {
  const auto result = solve_wand_calibration(data().cameras, data().tracks, kWand);
  EXPECT_TRUE(has_error(result, "cam7", "never saw the wand")) << report_summary_for_test(result);
  EXPECT_FALSE(result.cameras[7].T_world_cam.has_value());
  EXPECT_EQ(result.calibrated_count(), 7);
}

TEST(BadInput, CameraWithoutFeaturesIsNamed) {
  auto tracks = data().tracks;
  tracks.erase(tracks.begin() + 2);  // no file for cam2
  const auto result = solve_wand_calibration(data().cameras, tracks, kWand);
  EXPECT_TRUE(has_error(result, "cam2", "no features"));
  EXPECT_EQ(result.calibrated_count(), 6);
}

TEST(BadInput, TooFewObservations) {
  auto tracks = data().tracks;
  tracks[3].frames.resize(10);
  const auto result = solve_wand_calibration(data().cameras, tracks, kWand);
  EXPECT_TRUE(has_error(result, "cam3", "too few wand observations"));
  EXPECT_FALSE(result.cameras[3].T_world_cam.has_value());
}

TEST(BadInput, DisconnectedViewGraphNamesBothGroups) {
  // cam0-cam2 recorded only in the first half, cam3-cam6 only in the second: no common instant.
  auto tracks = data().tracks;
  const TimeNs middle = kEpoch + 4'000'000'000;
  for (std::size_t c = 0; c < 7; ++c) {
    auto& frames = tracks[c].frames;
    std::erase_if(frames,
                  [&](const WandFrame& f) { return c < 3 ? f.stamp_ns >= middle : f.stamp_ns < middle; });
  }
  const auto result = solve_wand_calibration(data().cameras, tracks, kWand);
  EXPECT_TRUE(has_error(result, "cam0", "disconnected view graph")) << report_summary_for_test(result);
  EXPECT_TRUE(has_error(result, "cam0", "cam3"));
  EXPECT_EQ(result.calibrated_count(), 4);  // the larger group, cam3..cam6
}

TEST(BadInput, WrongWandSpacingLengthsNeverMatch) {
  const WandDefinition wrong{{0.0, 0.3, 0.5}};  // the real wand has its middle marker at 0.18
  std::vector<CameraWandTrack> tracks;
  // Identify again with the wrong definition: the spacing never fits.
  SceneSpec spec = room8();
  spec.duration_s = 3;
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  std::vector<CameraIntrinsics> intrinsics;
  for (const auto& camera : data().cameras) intrinsics.push_back(camera.intrinsics);
  tracks = simulate_tracks(scene, wrong, intrinsics);
  const auto result = solve_wand_calibration(data().cameras, tracks, wrong);
  EXPECT_EQ(result.calibrated_count(), 0);
  EXPECT_TRUE(has_error(result, "cam0", "lengths never match")) << report_summary_for_test(result);
}

TEST(BadInput, MalformedWandIsRejected) {
  EXPECT_THROW(parse_wand("0,abc,0.5"), std::invalid_argument);
  EXPECT_THROW(parse_wand("0,0.5,0.2"), std::invalid_argument);
  EXPECT_NO_THROW(parse_wand("0,0.18,0.5"));
}

}  // namespace
}  // namespace panoptes::calib::testing
