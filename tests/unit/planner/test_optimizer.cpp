// SPDX-License-Identifier: Apache-2.0
// The optimiser: seed 003 §4.5's three ceiling cameras over a square floor, determinism, budgets,
// adding to an existing rig, removal costs and infeasible plans.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "panoptes/planner/optimizer.h"

namespace panoptes::planner {
namespace {

Lens ceiling_lens() {
  Lens lens;
  lens.name = "wide";
  lens.intrinsics.width = 1280;
  lens.intrinsics.height = 1024;
  lens.intrinsics.fx = lens.intrinsics.fy = 640.0 / std::tan(35.0 * std::numbers::pi / 180.0);  // 70° across
  lens.intrinsics.cx = 639.5;
  lens.intrinsics.cy = 511.5;
  lens.min_depth_m = 0.3;
  lens.max_depth_m = 15.0;
  return lens;
}

// A 4 × 4 m floor (markers within 5 cm of it) under a 10 × 10 m ceiling at 3 m.
Room floor_room() {
  Room room;
  room.volume = {Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(2, 2, 0.05)};
  room.mounts.push_back(
      {"ceiling", Eigen::Vector3d(-5, -5, 3), Eigen::Vector3d(10, 0, 0), Eigen::Vector3d(0, 10, 0)});
  room.lenses.push_back(ceiling_lens());
  return room;
}

// Fraction of the floor seen by all of `cameras` (no dynamic occluder).
double seen_by_all(const std::vector<PlannedCamera>& cameras, const Room& room) {
  const SampleSet samples = draw_samples(room, {0}, 800, 16, 99);
  return evaluate(cameras, samples, {}, {}).visible_histogram.back();
}

double mean_distance_from_centre(const std::vector<PlannedCamera>& cameras) {
  double sum = 0;
  for (const auto& camera : cameras) sum += camera.model.center_world().head<2>().norm();
  return sum / static_cast<double>(cameras.size());
}

// §4.5, Fig. 4.16: resolution only puts cameras close, covering parts of the floor; with the
// occlusion-weighted metric they back off so that every camera sees the whole floor.
class CeilingExample : public ::testing::TestWithParam<ResolutionModel> {};

TEST_P(CeilingExample, ThreeCeilingCamerasBackOffUnderOcclusion) {
  const Room room = floor_room();
  PlanOptions options;
  options.cameras = 3;
  options.evaluations = 2500;
  options.seed = 5;
  MetricOptions metric;
  metric.pixel_sigma = 0.3;
  metric.resolution = GetParam();

  const SampleSet plain = draw_samples(room, {0}, 300, 32, 1);
  const PlanResult resolution = plan(room, plain, metric, options);
  const SampleSet occluded = draw_samples(room, {48}, 300, 32, 1);
  const PlanResult occlusion = plan(room, occluded, metric, options);

  const double all_res = seen_by_all(resolution.cameras, room),
               all_occ = seen_by_all(occlusion.cameras, room);
  std::printf(
      "resolution only: q %.5f m, floor seen by all 3: %.3f, mean distance from centre %.2f m (%d "
      "evaluations)\n",
      resolution.evaluation.quality, all_res, mean_distance_from_centre(resolution.cameras),
      resolution.evaluations);
  std::printf(
      "with occlusion:  q %.5f m, floor seen by all 3: %.3f, mean distance from centre %.2f m (%d "
      "evaluations)\n",
      occlusion.evaluation.quality, all_occ, mean_distance_from_centre(occlusion.cameras),
      occlusion.evaluations);
  for (const auto* result : {&resolution, &occlusion})
    for (const auto& camera : result->cameras) {
      const Eigen::Vector3d c = camera.model.center_world();
      std::printf("  camera at (%.2f, %.2f, %.2f)\n", c.x(), c.y(), c.z());
    }
  EXPECT_GE(all_occ, 0.95);
  EXPECT_GT(mean_distance_from_centre(occlusion.cameras),
            mean_distance_from_centre(resolution.cameras) + 1.0);
  if (GetParam() == ResolutionModel::kPyramid) {
    // The seed's resolution-only layout: cameras close to the floor, each covering a part.
    EXPECT_LT(all_res, all_occ - 0.1);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CeilingExample,
                         ::testing::Values(ResolutionModel::kPyramid, ResolutionModel::kCovariance),
                         [](const auto& info) {
                           return info.param == ResolutionModel::kPyramid ? "Pyramid" : "Covariance";
                         });

TEST(Optimizer, SameSeedSamePlanAndHistoryImproves) {
  const Room room = floor_room();
  const SampleSet samples = draw_samples(room, {16}, 100, 16, 2);
  PlanOptions options;
  options.cameras = 2;
  options.evaluations = 600;
  const PlanResult a = plan(room, samples, {}, options);
  const PlanResult b = plan(room, samples, {}, options);
  ASSERT_EQ(a.cameras.size(), 2U);
  EXPECT_EQ(a.evaluation.quality, b.evaluation.quality);
  EXPECT_TRUE(a.cameras[1].model.center_world().isApprox(b.cameras[1].model.center_world()));
  EXPECT_FALSE(a.stopped_by_time);
  EXPECT_LE(a.evaluations, options.evaluations);
  ASSERT_GE(a.history.size(), 2U);
  EXPECT_LE(a.history.back(), a.history.front());
  for (std::size_t i = 1; i < a.history.size(); ++i) EXPECT_LE(a.history[i], a.history[i - 1]);
}

TEST(Optimizer, AddsToAnExistingRigAndRanksRemovals) {
  const Room room = floor_room();
  const SampleSet samples = draw_samples(room, {32}, 150, 16, 3);
  PlanOptions options;
  options.cameras = 1;
  options.evaluations = 400;
  options.fixed.push_back(make_camera("old0", room.lenses[0], {-3, -3, 3}, {0, 0, 0}));
  options.fixed.push_back(make_camera("old1", room.lenses[0], {3, -3, 3}, {0, 0, 0}));
  const PlanResult result = plan(room, samples, {}, options);
  ASSERT_EQ(result.cameras.size(), 3U);
  EXPECT_EQ(result.cameras[0].id, "old0");
  EXPECT_EQ(result.cameras[2].id, "plan2");
  const double before = evaluate(options.fixed, samples, {}, {}).quality;
  EXPECT_LT(result.evaluation.quality, before);
  // Removing any camera costs quality; the placed camera is not the cheapest to lose if it was
  // placed well, but every removal is at least as bad as the full rig.
  const auto costs = removal_costs(result.cameras, samples, {}, {});
  ASSERT_EQ(costs.size(), 3U);
  for (const double cost : costs) EXPECT_GE(cost, result.evaluation.quality);
}

// The validation room of deploy/planner/walk_room.yaml: a walking subject in an 8 × 6 m room,
// cameras on the walls between 2.0 and 2.8 m, markers facing mostly sideways.
Room walk_room() {
  Room room;
  room.volume = {Eigen::Vector3d(-1.6, -0.45, 0.0), Eigen::Vector3d(1.8, 0.45, 1.6)};
  const Eigen::Vector3d up(0, 0, 0.8);
  room.mounts = {{"north", {-4, 3, 2}, {8, 0, 0}, up},
                 {"south", {-4, -3, 2}, {8, 0, 0}, up},
                 {"east", {4, -3, 2}, {0, 6, 0}, up},
                 {"west", {-4, -3, 2}, {0, 6, 0}, up}};
  room.lenses = {{"f1000", CameraIntrinsics{1280, 1024, 1000.0, 1000.0, 639.5, 511.5, {}}, 0.3, 12.0}};
  return room;
}

// q prices mostly the share of a point's planes that fewer than two cameras see; the tracker
// objective prices the triangulation error of the rest as well. On the walking room they prefer
// different layouts of 4 cameras, and the search with each objective finds the layout its own
// objective prefers: each plan is better than the other on its own objective and worse on the other.
TEST(Optimizer, QualityAndTrackerRmsePickTheirOwnLayouts) {
  const Room room = walk_room();
  const OccluderModel body{.planes = 64, .max_angle_deg = 135, .min_angle_deg = 45, .facing_angle_deg = 100};
  const SampleSet samples = draw_samples(room, body, 300, 16, 1);
  const MetricOptions metric;
  TrackerModel tracker;
  tracker.subject_markers = 41;
  PlanOptions options;
  options.cameras = 4;
  options.evaluations = 2000;
  options.tracker = tracker;
  options.objective = Objective::kQuality;
  const PlanResult by_q = plan(room, samples, metric, options);
  options.objective = Objective::kTrackerRmse;
  const PlanResult by_rmse = plan(room, samples, metric, options);
  const auto value = [&](const PlanResult& result, Objective objective) {
    return objective_value(result.cameras, samples, room.obstacles, metric, objective, tracker);
  };
  const double q_of_q = value(by_q, Objective::kQuality), q_of_rmse = value(by_rmse, Objective::kQuality);
  const double rmse_of_q = value(by_q, Objective::kTrackerRmse);
  const double rmse_of_rmse = value(by_rmse, Objective::kTrackerRmse);
  std::printf("q plan: q %.5f m, tracker_rmse %.4f mm; tracker_rmse plan: q %.5f m, tracker_rmse %.4f mm\n",
              q_of_q, 1000 * rmse_of_q, q_of_rmse, 1000 * rmse_of_rmse);
  EXPECT_DOUBLE_EQ(by_q.objective_value, q_of_q);
  EXPECT_DOUBLE_EQ(by_rmse.objective_value, rmse_of_rmse);
  EXPECT_LT(q_of_q, 0.95 * q_of_rmse);
  EXPECT_LT(rmse_of_rmse, 0.95 * rmse_of_q);
}

TEST(Optimizer, InfeasiblePlansNameTheConstraint) {
  Room room = floor_room();
  const SampleSet samples = draw_samples(room, {8}, 50, 8, 4);
  PlanOptions options;
  options.cameras = 2;
  options.evaluations = 100;
  Room no_mounts = room;
  no_mounts.mounts.clear();
  try {
    plan(no_mounts, samples, {}, options);
    FAIL() << "no mounts accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no mounting surface"), std::string::npos) << e.what();
  }
  // A lens that cannot reach the floor from the ceiling.
  Room short_sighted = room;
  short_sighted.lenses[0].max_depth_m = 1.0;
  try {
    plan(short_sighted, samples, {}, options);
    FAIL() << "an unreachable volume accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("see any point"), std::string::npos) << e.what();
  }
}

// A lens of `fov_deg` across a 1280 × 1024 sensor.
Lens lens_with_fov(const std::string& name, double fov_deg) {
  Lens lens = ceiling_lens();
  lens.name = name;
  lens.intrinsics.fx = lens.intrinsics.fy = 640.0 / std::tan(fov_deg / 2 * std::numbers::pi / 180.0);
  return lens;
}

// Lens choice (issue 19 item 2): the optimiser picks per camera from the room's lenses. A camera
// 2.5 m above a 4 × 4 m floor needs a wide lens to see all of it; a 0.4 m cube 8 m away is seen
// whole by either lens, and the long lens resolves it 4× better. The plan must pick the right one
// in both rooms, from a list in which the right lens is not the first.
TEST(Optimizer, PicksTheLensTheVolumeNeeds) {
  const Lens wide = lens_with_fov("wide", 100.0), tele = lens_with_fov("tele", 28.0);
  PlanOptions options;
  options.cameras = 2;
  options.evaluations = 800;
  options.seed = 11;

  Room low_ceiling = floor_room();
  low_ceiling.mounts[0].corner.z() = 2.5;
  low_ceiling.lenses = {tele, wide};
  const SampleSet floor = draw_samples(low_ceiling, {16}, 150, 16, 5);
  const PlanResult near = plan(low_ceiling, floor, {}, options);

  Room far_target;
  far_target.volume = {Eigen::Vector3d(-0.2, -0.2, 0.8), Eigen::Vector3d(0.2, 0.2, 1.2)};
  far_target.mounts.push_back(
      {"wall", Eigen::Vector3d(-4, -8, 0.5), Eigen::Vector3d(8, 0, 0), Eigen::Vector3d(0, 0, 2)});
  far_target.lenses = {wide, tele};
  const SampleSet target = draw_samples(far_target, {16}, 150, 16, 6);
  const PlanResult far = plan(far_target, target, {}, options);

  for (const auto* result : {&near, &far})
    for (const auto& camera : result->cameras)
      std::printf("  %s: %s lens\n", camera.id.c_str(), camera.lens.c_str());
  for (const auto& camera : near.cameras) EXPECT_EQ(camera.lens, "wide");
  for (const auto& camera : far.cameras) EXPECT_EQ(camera.lens, "tele");
  // The choice matters: the same layouts with the other lens are worse.
  auto with_lens = [](std::vector<PlannedCamera> cameras, const Lens& lens) {
    for (auto& camera : cameras)
      camera = make_camera(camera.id, lens, camera.model.center_world(),
                           camera.model.center_world() + camera.model.T_world_cam().rotation().col(2));
    return cameras;
  };
  EXPECT_LT(near.evaluation.quality, evaluate(with_lens(near.cameras, tele), floor, {}, {}).quality);
  EXPECT_LT(far.evaluation.quality, evaluate(with_lens(far.cameras, wide), target, {}, {}).quality);
}

TEST(Metric, StaticObstacleHidesWhatIsBehindIt) {
  Room room = floor_room();
  const auto camera = make_camera("c", room.lenses[0], {0, 0, 3}, {0, 0, 0});
  SampleSet samples;
  samples.points = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1.5, 0, 0)};
  samples.weights = {0.5, 0.5};
  const std::vector<Box> pillar = {{Eigen::Vector3d(-0.2, -0.2, 0.5), Eigen::Vector3d(0.2, 0.2, 1.0)}};
  const std::vector<PlannedCamera> cameras = {camera};
  MetricOptions metric;
  metric.k_cameras = 1;
  const Evaluation e = evaluate(cameras, samples, pillar, metric);
  EXPECT_EQ(e.point_p_k[0], 0.0);  // under the pillar
  EXPECT_EQ(e.point_p_k[1], 1.0);
  EXPECT_TRUE(pillar[0].blocks({0, 0, 0}, {0, 0, 3}));
  EXPECT_FALSE(pillar[0].blocks({1.5, 0, 0}, {0, 0, 3}));
  EXPECT_FALSE(pillar[0].blocks({0, 0, 0}, {0, 0, 0.5}));  // ends on its face
}

TEST(Metric, OccluderCapRestrictsNormals) {
  Room room = floor_room();
  const SampleSet samples = draw_samples(room, {200, Eigen::Vector3d::UnitZ(), 60.0}, 10, 8, 7);
  for (const auto& n : samples.normals) {
    EXPECT_NEAR(n.norm(), 1.0, 1e-12);
    EXPECT_GE(n.z(), std::cos(60.0 * std::numbers::pi / 180.0) - 1e-12);
  }
}

}  // namespace
}  // namespace panoptes::planner
