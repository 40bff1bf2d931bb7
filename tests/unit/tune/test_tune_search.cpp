// SPDX-License-Identifier: Apache-2.0
// The tuner's search and parameters (estimator_node/tune): deterministic coordinate descent in log
// space finds a known minimum, evaluates each point once, stays within the limits; unknown
// settings are errors naming them.
#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "panoptes/errors.h"
#include "panoptes/tune/search.h"
#include "panoptes/tune/tune_parameters.h"

namespace panoptes::tune {
namespace {

// A bowl in log space with its minimum at process_noise 400, measurement_noise_px 2.
CostResult bowl(const session::EstimatorConfig& config) {
  const double a = std::log(config.tracker.process_noise / 400.0);
  const double b = std::log(config.tracker.measurement_noise_px / 2.0);
  return {a * a + 2.0 * b * b + 0.5 * a * b, {}};
}

TEST(TuneSearch, FindsTheMinimumOfALogSpaceBowlFromFourTimesOff) {
  SearchOptions options;
  options.parameters = {"process_noise", "measurement_noise_px"};
  options.sweeps = 3;
  session::EstimatorConfig start;  // 50 and 0.5: 8x and 4x off
  const SearchResult result = coordinate_search(start, options, bowl);
  EXPECT_NEAR(result.best.tracker.process_noise / 400.0, 1.0, 0.05);
  EXPECT_NEAR(result.best.tracker.measurement_noise_px / 2.0, 1.0, 0.05);
  EXPECT_EQ(result.best_sample.cost, bowl(result.best).cost);
  // Each point once (the cache), and the same run twice gives the same samples.
  std::set<std::vector<double>> seen;
  for (const auto& sample : result.samples) EXPECT_TRUE(seen.insert(sample.values).second);
  const SearchResult again = coordinate_search(start, options, bowl);
  ASSERT_EQ(again.samples.size(), result.samples.size());
  for (std::size_t i = 0; i < result.samples.size(); ++i)
    EXPECT_EQ(again.samples[i].values, result.samples[i].values);
}

TEST(TuneSearch, StaysWithinTheParameterLimits) {
  SearchOptions options;
  options.parameters = {"gate_chi2"};
  options.span = 1000;
  const auto& info = parameter_info("gate_chi2");
  // Cost falls forever towards small gates: the search must stop at the lower limit.
  const SearchResult result = coordinate_search(session::EstimatorConfig{}, options, [](const auto& config) {
    return CostResult{config.tracker.gate_chi2, {}};
  });
  for (const auto& sample : result.samples) {
    EXPECT_GE(sample.values[0], info.lower * (1 - 1e-9));
    EXPECT_LE(sample.values[0], info.upper * (1 + 1e-9));
  }
  EXPECT_NEAR(result.best.tracker.gate_chi2, info.lower, 1e-6);
}

TEST(TuneParameters, NamesMapToTheTrackerSettingsAndUnknownNamesAreErrors) {
  session::EstimatorConfig config;
  set_parameter_value(config, "init.epipolar_px", 3.5);
  EXPECT_EQ(config.tracker.init.epipolar_px, 3.5);
  EXPECT_EQ(parameter_value(config, "measurement_noise_px"), config.tracker.measurement_noise_px);
  try {
    set_parameter_value(config, "process_nosie", 1.0);
    FAIL() << "no error for an unknown name";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("process_nosie"), std::string::npos) << error.what();
  }
  SearchOptions bad;
  bad.span = 1.0;
  EXPECT_THROW(coordinate_search(config, bad, bowl), ConfigError);
}

}  // namespace
}  // namespace panoptes::tune
