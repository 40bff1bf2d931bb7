// SPDX-License-Identifier: Apache-2.0
// The deterministic search (docs/recording.md, "Tune the filter"): coordinate descent in log
// space. Each sweep takes the parameters in the order given; for each, a log-spaced grid of
// `grid_points` values over [x / span, x · span] (clamped to the parameter's limits) around the
// current value x, stepped on outwards while the best point is at an end of the grid (up to 40
// steps, never past the limits), then `golden_iterations` golden-section steps between the best grid point's
// neighbours; the best value seen is kept. Each later sweep searches √ of the previous span.
// Identical settings are evaluated once (a cache), so the result depends only on the input.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "panoptes/session/estimator_config.h"

namespace panoptes::tune {

struct SearchOptions {
  std::vector<std::string> parameters = {"measurement_noise_px", "process_noise", "gate_chi2"};
  double span = 8.0;  // first sweep: factor either side of the start value
  int grid_points = 7;
  int golden_iterations = 4;
  int sweeps = 3;
};

// One evaluation of the criterion.
struct SearchSample {
  std::size_t index = 0;
  int sweep = 0;
  std::string varied;          // the parameter being searched when it was evaluated
  std::vector<double> values;  // of SearchOptions::parameters, in order
  double cost = 0;
  std::vector<double> extras;  // criterion details (CostFunction's choice), for the curve file
};

struct CostResult {
  double cost = 0;
  std::vector<double> extras;
};
using CostFunction = std::function<CostResult(const session::EstimatorConfig&)>;
using SearchProgress = std::function<void(const SearchSample&, const SearchSample& best)>;

struct SearchResult {
  session::EstimatorConfig best;
  SearchSample best_sample;
  std::vector<SearchSample> samples;  // in evaluation order (cache hits not repeated)
};

// Throws ConfigError for an unknown parameter or a non-positive span / grid.
SearchResult coordinate_search(const session::EstimatorConfig& start, const SearchOptions& options,
                               const CostFunction& cost, const SearchProgress& progress = {});

}  // namespace panoptes::tune
