// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/search.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "panoptes/errors.h"
#include "panoptes/tune/tune_parameters.h"

namespace panoptes::tune {

namespace {

class Searcher {
 public:
  Searcher(const session::EstimatorConfig& start, const SearchOptions& options, const CostFunction& cost,
           const SearchProgress& progress)
      : options_(options), cost_(cost), progress_(progress) {
    result_.best = start;
    for (const auto& name : options_.parameters) current_.push_back(parameter_value(start, name));
  }

  SearchResult run() {
    evaluate(current_, 0, "start");
    double span = options_.span;
    for (int sweep = 0; sweep < options_.sweeps; ++sweep) {
      for (std::size_t p = 0; p < options_.parameters.size(); ++p) line_search(p, sweep, span);
      span = std::sqrt(span);
    }
    result_.best = configure(result_.best_sample.values);
    return std::move(result_);
  }

 private:
  session::EstimatorConfig configure(const std::vector<double>& values) const {
    session::EstimatorConfig config = result_.best;
    for (std::size_t p = 0; p < values.size(); ++p) set_parameter_value(config, options_.parameters[p], values[p]);
    return config;
  }

  // The cost at `values` (evaluated once; later calls hit the cache).
  double evaluate(const std::vector<double>& values, int sweep, const std::string& varied) {
    if (const auto hit = cache_.find(values); hit != cache_.end()) return hit->second;
    const CostResult cost = cost_(configure(values));
    SearchSample sample{result_.samples.size(), sweep, varied, values, cost.cost, cost.extras};
    if (result_.samples.empty() || sample.cost < result_.best_sample.cost) result_.best_sample = sample;
    result_.samples.push_back(sample);
    cache_[values] = cost.cost;
    if (progress_) progress_(sample, result_.best_sample);
    return cost.cost;
  }

  double cost_at_log(std::size_t p, double log_value, int sweep) {
    std::vector<double> values = current_;
    // Rounded to 6 significant digits: equal points of the grid and the golden section meet in
    // the cache, and the YAML written shows what was evaluated.
    const double value = std::exp(log_value);
    const double scale = std::pow(10.0, std::floor(std::log10(value)) - 5);
    values[p] = std::round(value / scale) * scale;
    return evaluate(values, sweep, options_.parameters[p]);
  }

  // Grid over [x / span, x · span] in log space, then golden section between the best grid point's
  // neighbours; current_[p] becomes the best value evaluated with the other parameters as they are.
  void line_search(std::size_t p, int sweep, double span) {
    const ParameterInfo& info = parameter_info(options_.parameters[p]);
    const double lo = std::max(std::log(current_[p] / span), std::log(info.lower));
    const double hi = std::min(std::log(current_[p] * span), std::log(info.upper));
    const int n = std::max(options_.grid_points, 2);
    std::vector<double> grid(n), costs(n);
    for (int i = 0; i < n; ++i) {
      grid[i] = lo + (hi - lo) * i / (n - 1);
      costs[i] = cost_at_log(p, grid[i], sweep);
    }
    const auto best = static_cast<int>(std::min_element(costs.begin(), costs.end()) - costs.begin());
    double a = grid[std::max(best - 1, 0)], b = grid[std::min(best + 1, n - 1)];
    const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
    double c = b - ratio * (b - a), d = a + ratio * (b - a);
    double fc = cost_at_log(p, c, sweep), fd = cost_at_log(p, d, sweep);
    for (int i = 1; i < options_.golden_iterations; ++i) {
      if (fc <= fd) {
        b = d, d = c, fd = fc;
        c = b - ratio * (b - a);
        fc = cost_at_log(p, c, sweep);
      } else {
        a = c, c = d, fc = fd;
        d = a + ratio * (b - a);
        fd = cost_at_log(p, d, sweep);
      }
    }
    // The best point of this line (the other parameters fixed) wherever it was found.
    double best_cost = std::numeric_limits<double>::infinity();
    for (const auto& sample : result_.samples) {
      bool on_line = true;
      for (std::size_t q = 0; q < current_.size(); ++q)
        if (q != p && sample.values[q] != current_[q]) on_line = false;
      if (on_line && sample.cost < best_cost) best_cost = sample.cost, best_value_ = sample.values[p];
    }
    current_[p] = best_value_;
  }

  SearchOptions options_;
  const CostFunction& cost_;
  const SearchProgress& progress_;
  std::vector<double> current_;
  double best_value_ = 0;
  std::map<std::vector<double>, double> cache_;
  SearchResult result_;
};

}  // namespace

SearchResult coordinate_search(const session::EstimatorConfig& start, const SearchOptions& options,
                               const CostFunction& cost, const SearchProgress& progress) {
  if (options.parameters.empty()) throw ConfigError("--params", "", "no parameter to search");
  if (!(options.span > 1.0)) throw ConfigError("--span", "", "must be > 1");
  if (options.grid_points < 2) throw ConfigError("--grid", "", "must be at least 2");
  if (options.sweeps < 1) throw ConfigError("--sweeps", "", "must be at least 1");
  for (const auto& name : options.parameters) {
    const ParameterInfo& info = parameter_info(name);
    const double value = parameter_value(start, name);
    if (!(value >= info.lower && value <= info.upper))
      throw ConfigError("start settings", "tracker." + name, "outside the search limits");
  }
  return Searcher(start, options, cost, progress).run();
}

}  // namespace panoptes::tune
