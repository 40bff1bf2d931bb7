// SPDX-License-Identifier: Apache-2.0
// Stage 1 of the wand solver on its own (two_view.h): relative poses of camera pairs from the wand's
// pixels, against the known poses of a synthetic scene.
#include <gtest/gtest.h>

#include "panoptes/calib/two_view.h"
#include "stage_scenes.h"

namespace panoptes::calib::testing {
namespace {

std::vector<WandPixelPair> common_pixels(const StageScene& scene, std::size_t a, std::size_t b,
                                         double noise_px = 0.0) {
  std::mt19937 rng(9);
  std::vector<WandPixelPair> common;
  for (std::size_t s = 0; s < scene.wand_markers.size(); ++s) {
    auto pa = stage_pixels(scene, a, s, noise_px, &rng), pb = stage_pixels(scene, b, s, noise_px, &rng);
    if (!pa.empty() && !pb.empty()) common.push_back({std::move(pa), std::move(pb)});
  }
  return common;
}

TEST(TwoView, RecoversAKnownRelativePoseAndItsMetricScale) {
  const StageScene scene = ring_stage_scene(4, 200);
  const auto common = common_pixels(scene, 0, 1);
  ASSERT_GE(common.size(), 100u);
  const TwoViewResult result = solve_two_view(scene.cameras[0].intrinsics, scene.cameras[1].intrinsics,
                                              common, scene.wand, TwoViewOptions{});
  ASSERT_TRUE(result.pose.has_value());
  const RelativePose truth = true_relative_pose(scene, 0, 1);
  EXPECT_LT(rotation_error_deg(result.pose->R_ab, truth.R_ab), 1e-3);
  // The baseline is in metres: the wand's known length gave the scale.
  EXPECT_NEAR((result.pose->c_b - truth.c_b).norm(), 0.0, 1e-4) << "baseline " << truth.c_b.norm() << " m";
  EXPECT_NEAR(result.scale, truth.c_b.norm(), 1e-4);  // metres per unit baseline
  EXPECT_LT(result.residual_px, 1e-3);
  EXPECT_EQ(result.samples, static_cast<int>(common.size()));
  EXPECT_EQ(result.inliers, static_cast<int>(common.size() * scene.wand.marker_count()));
  EXPECT_NEAR(result.score, result.residual_px + 0.01, 1e-12);  // >= 100 inliers: no penalty
}

TEST(TwoView, WithNoiseTheRelativePoseStaysWithinTolerance) {
  const StageScene scene = ring_stage_scene(4, 300);
  const auto common = common_pixels(scene, 1, 2, 0.2);
  const TwoViewResult result = solve_two_view(scene.cameras[1].intrinsics, scene.cameras[2].intrinsics,
                                              common, scene.wand, TwoViewOptions{});
  ASSERT_TRUE(result.pose.has_value());
  const RelativePose truth = true_relative_pose(scene, 1, 2);
  // The pose is the best RANSAC hypothesis (a minimal sample), not refined: the bundle adjustment
  // refines it. With 0.2 px noise it is within a few degrees and a few percent of the baseline.
  const double rotation_deg = rotation_error_deg(result.pose->R_ab, truth.R_ab);
  const double baseline_rel = (result.pose->c_b - truth.c_b).norm() / truth.c_b.norm();
  std::printf("  two-view with 0.2 px noise: rotation error %.3f deg, baseline error %.2f%%\n", rotation_deg,
              100 * baseline_rel);
  EXPECT_LT(rotation_deg, 3.0);
  EXPECT_LT(baseline_rel, 0.05);
  EXPECT_GT(result.residual_px, 0.05);  // the noise shows in the residual, ...
  EXPECT_LT(result.residual_px, 0.5);   // ... and not much more
}

TEST(TwoView, ASingleLightGivesTheDirectionOfTheBaselineOnly) {
  StageScene scene = ring_stage_scene(3, 300);
  scene.wand = WandDefinition{{0.0}};
  for (auto& markers : scene.wand_markers) markers.resize(1);
  const auto common = common_pixels(scene, 0, 2);
  const TwoViewResult result = solve_two_view(scene.cameras[0].intrinsics, scene.cameras[2].intrinsics,
                                              common, scene.wand, TwoViewOptions{});
  ASSERT_TRUE(result.pose.has_value());
  const RelativePose truth = true_relative_pose(scene, 0, 2);
  EXPECT_EQ(result.scale, 0.0);
  EXPECT_NEAR(result.pose->c_b.norm(), 1.0, 1e-9);
  EXPECT_LT((result.pose->c_b - truth.c_b.normalized()).norm(), 1e-4);
  EXPECT_LT(rotation_error_deg(result.pose->R_ab, truth.R_ab), 1e-3);
}

TEST(TwoView, TooFewCommonInstantsGiveNoPose) {
  const StageScene scene = ring_stage_scene(4, 200);
  auto common = common_pixels(scene, 0, 1);
  common.resize(24);
  const TwoViewResult result = solve_two_view(scene.cameras[0].intrinsics, scene.cameras[1].intrinsics,
                                              common, scene.wand, TwoViewOptions{});
  EXPECT_FALSE(result.pose.has_value());
  EXPECT_EQ(result.samples, 24);
  EXPECT_EQ(result.inliers, 0);
}

TEST(TwoView, UnrelatedPixelsGiveNoPose) {
  const StageScene scene = ring_stage_scene(4, 200);
  auto common = common_pixels(scene, 0, 1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> x(0, 1279), y(0, 1023);
  for (auto& pair : common)
    for (auto& pixel : pair.b) pixel = {x(rng), y(rng)};
  const TwoViewResult result = solve_two_view(scene.cameras[0].intrinsics, scene.cameras[1].intrinsics,
                                              common, scene.wand, TwoViewOptions{});
  EXPECT_FALSE(result.pose.has_value());
}

TEST(TwoView, PairwiseSolvesEveryPairWithCommonInstantsInOrder) {
  const StageScene scene = ring_stage_scene(4, 200);
  const auto instants = stage_instants(scene);
  int progress_calls = 0;
  const PairwiseResult result = pairwise_relative_poses(scene.cameras, instants, scene.wand, TwoViewOptions{},
                                                        [&](const std::string&) { ++progress_calls; });
  ASSERT_EQ(result.edges.size(), 6u);
  EXPECT_EQ(result.pairs_with_common, 6u);
  ASSERT_EQ(result.pairs.size(), 6u);
  EXPECT_EQ(progress_calls, 0);  // one call per ten pairs
  for (const auto& pair : result.pairs) {
    ASSERT_LT(pair.a, pair.b);
    const PairEdge& edge = result.edges[pair.edge_index];
    EXPECT_EQ(edge.camera_a, scene.cameras[pair.a].id);
    EXPECT_EQ(edge.camera_b, scene.cameras[pair.b].id);
    EXPECT_GT(edge.scale, 0.0);
    const RelativePose truth = true_relative_pose(scene, pair.a, pair.b);
    EXPECT_LT(rotation_error_deg(pair.pose.R_ab, truth.R_ab), 1e-3) << edge.camera_a << "-" << edge.camera_b;
    EXPECT_LT((pair.pose.c_b - truth.c_b).norm(), 1e-3) << edge.camera_a << "-" << edge.camera_b;
  }
  // Ascending (a, b): cam0-cam1, cam0-cam2, ..., cam2-cam3.
  EXPECT_EQ(result.edges.front().camera_b, "cam1");
  EXPECT_EQ(result.edges.back().camera_a, "cam2");
}

}  // namespace
}  // namespace panoptes::calib::testing
