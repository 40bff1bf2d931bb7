// SPDX-License-Identifier: Apache-2.0
// Acceptance of the wand calibration on seeded simulations (issue 6).
#include <gtest/gtest.h>

#include "calib_scenes.h"

namespace panoptes::calib::testing {
namespace {

const WandDefinition kWand{{0.0, 0.18, 0.5}};

TEST(WandSolver, EightCamerasRoomKnownIntrinsics) {
  const Scene scene = Scene::from_yaml_string(scene_yaml(room8()));
  SolveOptions options;
  options.progress = [](const std::string& m) { std::printf("  %s\n", m.c_str()); };
  const Measured m = solve_and_measure(scene, kWand, options);
  print("room8", m);
  print_coverage(m, scene);
  ASSERT_TRUE(m.result.ok());
  EXPECT_EQ(m.result.calibrated_count(), 8);
  EXPECT_LE(m.result.raw_rms_axis_px, 0.11);
  EXPECT_LE(m.max_position_error_mm, 1.0);
  EXPECT_LE(m.max_rotation_error_deg, 0.02);
  EXPECT_LE(std::abs(m.result.lengths.mean_error_mm), 0.05);
  // The spread of freely triangulated lengths is set by the centroid noise: the calibration must
  // not add to it measurably (see docs/calibration.md for the 0.1 mm goal and the optics it needs).
  EXPECT_LE(m.result.lengths.sigma_mm, std::max(0.1, 1.05 * m.truth_lengths.sigma_mm));
}

TEST(WandSolver, RefinesIntrinsicsAndDistortionFromFivePercentOff) {
  SceneSpec spec = room8();
  spec.distortion = "[-0.09, 0.04, 0.0006, -0.0004, 0]";
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  SolveOptions options;
  options.refine_intrinsics = true;
  const Measured m = solve_and_measure(scene, kWand, options, 0.05);
  print("room8 intrinsics from 5% off", m);
  ASSERT_TRUE(m.result.ok());
  EXPECT_LE(m.max_focal_error_rel, 0.001);
  EXPECT_LE(m.result.raw_rms_axis_px, 0.11);
  EXPECT_LE(m.max_position_error_mm, 2.0);
}

TEST(WandSolver, LShapedCorridorNoPointSeenByAll) {
  const Scene scene = Scene::from_yaml_string(scene_yaml(corridor10()));
  SolveOptions options;
  const Measured m = solve_and_measure(scene, kWand, options);
  print("corridor10", m);
  int most_cameras = 0;
  for (const auto& sample : m.result.samples) most_cameras = std::max(most_cameras, sample.cameras);
  std::printf("  most cameras seeing one sample: %d of 10\n", most_cameras);
  EXPECT_LT(most_cameras, 10);
  ASSERT_TRUE(m.result.ok());
  EXPECT_EQ(m.result.calibrated_count(), 10);
  EXPECT_LE(m.max_position_error_mm, 2.0);
  EXPECT_LE(m.max_rotation_error_deg, 0.04);
}

TEST(WandSolver, AsynchronousPhasesAndUnknownClockOffsets) {
  SceneSpec spec = room8();
  const double offsets_ms[8] = {0.0, 1.7, -2.0, 0.6, -1.1, 2.0, -0.4, 1.2};
  for (std::size_t i = 0; i < spec.cameras.size(); ++i) {
    spec.cameras[i].phase_s = 1.3e-3 * static_cast<double>(i);  // 0 .. 9.1 ms
    spec.cameras[i].clock_offset_s = offsets_ms[i] * 1e-3;
  }
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  SolveOptions without;
  const Measured ignored = solve_and_measure(scene, kWand, without);
  print("room8 async, offsets ignored", ignored);
  SolveOptions options;
  options.time_offsets = true;
  const Measured m = solve_and_measure(scene, kWand, options);
  print("room8 async, offsets estimated", m);
  ASSERT_TRUE(m.result.ok());
  EXPECT_LE(m.max_offset_error_ms, 0.1);
  EXPECT_LE(m.result.raw_rms_axis_px, 0.11);
  EXPECT_LE(m.max_position_error_mm, 1.0);
  EXPECT_LE(m.max_rotation_error_deg, 0.02);
}

}  // namespace
}  // namespace panoptes::calib::testing
