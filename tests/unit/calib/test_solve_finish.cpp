// SPDX-License-Identifier: Apache-2.0
// Stage 4 of the wand solver on its own (solve_finish.h): statistics of a known solution, the wand
// measured against its known length, and the provisional world frame.
#include <gtest/gtest.h>

#include "panoptes/calib/solve_finish.h"
#include "stage_scenes.h"

namespace panoptes::calib::testing {
namespace {

// The true cameras and wand with every position scaled by `scale` about the origin: the images
// stay the same, the wand's measured length grows by `scale`.
BundleState scaled_truth(const StageScene& scene, const std::vector<WandInstant>& instants, double scale) {
  BundleState state;
  for (const auto& camera : scene.cameras) {
    RigidTransform T = *camera.T_world_cam;
    T.t *= scale;
    state.cameras.push_back(camera_parameters(camera.intrinsics, T));
  }
  state.instants = instants;
  for (const auto& instant : instants)
    for (const auto& X : scene.wand_markers[static_cast<std::size_t>(instant.t_ns / 10'000'000)]) {
      const Eigen::Vector3d p = scale * X;
      state.points.insert(state.points.end(), p.data(), p.data() + 3);
    }
  return state;
}

// Every camera's raw frames: its observations at the instants themselves.
std::vector<CameraWandTrack> frames_at_instants(const StageScene& scene,
                                                const std::vector<WandInstant>& instants) {
  std::vector<CameraWandTrack> tracks(scene.cameras.size());
  for (const auto& instant : instants)
    for (const auto& observation : instant.observations)
      tracks[static_cast<std::size_t>(observation.camera)].frames.push_back(
          {instant.t_ns, observation.segment.p0, 0});
  return tracks;
}

SolveResult partial_result(const StageScene& scene) {
  SolveResult partial;
  for (const auto& camera : scene.cameras) {
    CameraResult result;
    result.id = camera.id;
    partial.cameras.push_back(result);
  }
  return partial;
}

TEST(SolveFinish, AKnownSolutionHasNoErrorAndGetsAWorldFrameZUp) {
  const StageScene scene = ring_stage_scene(4, 120);
  const auto instants = stage_instants(scene);
  const auto tracks = frames_at_instants(scene, instants);
  const SolveResult result = finish_solution(partial_result(scene), scaled_truth(scene, instants, 1.0),
                                             scene.cameras, tracks, scene.wand);
  ASSERT_TRUE(result.ok()) << result.errors.front();
  EXPECT_EQ(result.calibrated_count(), 4);
  EXPECT_LT(result.rms_px, 1e-9);
  EXPECT_EQ(result.samples.size(), instants.size());
  std::size_t observations = 0;
  for (const auto& instant : instants) observations += instant.observations.size();
  EXPECT_EQ(result.residuals.size(), 3 * observations);
  EXPECT_EQ(result.raw_all.count, static_cast<int>(3 * observations));
  EXPECT_LT(result.raw_all.median_px, 1e-9);
  EXPECT_EQ(result.lengths.count, static_cast<int>(instants.size()));
  EXPECT_LT(std::abs(result.lengths.mean_error_mm), 1e-6);
  // The provisional frame moves the solution rigidly, with z along the truth's z (the cameras' plane
  // is level), the wand's lowest samples near z = 0 and the cameras above them.
  for (std::size_t a = 0; a < 4; ++a) {
    EXPECT_GT(result.cameras[a].T_world_cam->t.z(), 1.0);
    for (std::size_t b = a + 1; b < 4; ++b) {
      const Eigen::Vector3d estimated = result.cameras[a].T_world_cam->t - result.cameras[b].T_world_cam->t;
      const Eigen::Vector3d truth = scene.cameras[a].T_world_cam->t - scene.cameras[b].T_world_cam->t;
      EXPECT_NEAR(estimated.norm(), truth.norm(), 1e-9);
      EXPECT_NEAR(estimated.z(), truth.z(), 1e-9);
    }
  }
  double lowest = 1e9;
  for (const auto& sample : result.samples)
    for (const auto& p : sample.markers) lowest = std::min(lowest, p.z());
  EXPECT_LE(lowest, 0.0);
  EXPECT_GT(lowest, -0.3);
  for (const auto& camera : result.cameras) {
    EXPECT_LT(camera.rms_px, 1e-9);
    EXPECT_EQ(camera.intrinsics.fx, scene.cameras[0].intrinsics.fx);
  }
}

TEST(SolveFinish, TheFreeWandLengthShowsAScaleError) {
  const StageScene scene = ring_stage_scene(4, 120);
  const auto instants = stage_instants(scene);
  // 0.3% too large: the images are the same, the wand measures 1.5 mm long, each gap within 2 mm.
  const SolveResult result = finish_solution(partial_result(scene), scaled_truth(scene, instants, 1.003),
                                             scene.cameras, frames_at_instants(scene, instants), scene.wand);
  ASSERT_TRUE(result.ok());
  EXPECT_LT(result.rms_px, 1e-9);
  EXPECT_NEAR(result.lengths.mean_error_mm, 1.5, 1e-6);
  EXPECT_NEAR(result.lengths.max_abs_error_mm, 1.5, 1e-6);
  EXPECT_LT(result.lengths.sigma_mm, 1e-6);
}

TEST(SolveFinish, AWandThatDoesNotMatchItsDefinitionFailsEveryCamera) {
  const StageScene scene = ring_stage_scene(4, 120);
  const auto instants = stage_instants(scene);
  // 2% too large: the gap between markers 0 and 1 measures 3.6 mm more than --wand.
  const SolveResult result = finish_solution(partial_result(scene), scaled_truth(scene, instants, 1.02),
                                             scene.cameras, frames_at_instants(scene, instants), scene.wand);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.errors.front(),
            "wand lengths never match: markers 0-1 measure 0.1836 m, --wand says 0.18 m; cameras cam0, cam1, "
            "cam2, cam3 are not calibrated (check --wand and the wand itself)");
  EXPECT_EQ(result.calibrated_count(), 0);
  for (const auto& camera : result.cameras) EXPECT_EQ(camera.failure, "lengths never match --wand");
}

TEST(SolveFinish, InactiveObservationsAndUnregisteredCamerasAreLeftOut) {
  const StageScene scene = ring_stage_scene(4, 120);
  auto instants = stage_instants(scene);
  BundleState state = scaled_truth(scene, instants, 1.0);
  state.cameras[3].registered = false;
  std::size_t active = 0;  // in instants still seen by two cameras
  for (auto& instant : state.instants) {
    std::size_t seen = 0;
    for (auto& observation : instant.observations) {
      observation.active = observation.camera != 3;
      seen += observation.active ? 1 : 0;
    }
    active += seen >= 2 ? seen : 0;
  }
  const SolveResult result = finish_solution(partial_result(scene), state, scene.cameras,
                                             frames_at_instants(scene, instants), scene.wand);
  EXPECT_EQ(result.calibrated_count(), 3);
  EXPECT_FALSE(result.cameras[3].T_world_cam.has_value());
  EXPECT_EQ(result.cameras[3].observations, 0);
  EXPECT_EQ(result.residuals.size(), 3 * active);
  EXPECT_EQ(result.cameras[3].raw_all.count, 0);
}

}  // namespace
}  // namespace panoptes::calib::testing
