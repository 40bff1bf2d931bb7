// SPDX-License-Identifier: Apache-2.0
// Stage 3 of the wand solver on its own (bundle_adjustment.h): from a perturbed start, the
// adjustment reduces the reprojection error and recovers the known cameras and wand.
#include <gtest/gtest.h>

#include "panoptes/calib/bundle_adjustment.h"
#include "stage_scenes.h"

namespace panoptes::calib::testing {
namespace {

std::vector<CameraIntrinsics> given_intrinsics(const StageScene& scene) {
  std::vector<CameraIntrinsics> given;
  for (const auto& camera : scene.cameras) given.push_back(camera.intrinsics);
  return given;
}

// The truth in the frame of camera 0 (the gauge), cameras other than 0 moved by ~`error_m` and
// ~`error_rad`, every marker by ~`error_m`, all at random.
BundleState perturbed_state(const StageScene& scene, const std::vector<WandInstant>& instants, double error_m,
                            double error_rad) {
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 1.0);
  const auto random = [&]() { return Eigen::Vector3d(noise(rng), noise(rng), noise(rng)); };
  const RigidTransform T_0_world = scene.cameras[0].T_world_cam->inverse();
  BundleState state;
  for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
    RigidTransform T = T_0_world * *scene.cameras[c].T_world_cam;
    if (c != 0) {
      T.t += error_m * random();
      const Eigen::Vector3d w = error_rad * random();
      T.q = Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized())) * T.q;
    }
    state.cameras.push_back(camera_parameters(scene.cameras[c].intrinsics, T));
  }
  state.instants = instants;
  const std::size_t markers = scene.wand.marker_count();
  for (const auto& instant : instants) {
    const auto& truth = scene.wand_markers[static_cast<std::size_t>(instant.t_ns / 10'000'000)];
    for (std::size_t m = 0; m < markers; ++m) {
      const Eigen::Vector3d X = T_0_world.apply(truth[m]) + error_m * random();
      state.points.insert(state.points.end(), X.data(), X.data() + 3);
    }
  }
  return state;
}

// The largest position (m) and rotation (deg) error of the cameras against the truth in the
// frame of camera 0.
struct CameraErrors {
  double position_m = 0, rotation_deg = 0;
};

CameraErrors camera_errors(const StageScene& scene, const BundleState& state) {
  const RigidTransform T_0_world = scene.cameras[0].T_world_cam->inverse();
  CameraErrors worst;
  for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
    const RigidTransform truth = T_0_world * *scene.cameras[c].T_world_cam;
    const RigidTransform estimated = T_world_cam_of(state.cameras[c]);
    worst.position_m = std::max(worst.position_m, (estimated.t - truth.t).norm());
    worst.rotation_deg = std::max(worst.rotation_deg, truth.q.angularDistance(estimated.q) * 180 / M_PI);
  }
  return worst;
}

double max_camera_error_m(const StageScene& scene, const BundleState& state) {
  return camera_errors(scene, state).position_m;
}

double max_rotation_error_deg(const StageScene& scene, const BundleState& state) {
  return camera_errors(scene, state).rotation_deg;
}

TEST(BundleAdjustment, CameraParametersRoundTrip) {
  const StageScene scene = ring_stage_scene(3, 0);
  const CameraParameters camera =
      camera_parameters(scene.cameras[1].intrinsics, scene.cameras[1].T_world_cam);
  EXPECT_TRUE(camera.registered);
  const RigidTransform back = T_world_cam_of(camera);
  EXPECT_LT((back.t - scene.cameras[1].T_world_cam->t).norm(), 1e-12);
  EXPECT_LT(back.q.angularDistance(scene.cameras[1].T_world_cam->q), 1e-12);
  EXPECT_EQ(intrinsics_of(camera, scene.cameras[1].intrinsics).fx, scene.cameras[1].intrinsics.fx);
  EXPECT_FALSE(camera_parameters(scene.cameras[1].intrinsics, std::nullopt).registered);
}

