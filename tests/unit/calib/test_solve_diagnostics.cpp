// SPDX-License-Identifier: Apache-2.0
// Calibration honesty (issue 34 item 8): the solve reports how well focal length and depth are
// separated and how consistently the cameras measure the wand, and warns when a small
// reprojection error hides camera positions millimetres off; `calibrate world`'s scale check.
#include <gtest/gtest.h>

#include "calib_scenes.h"
#include "panoptes/calib/scale_check.h"

namespace panoptes::calib::testing {
namespace {

const WandDefinition kWand{{0.0, 0.18, 0.5}};

// The cameras file a user without a chessboard writes: the focal length from the lens and the pixel
// pitch (here 10% long), the principal point at the image centre, no distortion, `nominal: true`.
void nominal(CameraCalibration& camera, double focal_factor) {
  auto& k = camera.intrinsics;
  k.fx = k.fy = 700 * focal_factor;
  k.cx = (k.width - 1) / 2.0;
  k.cy = (k.height - 1) / 2.0;
  k.distortion = {0, 0, 0, 0, 0};
  camera.nominal_intrinsics = true;
}

void print_diagnostics(const SolveResult& result) {
  std::printf("  free wand length: RMS %.3f mm (predicted %.3f mm), median %+.3f mm, max %.3f mm\n",
              result.lengths.rms_error_mm, result.predicted_length_rms_mm, result.lengths.median_error_mm,
              result.lengths.max_abs_error_mm);
  for (const auto& camera : result.cameras) {
    const auto& s = camera.focal_depth;
    std::printf(
        "  %s: depth %.3f m sigma %.3f mm, position sigma %.3f mm, focal %.1f px sigma %.3f px, corr %+.3f, "
        "1%% focal: %.2f mm, +%.4f px\n",
        camera.id.c_str(), s.depth_m, s.depth_sigma_mm, s.position_sigma_mm, camera.intrinsics.fx,
        s.focal_sigma_px, s.correlation, s.shift_per_percent_mm, s.rms_increase_per_percent_px);
  }
  for (const auto& warning : result.warnings) std::printf("  WARNING: %s\n", warning.c_str());
}

SolveOptions with_offsets() {
  SolveOptions options;
  options.time_offsets = true;
  return options;
}

// Issue 34's finding: nominal intrinsics on the wand room, a raw median near 0.2 px, cameras
// millimetres off. Now the free wand length gives it away and the solve warns.
TEST(SolveDiagnostics, NominalIntrinsicsOnTheWandRoomWarn) {
  const Scene scene = Scene::from_yaml_string(scene_yaml(wand_room6()));
  const Measured m = solve_and_measure(scene, kWand, with_offsets(), 0.0, {},
                                       [](CameraCalibration& camera) { nominal(camera, 1.1); });
  print("wand room, nominal intrinsics (f +10%, centred principal point)", m);
  print_diagnostics(m.result);
  ASSERT_TRUE(m.result.ok());
  EXPECT_NE(m.result.intrinsics_refined.find("nominal"), std::string::npos);
  EXPECT_LE(m.result.raw_all.median_px, 0.3) << "the reprojection error looks fine";
  EXPECT_GE(m.max_position_error_mm, 2.5) << "the finding: positions millimetres off";
  EXPECT_GT(m.result.lengths.rms_error_mm, 1.6 * m.result.predicted_length_rms_mm);
  ASSERT_FALSE(m.result.warnings.empty());
  EXPECT_NE(m.result.warnings.back().find("free length"), std::string::npos);
  EXPECT_NE(m.result.warnings.back().find("1% focal length error moves"), std::string::npos);
  for (const auto& camera : m.result.cameras) {
    EXPECT_TRUE(camera.focal_depth.available && camera.focal_depth.focal_free) << camera.id;
    EXPECT_GT(std::abs(camera.focal_depth.shift_per_percent_mm), 5.0) << camera.id;
  }
  // `calibrate world` with an L-frame of 0.5 m and 0.3 m arms at the true origin: the calibration's
  // scale is off by more than the default tolerance.
  const LFrameRecording lframe = record_lframe(m.result, wand_room6(), 0.3);
  std::string error;
  const auto T_new_old = lframe_frame(lframe.points, lframe.up_hint, 0.5, 0.3, &error);
  ASSERT_TRUE(T_new_old) << error;
  const ScaleCheck check = check_scale(lframe_arm_lengths(lframe.points, *T_new_old, 0.5, 0.3), {0.5, 0.3});
  std::printf("  %s", scale_check_summary(check, "L-frame").c_str());
  EXPECT_TRUE(check.exceeded);
}

// The same room with intrinsics that fit (the true ones, still marked nominal so that the focal
// lengths are refined and the correlation computed): no warning, and the figures are what the
// noise allows.
TEST(SolveDiagnostics, GoodIntrinsicsOnTheWandRoomDoNotWarn) {
  const Scene scene = Scene::from_yaml_string(scene_yaml(wand_room6()));
  const Measured m = solve_and_measure(scene, kWand, with_offsets(), 0.0, {},
                                       [](CameraCalibration& camera) { camera.nominal_intrinsics = true; });
  print("wand room, true intrinsics marked nominal", m);
  print_diagnostics(m.result);
  ASSERT_TRUE(m.result.ok());
  EXPECT_LE(m.max_position_error_mm, 1.0);
  EXPECT_TRUE(m.result.warnings.empty());
  EXPECT_LE(m.result.lengths.rms_error_mm, 1.6 * m.result.predicted_length_rms_mm);
  // The prediction is the noise's own figure: the free length's RMS is close to it.
  EXPECT_GE(m.result.lengths.rms_error_mm, 0.7 * m.result.predicted_length_rms_mm);
  for (const auto& camera : m.result.cameras) {
    EXPECT_TRUE(camera.focal_depth.focal_free) << camera.id;
    EXPECT_LT(std::abs(camera.focal_depth.correlation), 0.9) << camera.id;
    EXPECT_GT(camera.focal_depth.position_sigma_mm, 0.0) << camera.id;
    EXPECT_LT(camera.focal_depth.position_sigma_mm, 1.0) << camera.id;
  }
}

// A camera far from a shallow wand volume with a long lens: a longer focal length and a camera
// further away look alike, and the correlation says so.
TEST(SolveDiagnostics, CorrelationWarnsWhenDepthIsNotSeparated) {
  SceneSpec spec = wand_room6();
  spec.wand_path =
      "{type: lissajous, center: [0, 0, 1.0], amplitude: [0.35, 0.35, 0.1], frequency: [0.13, 0.171, 0.23]}";
  spec.duration_s = 6;
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  const Measured m = solve_and_measure(scene, kWand, with_offsets(), 0.0, {},
                                       [](CameraCalibration& camera) { camera.nominal_intrinsics = true; });
  print("wand room, wand in a small shallow volume", m);
  print_diagnostics(m.result);
  ASSERT_TRUE(m.result.ok());
  double strongest = 0;
  for (const auto& camera : m.result.cameras)
    strongest = std::max(strongest, std::abs(camera.focal_depth.correlation));
  EXPECT_GT(strongest, 0.9);
  bool warned = false;
  for (const auto& warning : m.result.warnings)
    warned = warned || warning.find("focal length and depth are not separated") != std::string::npos;
  EXPECT_TRUE(warned);
}

// `calibrate world`'s check on synthetic L-frames: the right scale passes, 0.3% too large warns,
// and the arms are found whatever the frame the calibration is in.
TEST(ScaleCheck, LFrameArmsAgainstTheCalibrationsScale) {
  const RigidTransform T_old_true{
      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(0.4, -1.1, 2.0)};
  const std::vector<Eigen::Vector3d> lframe = {{0, 0, 0}, {0.5, 0, 0}, {0, 0.3, 0}, {1.2, 0.8, 0.0}};
  for (const double scale : {1.0, 1.003, 0.9995}) {
    std::vector<Eigen::Vector3d> points;
    for (const auto& p : lframe) points.push_back(T_old_true.apply(scale * p));
    const Eigen::Vector3d up = T_old_true.apply(Eigen::Vector3d(0, 0, 3));
    std::string error;
    const auto T_new_old = lframe_frame(points, up, 0.5, 0.3, &error);
    ASSERT_TRUE(T_new_old) << error;
    const auto arms = lframe_arm_lengths(points, *T_new_old, 0.5, 0.3);
    ASSERT_EQ(arms.size(), 2u);
    EXPECT_NEAR(arms[0], 0.5 * scale, 1e-9);
    EXPECT_NEAR(arms[1], 0.3 * scale, 1e-9);
    const ScaleCheck check = check_scale(arms, {0.5, 0.3});
    EXPECT_NEAR(check.scale_error_ppm, (scale - 1) * 1e6, 1e-3);
    EXPECT_EQ(check.exceeded, scale == 1.003) << scale;
    const std::string line = scale_check_summary(check, "L-frame");
    EXPECT_EQ(line.find("WARNING") != std::string::npos, scale == 1.003) << line;
  }
}

TEST(ScaleCheck, WandLengthOnTheFloorAndTolerance) {
  const ScaleCheck long_wand = check_scale({0.5012}, {0.5});
  EXPECT_NEAR(long_wand.scale_error_ppm, 2400, 1e-6);
  EXPECT_NEAR(long_wand.max_error_mm, 1.2, 1e-9);
  EXPECT_TRUE(long_wand.exceeded);
  EXPECT_FALSE(check_scale({0.5012}, {0.5}, 0.003).exceeded) << "--scale-tolerance 0.003";
  EXPECT_FALSE(check_scale({0.4998}, {0.5}).exceeded);
  EXPECT_EQ(check_scale({}, {}).lengths, 0);
}

}  // namespace
}  // namespace panoptes::calib::testing
