// SPDX-License-Identifier: Apache-2.0
// Stage 2 of the wand solver on its own (view_graph.h): known pairwise relative poses chained into
// one frame, the reference at the origin.
#include <gtest/gtest.h>

#include "panoptes/calib/view_graph.h"
#include "stage_scenes.h"

namespace panoptes::calib::testing {
namespace {

PairPose true_pair(const StageScene& scene, int a, int b, double score, std::size_t edge,
                   bool metric = true) {
  RelativePose pose = true_relative_pose(scene, static_cast<std::size_t>(a), static_cast<std::size_t>(b));
  if (!metric) pose.c_b.normalize();
  return {a, b, pose, score, edge};
}

ViewGraphInput input_for(const StageScene& scene) {
  ViewGraphInput input;
  for (const auto& camera : scene.cameras) input.camera_ids.push_back(camera.id);
  input.usable.assign(scene.cameras.size(), true);
  return input;
}

// T_world_cam of `c` in the frame of camera `reference`.
RigidTransform in_frame_of(const StageScene& scene, int reference, int c) {
  return scene.cameras[static_cast<std::size_t>(reference)].T_world_cam->inverse() *
         *scene.cameras[static_cast<std::size_t>(c)].T_world_cam;
}

TEST(ViewGraph, ChainsKnownPairwisePosesIntoOneFrame) {
  const StageScene scene = ring_stage_scene(5, 0);
  ViewGraphInput input = input_for(scene);
  // A chain 0-1-2-3-4 plus one chord; camera 2 has the most pairs and becomes the reference.
  input.pairs = {true_pair(scene, 0, 1, 0.1, 0), true_pair(scene, 1, 2, 0.1, 1),
                 true_pair(scene, 2, 3, 0.1, 2), true_pair(scene, 3, 4, 0.1, 3),
                 true_pair(scene, 0, 2, 0.2, 4)};
  const ViewGraphResult result = unify_view_graph(input);
  ASSERT_EQ(result.reference, 2);
  EXPECT_EQ(result.placed, 5);
  for (int c = 0; c < 5; ++c) {
    ASSERT_TRUE(result.T_world_cam[c].has_value()) << c << ": " << result.failures[c];
    EXPECT_EQ(result.failures[c], "");
    const RigidTransform truth = in_frame_of(scene, 2, c);
    EXPECT_LT((result.T_world_cam[c]->t - truth.t).norm(), 1e-9) << c;
    EXPECT_LT(truth.q.angularDistance(result.T_world_cam[c]->q), 1e-9) << c;
  }
  EXPECT_EQ(result.used_edges.size(), 5u);  // camera 0 is placed from both of its pairs
}

TEST(ViewGraph, PairsVoteByRankWhenTheyDisagree) {
  const StageScene scene = ring_stage_scene(3, 0);
  ViewGraphInput input = input_for(scene);
  input.reference_camera = "cam0";
  PairPose bad = true_pair(scene, 1, 2, 1.0, 2);
  bad.pose.c_b += Eigen::Vector3d(0.3, 0, 0);
  input.pairs = {true_pair(scene, 0, 1, 0.1, 0), true_pair(scene, 0, 2, 0.1, 1), bad};
  const ViewGraphResult result = unify_view_graph(input);
  ASSERT_EQ(result.reference, 0);
  ASSERT_TRUE(result.T_world_cam[2].has_value());
  // Camera 2 is placed from both its pairs, weighted 1/score^2: the bad one moves it by 1% of 0.3 m
  // (whichever of 1 and 2 goes second).
  const double moved = std::max((result.T_world_cam[1]->t - in_frame_of(scene, 0, 1).t).norm(),
                                (result.T_world_cam[2]->t - in_frame_of(scene, 0, 2).t).norm());
  EXPECT_GT(moved, 0.001);
  EXPECT_LT(moved, 0.004);
}

TEST(ViewGraph, ASingleLightPlacesByIntersectingRays) {
  const StageScene scene = ring_stage_scene(4, 0);
  ViewGraphInput input = input_for(scene);
  input.metric = false;
  input.reference_camera = "cam0";
  // Unit baselines: the first pair sets the scale; the others are placed where the rays from two
  // placed cameras cross.
  input.pairs = {true_pair(scene, 0, 1, 0.1, 0, false), true_pair(scene, 0, 2, 0.2, 1, false),
                 true_pair(scene, 1, 2, 0.2, 2, false), true_pair(scene, 0, 3, 0.2, 3, false),
                 true_pair(scene, 2, 3, 0.2, 4, false)};
  const ViewGraphResult result = unify_view_graph(input);
  ASSERT_EQ(result.placed, 4);
  const double unit = in_frame_of(scene, 0, 1).t.norm();
  for (int c = 1; c < 4; ++c) {
    ASSERT_TRUE(result.T_world_cam[c].has_value()) << c;
    EXPECT_LT((result.T_world_cam[c]->t * unit - in_frame_of(scene, 0, c).t).norm(), 1e-9) << c;
  }
}

TEST(ViewGraph, ASingleLightCameraWithOnePairIsNotPlaced) {
  const StageScene scene = ring_stage_scene(4, 0);
  ViewGraphInput input = input_for(scene);
  input.metric = false;
  input.reference_camera = "cam0";
  input.pairs = {true_pair(scene, 0, 1, 0.1, 0, false), true_pair(scene, 0, 2, 0.2, 1, false),
                 true_pair(scene, 1, 2, 0.2, 2, false), true_pair(scene, 2, 3, 0.2, 3, false)};
  const ViewGraphResult result = unify_view_graph(input);
  EXPECT_EQ(result.placed, 3);
  EXPECT_FALSE(result.T_world_cam[3].has_value());
  EXPECT_NE(result.failures[3].find("connected to only one calibrated camera"), std::string::npos)
      << result.failures[3];
}

TEST(ViewGraph, DisconnectedCamerasFailNamingBothGroups) {
  const StageScene scene = ring_stage_scene(5, 0);
  ViewGraphInput input = input_for(scene);
  input.usable[4] = false;  // failed before: neither placed nor reported here
  input.pairs = {true_pair(scene, 0, 1, 0.1, 0), true_pair(scene, 1, 2, 0.1, 1)};
  ViewGraphResult result = unify_view_graph(input);
  EXPECT_EQ(result.placed, 3);
  EXPECT_EQ(result.reference, 1);
  EXPECT_NE(result.failures[3].find("shares too few wand samples with any other camera (need 25"),
            std::string::npos)
      << result.failures[3];
  EXPECT_EQ(result.failures[4], "");
  EXPECT_FALSE(result.T_world_cam[4].has_value());

  input.pairs.push_back(true_pair(scene, 3, 4, 0.1, 2));
  input.usable[4] = true;
  result = unify_view_graph(input);
  EXPECT_EQ(result.failures[3],
            "disconnected view graph: {cam3, cam4} share no usable wand samples with {cam0, cam1, cam2}");
  EXPECT_EQ(result.failures[4], result.failures[3]);
}

TEST(ViewGraph, TheReferenceAskedForChoosesTheComponent) {
  const StageScene scene = ring_stage_scene(5, 0);
  ViewGraphInput input = input_for(scene);
  input.reference_camera = "cam4";
  input.pairs = {true_pair(scene, 0, 1, 0.1, 0), true_pair(scene, 1, 2, 0.1, 1),
                 true_pair(scene, 3, 4, 0.1, 2)};
  const ViewGraphResult result = unify_view_graph(input);
  EXPECT_EQ(result.reference, 4);
  EXPECT_EQ(result.placed, 2);
  ASSERT_TRUE(result.T_world_cam[3].has_value());
  EXPECT_LT((result.T_world_cam[3]->t - in_frame_of(scene, 4, 3).t).norm(), 1e-9);
  EXPECT_FALSE(result.T_world_cam[0].has_value());
}

TEST(ViewGraph, NoUsableCameraNoReference) {
  const StageScene scene = ring_stage_scene(2, 0);
  ViewGraphInput input = input_for(scene);
  input.usable = {false, false};
  const ViewGraphResult result = unify_view_graph(input);
  EXPECT_EQ(result.reference, -1);
  EXPECT_EQ(result.placed, 0);
}

}  // namespace
}  // namespace panoptes::calib::testing
