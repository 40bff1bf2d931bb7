// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/search.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "panoptes/errors.h"
#include "panoptes/tune/tune_parameters.h"

namespace panoptes::tune {

namespace {

constexpr int kMaxExtensions = 40;  // grid steps beyond the span when the minimum is at its end

class Searcher {
 public:
  Searcher(const session::EstimatorConfig& start, const SearchOptions& options, const CostFunction& cost,
           const SearchProgress& progress)
      : options_(options), cost_(cost), progress_(progress) {
    result_.best = start;
    for (const auto& name : options_.parameters) current_.push_back(parameter_value(start, name));
    start_ = current_;
  }

  SearchResult run() {
    evaluate(current_, 0, "start");
    double span = options_.span;
    for (int sweep = 0; sweep < options_.sweeps; ++sweep) {
      for (std::size_t p = 0; p < options_.parameters.size(); ++p) line_search(p, sweep, span);
      span = std::sqrt(span);
    }
    // The last line searches' point: as good as the best sample (each line search starts from
    // the previous point), and nearest the start among equals.
    result_.best_sample = result_.samples[cache_.at(current_).index];
    result_.best = configure(current_);
    return std::move(result_);
  }

 private:
  session::EstimatorConfig configure(const std::vector<double>& values) const {
    session::EstimatorConfig config = result_.best;
    for (std::size_t p = 0; p < values.size(); ++p)
      set_parameter_value(config, options_.parameters[p], values[p]);
    return config;
  }

  // The cost at `values` (evaluated once; later calls hit the cache).
  double evaluate(const std::vector<double>& values, int sweep, const std::string& varied) {
    if (const auto hit = cache_.find(values); hit != cache_.end()) return hit->second.cost;
    const CostResult cost = cost_(configure(values));
    SearchSample sample{result_.samples.size(), sweep, varied, values, cost.cost, cost.extras};
    if (result_.samples.empty() || sample.cost < result_.best_sample.cost) result_.best_sample = sample;
    result_.samples.push_back(sample);
    cache_[values] = {sample.index, cost.cost};
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
    const int points = std::max(options_.grid_points, 2);
    const double step = (hi - lo) / (points - 1);
    std::vector<double> grid, costs;
    for (int i = 0; i < points; ++i) {
      grid.push_back(lo + step * i);
      costs.push_back(cost_at_log(p, grid.back(), sweep));
    }
    // A minimum at an end of the grid is not bracketed: step on outwards (same step) until the
    // cost rises or the limit is reached.
    for (int extra = 0; extra < kMaxExtensions; ++extra) {
      const auto at = std::min_element(costs.begin(), costs.end()) - costs.begin();
      if (at == 0 && grid.front() - step >= std::log(info.lower) - 1e-12) {
        grid.insert(grid.begin(), grid.front() - step);
        costs.insert(costs.begin(), cost_at_log(p, grid.front(), sweep));
      } else if (at + 1 == static_cast<long>(grid.size()) &&
                 grid.back() + step <= std::log(info.upper) + 1e-12) {
        grid.push_back(grid.back() + step);
        costs.push_back(cost_at_log(p, grid.back(), sweep));
      } else {
        break;
      }
    }
    const int n = static_cast<int>(grid.size());
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
    // The best point of this line (the other parameters fixed) wherever it was found; among equal
    // costs (a flat criterion, e.g. a gate nothing reaches) the one nearest the start value.
    std::vector<const SearchSample*> line;
    for (const auto& sample : result_.samples) {
      bool on_line = true;
      for (std::size_t q = 0; q < current_.size(); ++q)
        if (q != p && sample.values[q] != current_[q]) on_line = false;
      if (on_line) line.push_back(&sample);
    }
    const double best_cost = (*std::min_element(line.begin(), line.end(), [](auto* a, auto* b) {
                               return a->cost < b->cost;
                             }))->cost;
    const double tie = 1e-9 * std::abs(best_cost) + 1e-12;
    double best_distance = std::numeric_limits<double>::infinity();
    for (const SearchSample* sample : line) {
      const double distance = std::abs(std::log(sample->values[p] / start_[p]));
      if (sample->cost <= best_cost + tie && distance < best_distance)
        best_distance = distance, current_[p] = sample->values[p];
    }
  }

  SearchOptions options_;
  const CostFunction& cost_;
  const SearchProgress& progress_;
  std::vector<double> start_;
  std::vector<double> current_;
  struct Cached {
    std::size_t index;
    double cost;
  };
  std::map<std::vector<double>, Cached> cache_;
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
