// SPDX-License-Identifier: Apache-2.0
// The incremental metric the optimiser uses gives the quality that evaluate() gives, for every
// resolution model and norm, and the tracker objective that predict_tracking() gives, through
// places, removals and undos of single cameras.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "panoptes/planner/incremental_metric.h"
#include "panoptes/planner/optimizer.h"

namespace panoptes::planner {
namespace {

Room studio() {
  Room room;
  room.volume = {Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(2, 2, 2)};
  room.obstacles.push_back({Eigen::Vector3d(0.3, 0.3, 0), Eigen::Vector3d(0.6, 0.6, 1.5)});
  room.mounts.push_back(
      {"north", Eigen::Vector3d(-3, 3, 2.2), Eigen::Vector3d(6, 0, 0), Eigen::Vector3d(0, 0, 0.7)});
  room.mounts.push_back(
      {"south", Eigen::Vector3d(-3, -3, 2.2), Eigen::Vector3d(6, 0, 0), Eigen::Vector3d(0, 0, 0.7)});
  room.mounts.push_back(
      {"truss", Eigen::Vector3d(-2, 0, 2.9), Eigen::Vector3d(4, 0, 0), Eigen::Vector3d::Zero()});
  Lens wide;
  wide.name = "wide";
  wide.intrinsics.width = 1280;
  wide.intrinsics.height = 1024;
  wide.intrinsics.fx = wide.intrinsics.fy = 850;
  wide.intrinsics.cx = 639.5;
  wide.intrinsics.cy = 511.5;
  Lens narrow = wide;
  narrow.name = "narrow";
  narrow.intrinsics.fx = narrow.intrinsics.fy = 1500;
  narrow.max_depth_m = 5.0;  // some points beyond its depth range
  room.lenses = {wide, narrow};
  return room;
}

// Random places, removals and undos of single cameras in 5 slots; after each, the incremental
// value must equal `expected` (a full evaluation of the cameras in the slots) to 1e-9 relative.
template <typename FullEvaluation>
void check_through_moves_and_undos(const Room& room, IncrementalMetric& incremental,
                                   const FullEvaluation& full_evaluation) {
  std::vector<std::optional<PlannedCamera>> slots(incremental.slots());
  const auto expected = [&] {
    std::vector<PlannedCamera> cameras;
    for (const auto& camera : slots)
      if (camera) cameras.push_back(*camera);
    return full_evaluation(cameras);
  };
  EXPECT_NEAR(incremental.value(), expected(), 1e-9 * expected());  // no camera at all

  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int undone = 0, removed = 0;
  for (int step = 0; step < 40; ++step) {
    const std::size_t slot = rng() % slots.size();
    const double action = uniform(rng);
    if (action < 0.15 && slots[slot]) {
      slots[slot].reset();
      const double q = incremental.remove(slot);
      EXPECT_NEAR(q, expected(), 1e-9 * q) << "after removing slot " << slot;
      ++removed;
      continue;
    }
    std::array<double, kGenes> genes{};
    for (double& g : genes) g = uniform(rng);
    const PlannedCamera camera =
        decode_camera(room, genes.data(), std::string("c").append(std::to_string(slot)));
    const std::optional<PlannedCamera> before = slots[slot];
    const double q = incremental.place(slot, camera);
    slots[slot] = camera;
    ASSERT_NEAR(q, expected(), 1e-9 * q) << "after placing slot " << slot << " at step " << step;
    if (action > 0.6) {
      incremental.undo();
      slots[slot] = before;
      ASSERT_NEAR(incremental.value(), expected(), 1e-9 * q) << "after undoing slot " << slot;
      ++undone;
    }
  }
  EXPECT_GT(undone, 5);
  EXPECT_GT(removed, 0);
}

using Case = std::tuple<ResolutionModel, Norm, Norm, int>;  // model, over directions, over planes, planes

class IncrementalMetricMatches : public ::testing::TestWithParam<Case> {};

TEST_P(IncrementalMetricMatches, EvaluateThroughMovesAndUndos) {
  const auto [model, directions, planes_norm, planes] = GetParam();
  const Room room = studio();
  // 70 planes: two words of plane flags, the second partly used.
  const SampleSet samples = draw_samples(room, {planes}, 120, 12, 3);
  MetricOptions metric;
  metric.resolution = model;
  metric.over_directions = directions;
  metric.over_planes = planes_norm;
  metric.min_triangulation_deg = 15.0;
  IncrementalMetric incremental(samples, room.obstacles, metric, 5);
  check_through_moves_and_undos(room, incremental, [&](const std::vector<PlannedCamera>& cameras) {
    return evaluate(cameras, samples, room.obstacles, metric).quality;
  });
}

// The tracker objective (predicted tracker RMSE with gaps charged) against predict_tracking, for
// 64 planes, 70 (two words of flags) and none; the resolution model and norms of q do not enter it.
class IncrementalTrackerObjectiveMatches : public ::testing::TestWithParam<int> {};

TEST_P(IncrementalTrackerObjectiveMatches, PredictTrackingThroughMovesAndUndos) {
  const Room room = studio();
  const SampleSet samples = draw_samples(room, {GetParam()}, 120, 12, 3);
  MetricOptions metric;
  metric.min_triangulation_deg = 15.0;
  metric.resolution = ResolutionModel::kPyramid;  // q's choices: no effect on the tracker objective
  metric.over_planes = Norm::kMax;
  TrackerModel tracker;
  tracker.subject_markers = 41;
  tracker.one_view_episode_s = 0.2;
  IncrementalMetric incremental(samples, room.obstacles, metric, 5, Objective::kTrackerRmse, tracker);
  EXPECT_EQ(incremental.objective(), Objective::kTrackerRmse);
  check_through_moves_and_undos(room, incremental, [&](const std::vector<PlannedCamera>& cameras) {
    const double full =
        predict_tracking(cameras, samples, room.obstacles, metric, tracker).rmse_gaps_charged_m;
    EXPECT_DOUBLE_EQ(
        full, objective_value(cameras, samples, room.obstacles, metric, Objective::kTrackerRmse, tracker));
    return full;
  });
}

INSTANTIATE_TEST_SUITE_P(Planes, IncrementalTrackerObjectiveMatches, ::testing::Values(64, 70, 0));

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const auto name = [](Norm norm) {
    return norm == Norm::kRms ? "Rms" : norm == Norm::kMax ? "Max" : "Mean";
  };
  return std::string(std::get<0>(info.param) == ResolutionModel::kPyramid ? "Pyramid" : "Covariance") +
         name(std::get<1>(info.param)) + name(std::get<2>(info.param)) +
         std::to_string(std::get<3>(info.param)) + "Planes";
}

INSTANTIATE_TEST_SUITE_P(ModelsAndNorms, IncrementalMetricMatches,
                         ::testing::Values(Case{ResolutionModel::kCovariance, Norm::kRms, Norm::kRms, 64},
                                           Case{ResolutionModel::kCovariance, Norm::kRms, Norm::kMax, 70},
                                           Case{ResolutionModel::kCovariance, Norm::kMax, Norm::kMean, 16},
                                           Case{ResolutionModel::kCovariance, Norm::kMean, Norm::kRms, 0},
                                           Case{ResolutionModel::kPyramid, Norm::kRms, Norm::kRms, 64},
                                           Case{ResolutionModel::kPyramid, Norm::kMax, Norm::kMean, 0}),
                         case_name);

TEST(IncrementalMetric, RefusesMoreThan64Cameras) {
  const Room room = studio();
  const SampleSet samples = draw_samples(room, {4}, 10, 4, 1);
  EXPECT_THROW(IncrementalMetric(samples, {}, {}, 65), std::invalid_argument);
  EXPECT_THROW(IncrementalMetric(samples, {}, {}, 0), std::invalid_argument);
  IncrementalMetric metric(samples, {}, {}, 2);
  EXPECT_THROW(metric.remove(2), std::out_of_range);
}

}  // namespace
}  // namespace panoptes::planner