TEST(BundleAdjustment, TriangulatesTheWandFromRegisteredCamerasOnly) {
  const StageScene scene = ring_stage_scene(4, 50);
  BundleState state;
  for (const auto& camera : scene.cameras)
    state.cameras.push_back(camera_parameters(camera.intrinsics, camera.T_world_cam));
  state.cameras[3].registered = false;
  state.instants = stage_instants(scene);
  const BundleState triangulated = triangulate_instants(state, given_intrinsics(scene), 3);
  ASSERT_EQ(triangulated.points.size(), triangulated.instants.size() * 9);
  for (std::size_t s = 0; s < triangulated.instants.size(); ++s) {
    const auto& truth =
        scene.wand_markers[static_cast<std::size_t>(triangulated.instants[s].t_ns / 10'000'000)];
    int registered = 0;
    for (const auto& observation : triangulated.instants[s].observations)
      registered += observation.camera != 3 ? 1 : 0;
    if (registered < 2) continue;  // one ray: nothing to triangulate
    for (const auto& observation : triangulated.instants[s].observations)
      EXPECT_EQ(observation.active, observation.camera != 3);
    for (std::size_t m = 0; m < 3; ++m)
      EXPECT_LT((Eigen::Vector3d(&triangulated.points[(s * 3 + m) * 3]) - truth[m]).norm(), 1e-9);
  }
}

TEST(BundleAdjustment, OnePassRecoversKnownCamerasAndWandFromAPerturbedStart) {
  const StageScene scene = ring_stage_scene(4, 150);
  const auto instants = stage_instants(scene);
  const BundleState start = perturbed_state(scene, instants, 0.02, 0.01);
  ASSERT_GT(max_camera_error_m(scene, start), 0.01);
  // The start's error, as a pass that cannot move would report it.
  PassOptions frozen;
  frozen.max_iterations = 0;
  const double start_rms = adjust_pass(start, scene.wand, frozen, false).report.rms_px;
  PassOptions options;
  const PassResult adjusted = adjust_pass(start, scene.wand, options, false);
  EXPECT_TRUE(adjusted.report.converged) << adjusted.report.termination;
  EXPECT_GT(start_rms, 5.0);
  EXPECT_LT(adjusted.report.rms_px, 1e-6);
  EXPECT_LT(max_camera_error_m(scene, adjusted.state), 1e-6);
  EXPECT_LT(max_rotation_error_deg(scene, adjusted.state), 1e-6);
  EXPECT_TRUE(T_world_cam_of(adjusted.state.cameras[0]).t ==
              T_world_cam_of(start.cameras[0]).t);  // the gauge
  EXPECT_EQ(adjusted.report.steps + 1, adjusted.report.iterations);
}

TEST(BundleAdjustment, WithNoiseTheWandLengthsKeepTheScale) {
  const StageScene scene = ring_stage_scene(4, 200);
  const auto instants = stage_instants(scene, 0.1);
  const PassResult adjusted =
      adjust_pass(perturbed_state(scene, instants, 0.02, 0.01), scene.wand, PassOptions{}, true);
  EXPECT_GT(adjusted.report.rms_px, 0.05);
  EXPECT_LT(adjusted.report.rms_px, 0.2);
  EXPECT_LT(max_camera_error_m(scene, adjusted.state), 0.002);
  EXPECT_LT(max_rotation_error_deg(scene, adjusted.state), 0.05);
}

TEST(BundleAdjustment, ClockOffsetsAreRecoveredFromTheTracksVelocity) {
  const StageScene scene = ring_stage_scene(4, 150);
  auto instants = stage_instants(scene);
  // Camera 2's clock is 1.5 ms ahead: its observation at an instant is where its track will be
  // 1.5 ms later, and the track moves at 200 px/s along x.
  for (auto& instant : instants)
    for (auto& observation : instant.observations)
      if (observation.camera == 2)
        for (std::size_t m = 0; m < observation.segment.p0.size(); ++m) {
          observation.segment.m0[m] = observation.segment.m1[m] = Eigen::Vector2d(200, 0);
          observation.segment.p0[m].x() -= 200 * 1.5e-3;
          observation.segment.p1[m] = observation.segment.p0[m] + Eigen::Vector2d(200 * 0.01, 0);
        }
  PassOptions options;
  options.time_offsets = true;
  const PassResult adjusted =
      adjust_pass(perturbed_state(scene, instants, 0.005, 0.002), scene.wand, options, false);
  EXPECT_NEAR(adjusted.state.cameras[2].offset_s, 1.5e-3, 2e-5);
  EXPECT_EQ(adjusted.state.cameras[0].offset_s, 0.0);  // the reference clock
  EXPECT_LT(max_camera_error_m(scene, adjusted.state), 1e-5);
}

