// SPDX-License-Identifier: Apache-2.0
// Issue 17's tuning acceptance, at CI size: on deploy/scenes/tune4x.yaml (centroid noise 2 px, 4x
// the default measurement_noise_px) shortened to 6 s, the held-out-camera criterion — which needs
// no ground truth — picks settings whose ground-truth RMSE is within 5% of the best the
// ground-truth criterion finds, from the same 4x-off start. The full 20 s measurement is in
// docs/recording.md ("Filter tuning on a noisy scene").
#include <cstdio>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "panoptes/simulator.h"
#include "panoptes/tune/criteria.h"
#include "panoptes/tune/search.h"

namespace panoptes::tune {
namespace {

constexpr TimeNs kEpochNs = 1'700'000'000'000'000'000LL;

Scene short_scene(double duration_s) {
  const std::string path = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/tune4x.yaml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto at = yaml.find("duration: 20.0");
  EXPECT_NE(at, std::string::npos) << path;
  yaml.replace(at, 14, "duration: " + std::to_string(duration_s));
  return Scene::from_yaml_string(yaml, PANOPTES_SOURCE_DIR "/deploy/scenes", path);
}

TEST(TuneAcceptance, HeldOutCameraPickIsWithinFivePercentOfTheGroundTruthBest) {
  const Scene scene = short_scene(6.0);
  const TuneInput input = simulated_input(scene, kEpochNs);
  TruthCriterionOptions truth;
  truth.evaluation.epoch_ns = kEpochNs;
  SearchOptions search;
  search.parameters = {"measurement_noise_px", "process_noise"};
  search.grid_points = 5;
  search.golden_iterations = 3;
  const session::EstimatorConfig start;  // the defaults: measurement noise 4x too small

  const SearchResult held_out = coordinate_search(start, search, [&](const session::EstimatorConfig& config) {
    return CostResult{held_out_score(config, input, {}).cost, {}};
  });
  const SearchResult with_truth =
      coordinate_search(start, search, [&](const session::EstimatorConfig& config) {
        return CostResult{truth_score(config, input, scene, truth).cost, {}};
      });
  const TruthScore defaults = truth_score(start, input, scene, truth);
  const TruthScore picked = truth_score(held_out.best, input, scene, truth);
  const TruthScore best = truth_score(with_truth.best, input, scene, truth);
  std::printf("defaults: RMSE %.3f mm, %zu switches, coverage %.3f\n", defaults.rmse_mm, defaults.id_switches,
              defaults.coverage);
  std::printf(
      "held-out pick (q %.4g, sigma %.4g px, %zu evaluations): RMSE %.3f mm, %zu switches, coverage %.3f\n",
      held_out.best.tracker.process_noise, held_out.best.tracker.measurement_noise_px,
      held_out.samples.size(), picked.rmse_mm, picked.id_switches, picked.coverage);
  std::printf(
      "truth best (q %.4g, sigma %.4g px, %zu evaluations): RMSE %.3f mm, %zu switches, coverage %.3f\n",
      with_truth.best.tracker.process_noise, with_truth.best.tracker.measurement_noise_px,
      with_truth.samples.size(), best.rmse_mm, best.id_switches, best.coverage);

  EXPECT_LE(picked.rmse_mm, 1.05 * best.rmse_mm);
  EXPECT_GE(picked.coverage, best.coverage - 0.01);  // not bought by tracking less
  EXPECT_EQ(picked.id_switches, 0u);
  // The held-out criterion finds the simulated centroid noise (2 px) through NIS consistency ...
  EXPECT_NEAR(held_out.best.tracker.measurement_noise_px, 2.0, 0.4);
  // ... and the 4x-off defaults were really bad here (else the test would prove nothing).
  EXPECT_GT(defaults.cost, 3.0 * best.cost);
}

}  // namespace
}  // namespace panoptes::tune
