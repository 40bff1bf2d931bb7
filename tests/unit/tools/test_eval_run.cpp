// SPDX-License-Identifier: Apache-2.0
// panoptes_eval's library (tools/eval): which --require-* requirements an evaluation fails.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/eval_run/eval_run.h"

namespace panoptes::eval_run {
namespace {

estimator::Evaluation good_tracks() {
  estimator::Evaluation evaluation;
  evaluation.instants = 1000;
  evaluation.worst_marker_rmse_m = 0.0012;
  evaluation.min_tracked_fraction = 0.99;
  evaluation.trackable = 100;
  evaluation.tracked_trackable = 98;
  evaluation.records = 100;
  evaluation.false_records = 1;
  return evaluation;
}

TEST(EvalRun, NoRequirementOnlyNeedsInstants) {
  EXPECT_TRUE(track_failures(good_tracks(), EvalOptions{}).empty());
  estimator::Evaluation empty;
  EXPECT_EQ(track_failures(empty, EvalOptions{}), std::vector<std::string>{"no track records to judge"});
}

TEST(EvalRun, TrackRequirementsMetAndNot) {
  EvalOptions options;
  options.require_rmse_mm = 2.0;
  options.require_tracked = 0.95;
  options.require_coverage = 0.95;
  options.require_no_switches = true;
  options.require_max_false_fraction = 0.05;
  EXPECT_TRUE(track_failures(good_tracks(), options).empty());

  estimator::Evaluation bad = good_tracks();
  bad.worst_marker_rmse_m = 0.002;  // the bound is strict
  bad.min_tracked_fraction = 0.5;
  bad.id_switch_count = 2;
  const std::vector<std::string> failures = track_failures(bad, options);
  ASSERT_EQ(failures.size(), 3u);
  EXPECT_EQ(failures[0], "worst marker RMSE " + std::to_string(2.0) + " mm");
  EXPECT_EQ(failures[1], "min tracked fraction " + std::to_string(0.5));
  EXPECT_EQ(failures[2], "2 ID switches");
}

TEST(EvalRun, MaxSwitchesAllowsUpToTheBound) {
  EvalOptions options;
  options.require_max_switches = 2;
  estimator::Evaluation evaluation = good_tracks();
  evaluation.id_switch_count = 2;
  EXPECT_TRUE(track_failures(evaluation, options).empty());
  evaluation.id_switch_count = 3;
  EXPECT_EQ(track_failures(evaluation, options), std::vector<std::string>{"3 ID switches"});
}

TEST(EvalRun, PoseRequirementsNameTheBody) {
  estimator::PoseEvaluation evaluation;
  estimator::BodyEvaluation wand;
  wand.body = "wand";
  wand.rmse_m = 0.004;
  wand.rmse_deg = 0.5;
  wand.tracked_fraction = 0.99;
  wand.wrong = 1;
  evaluation.bodies.push_back(wand);
  EvalOptions options;
  EXPECT_TRUE(pose_failures(evaluation, options).empty());
  options.require_pose_rmse_mm = 3;
  options.require_pose_rmse_deg = 1;
  options.require_pose_tracked = 0.9;
  options.require_no_wrong_poses = true;
  EXPECT_EQ(pose_failures(evaluation, options),
            (std::vector<std::string>{"wand RMSE " + std::to_string(4.0) + " mm", "wand 1 wrong poses"}));
}

TEST(EvalRun, JoinFailures) {
  EXPECT_EQ(join_failures({}), "");
  EXPECT_EQ(join_failures({"a"}), "a");
  EXPECT_EQ(join_failures({"a", "b c"}), "a; b c");
}

}  // namespace
}  // namespace panoptes::eval_run
