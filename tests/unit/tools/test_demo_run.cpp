// SPDX-License-Identifier: Apache-2.0
// panoptes_demo's library (tools/demo): the demo's targets and its summary JSON.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "panoptes/demo_run/demo_run.h"
#include "panoptes/errors.h"

namespace panoptes::demo_run {
namespace {

estimator::Evaluation meeting_targets() {
  estimator::Evaluation evaluation;
  evaluation.instants = 100;
  evaluation.worst_marker_rmse_m = 0.0019;
  evaluation.min_tracked_fraction = 0.95;
  evaluation.id_switch_count = 0;
  return evaluation;
}

TEST(DemoRun, TargetsMetAtTheBounds) {
  EXPECT_TRUE(targets_met(meeting_targets()));
}

TEST(DemoRun, EachTargetMissedFails) {
  estimator::Evaluation rmse = meeting_targets();
  rmse.worst_marker_rmse_m = 0.002;
  EXPECT_FALSE(targets_met(rmse));
  estimator::Evaluation tracked = meeting_targets();
  tracked.min_tracked_fraction = 0.949;
  EXPECT_FALSE(targets_met(tracked));
  estimator::Evaluation switches = meeting_targets();
  switches.id_switch_count = 1;
  EXPECT_FALSE(targets_met(switches));
  estimator::Evaluation nothing = meeting_targets();
  nothing.instants = 0;
  EXPECT_FALSE(targets_met(nothing));
}

TEST(DemoRun, SummaryJsonAddsTheRun) {
  estimator::Evaluation evaluation = meeting_targets();
  const auto json = nlohmann::json::parse(summary_json(evaluation, "deploy/scenes/demo.yaml", 12.5, 4));
  EXPECT_EQ(json.at("scene"), "deploy/scenes/demo.yaml");
  EXPECT_EQ(json.at("duration_s"), 12.5);
  EXPECT_EQ(json.at("cameras"), 4);
  EXPECT_EQ(json.at("targets_met"), true);
  evaluation.id_switch_count = 3;
  EXPECT_EQ(nlohmann::json::parse(summary_json(evaluation, "s", 1, 1)).at("targets_met"), false);
}

TEST(DemoRun, MissingSceneIsTheInputsFault) {
  DemoOptions options;
  options.scene_file = "/nonexistent/scene.yaml";
  EXPECT_THROW(run_demo(options), InputError);
}

}  // namespace
}  // namespace panoptes::demo_run