TEST(BundleAdjustment, TheWholeStageDropsOutliersAndConverges) {
  StageScene scene = ring_stage_scene(4, 200);
  auto instants = stage_instants(scene, 0.1);
  // Ten observations of camera 1 are reflections 40 px off.
  int moved = 0;
  for (auto& instant : instants)
    for (auto& observation : instant.observations)
      if (observation.camera == 1 && moved < 10 && instant.t_ns % 70'000'000 == 0) {
        for (auto& p : observation.segment.p0) p.x() += 40;
        observation.segment.p1 = observation.segment.p0;
        ++moved;
      }
  ASSERT_EQ(moved, 10);
  std::vector<CameraWandTrack> tracks(scene.cameras.size());
  SolveOptions options;
  std::vector<std::string> messages;
  const BundleAdjustmentResult result =
      bundle_adjust(perturbed_state(scene, instants, 0.01, 0.005), 0, scene.cameras, tracks, scene.wand,
                    options, [&](const std::string& message) { messages.push_back(message); });
  EXPECT_TRUE(result.converged) << result.convergence;
  EXPECT_EQ(result.refinement, IntrinsicsRefinement::kNone);
  EXPECT_EQ(result.intrinsics_refined_why, "");
  int inactive = 0;
  for (const auto& instant : result.state.instants)
    for (const auto& observation : instant.observations) inactive += observation.active ? 0 : 1;
  EXPECT_EQ(inactive, 10);
  EXPECT_LT(max_camera_error_m(scene, result.state), 0.002);
  ASSERT_GE(messages.size(), 3u);
  EXPECT_EQ(messages[1], "pass 2: 10 outlier observations removed");
  for (const auto& failure : result.failures) EXPECT_EQ(failure, "");
}

TEST(BundleAdjustment, AFocalLengthFarFromTheGivenFailsTheCamera) {
  StageScene scene = ring_stage_scene(4, 150);
  const auto instants = stage_instants(scene);
  BundleState start = perturbed_state(scene, instants, 0.0, 0.0);
  std::vector<CameraCalibration> given = scene.cameras;
  for (auto& camera : given) camera.intrinsics.fx = camera.intrinsics.fy = 2.5 * 800;  // wrong pixel pitch
  given[0].intrinsics.fx = given[0].intrinsics.fy = 800;
  for (std::size_t c = 1; c < start.cameras.size(); ++c)
    start.cameras[c].intrinsics[0] = start.cameras[c].intrinsics[1] = 800;
  SolveOptions options;
  options.refine_intrinsics = true;
  std::vector<CameraWandTrack> tracks(scene.cameras.size());
  const BundleAdjustmentResult result = bundle_adjust(start, 0, given, tracks, scene.wand, options);
  EXPECT_EQ(result.refinement, IntrinsicsRefinement::kAll);
  EXPECT_EQ(result.intrinsics_refined_why, "--refine-intrinsics");
  EXPECT_EQ(result.failures[0], "");
  for (std::size_t c = 1; c < 4; ++c) {
    EXPECT_NE(result.failures[c].find(
                  "focal length 800 x 800 px fits the data, the cameras file gives 2000 x 2000"),
              std::string::npos)
        << result.failures[c];
    EXPECT_FALSE(result.state.cameras[c].registered);
    EXPECT_TRUE(result.intrinsics_refined[c]);
  }
}

}  // namespace
}  // namespace panoptes::calib::testing
