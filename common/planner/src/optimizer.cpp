// SPDX-License-Identifier: Apache-2.0
#include "panoptes/planner/optimizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

namespace panoptes::planner {

namespace {

using Clock = std::chrono::steady_clock;

std::size_t pick_index(double gene, std::size_t count) {
  return std::min(count - 1, static_cast<std::size_t>(std::max(0.0, gene) * static_cast<double>(count)));
}

class Search {
 public:
  Search(const Room& room, const SampleSet& samples, const MetricOptions& metric, const PlanOptions& options)
      : room_(room), samples_(samples), metric_(metric), options_(options), begin_(Clock::now()) {
    // The search's figure is the quality alone; the histogram etc. are recomputed at the end.
    dimensions_ = static_cast<std::size_t>(options.cameras) * kGenes;
  }

  double score(const std::vector<double>& genes) {
    ++evaluations_;
    std::vector<PlannedCamera> cameras = options_.fixed;
    for (int c = 0; c < options_.cameras; ++c)
      cameras.push_back(decode_camera(room_, genes.data() + static_cast<std::ptrdiff_t>(c) * kGenes, ""));
    const double q = evaluate(cameras, samples_, room_.obstacles, metric_).quality;
    if (q < best_) {
      best_ = q;
      best_genes_ = genes;
    }
    if (options_.progress && evaluations_ % std::max(1, options_.evaluations / 50) == 0)
      options_.progress({evaluations_, start_, best_, seconds()});
    return q;
  }

  bool out_of_budget() {
    if (evaluations_ >= options_.evaluations) return true;
    if (seconds() > options_.seconds) {
      stopped_by_time_ = true;
      return true;
    }
    return false;
  }

  // One (mu/mu_w, lambda) evolution strategy with cumulative step-size adaptation in the unit
  // cube (genes clamped), until its share of the budget is spent or its step has collapsed.
  void evolve(std::mt19937_64& rng, int budget) {
    const std::size_t n = dimensions_;
    const auto lambda =
        static_cast<std::size_t>(std::max(10.0, 4.0 + 3.0 * std::log(static_cast<double>(n))));
    const std::size_t mu = lambda / 2;
    std::vector<double> w(mu);
    for (std::size_t i = 0; i < mu; ++i)
      w[i] = std::log(static_cast<double>(mu) + 0.5) - std::log(static_cast<double>(i) + 1.0);
    const double w_sum = std::accumulate(w.begin(), w.end(), 0.0);
    for (double& wi : w) wi /= w_sum;
    double mu_eff = 0.0;
    for (const double wi : w) mu_eff += wi * wi;
    mu_eff = 1.0 / mu_eff;
    const double dn = static_cast<double>(n);
    const double c_sigma = (mu_eff + 2.0) / (dn + mu_eff + 5.0);
    const double d_sigma = 1.0 + c_sigma + 2.0 * std::max(0.0, std::sqrt((mu_eff - 1.0) / (dn + 1.0)) - 1.0);
    const double chi_n = std::sqrt(dn) * (1.0 - 1.0 / (4.0 * dn) + 1.0 / (21.0 * dn * dn));

    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::vector<double> mean(n);
    for (double& m : mean) m = uniform(rng);
    double sigma = 0.3;
    std::vector<double> path(n, 0.0);
    const int stop_at = evaluations_ + budget;
    std::vector<std::vector<double>> steps(lambda, std::vector<double>(n));
    std::vector<std::pair<double, std::size_t>> ranked(lambda);
    std::vector<double> candidate(n);
    while (evaluations_ + static_cast<int>(lambda) <= stop_at && !out_of_budget() && sigma > 1e-4) {
      for (std::size_t k = 0; k < lambda; ++k) {
        for (std::size_t i = 0; i < n; ++i) {
          steps[k][i] = gauss(rng);
          candidate[i] = std::clamp(mean[i] + sigma * steps[k][i], 0.0, 1.0);
        }
        ranked[k] = {score(candidate), k};
      }
      std::sort(ranked.begin(), ranked.end());
      std::vector<double> step(n, 0.0);
      for (std::size_t r = 0; r < mu; ++r)
        for (std::size_t i = 0; i < n; ++i) step[i] += w[r] * steps[ranked[r].second][i];
      double path_norm2 = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        mean[i] = std::clamp(mean[i] + sigma * step[i], 0.0, 1.0);
        path[i] = (1.0 - c_sigma) * path[i] + std::sqrt(c_sigma * (2.0 - c_sigma) * mu_eff) * step[i];
        path_norm2 += path[i] * path[i];
      }
      sigma *= std::exp(c_sigma / d_sigma * (std::sqrt(path_norm2) / chi_n - 1.0));
      sigma = std::min(sigma, 0.5);
      history_.push_back(best_);
    }
  }

  // Pattern search around the best genes with halving steps.
  void refine() {
    if (best_genes_.empty()) return;
    std::vector<double> genes = best_genes_;
    double current = best_;
    for (double step = 0.05; step > 1e-3 && !out_of_budget(); step *= 0.5) {
      bool improved = true;
      while (improved && !out_of_budget()) {
        improved = false;
        for (std::size_t i = 0; i < genes.size() && !out_of_budget(); ++i) {
          for (const double sign : {1.0, -1.0}) {
            if (out_of_budget()) break;
            std::vector<double> trial = genes;
            trial[i] = std::clamp(trial[i] + sign * step, 0.0, 1.0);
            if (trial[i] == genes[i]) continue;
            const double q = score(trial);
            if (q < current) {
              current = q;
              genes = std::move(trial);
              improved = true;
              break;
            }
          }
        }
      }
      history_.push_back(best_);
    }
  }

  PlanResult run() {
    std::mt19937_64 rng(options_.seed);
    const int starts = std::max(1, options_.starts);
    const int refine_budget = options_.evaluations / 5;
    for (start_ = 0; start_ < starts && !out_of_budget(); ++start_) {
      std::mt19937_64 start_rng(rng());
      evolve(start_rng, (options_.evaluations - refine_budget) / starts);
    }
    refine();
    PlanResult result;
    result.cameras = options_.fixed;
    for (int c = 0; c < options_.cameras; ++c)
      result.cameras.push_back(
          decode_camera(room_, best_genes_.data() + static_cast<std::ptrdiff_t>(c) * kGenes,
                        "plan" + std::to_string(options_.fixed.size() + static_cast<std::size_t>(c))));
    result.evaluation = evaluate(result.cameras, samples_, room_.obstacles, metric_);
    result.history = history_;
    result.evaluations = evaluations_;
    result.seconds = seconds();
    result.stopped_by_time = stopped_by_time_;
    return result;
  }

 private:
  double seconds() const { return std::chrono::duration<double>(Clock::now() - begin_).count(); }

  const Room& room_;
  const SampleSet& samples_;
  const MetricOptions& metric_;
  const PlanOptions& options_;
  Clock::time_point begin_;
  std::size_t dimensions_ = 0;
  int evaluations_ = 0;
  int start_ = 0;
  double best_ = std::numeric_limits<double>::infinity();
  std::vector<double> best_genes_;
  std::vector<double> history_;
  bool stopped_by_time_ = false;
};

}  // namespace

PlannedCamera decode_camera(const Room& room, const double* genes, const std::string& id) {
  const MountSurface& mount = room.mounts[pick_index(genes[0], room.mounts.size())];
  const Eigen::Vector3d position = mount.at(genes[1], genes[2]);
  const Box& v = room.volume;
  Eigen::Vector3d aim = v.min + Eigen::Vector3d(genes[3], genes[4], genes[5]).cwiseProduct(v.max - v.min);
  if ((aim - position).norm() < 1e-6) aim += Eigen::Vector3d(0.0, 0.0, -0.1);
  return make_camera(id, room.lenses[pick_index(genes[6], room.lenses.size())], position, aim);
}

PlanResult plan(const Room& room, const SampleSet& samples, const MetricOptions& metric,
                const PlanOptions& options) {
  if (room.mounts.empty())
    throw std::invalid_argument("infeasible plan: the room has no mounting surface (mounts)");
  if (room.lenses.empty())
    throw std::invalid_argument("infeasible plan: the room lists no camera lens (lenses)");
  if (options.cameras < 1) throw std::invalid_argument("infeasible plan: at least one camera to place");
  if (static_cast<std::size_t>(options.cameras) + options.fixed.size() > 64)
    throw std::invalid_argument("infeasible plan: at most 64 cameras");
  if (room.volume.volume() <= 0.0)
    throw std::invalid_argument("infeasible plan: the working volume is empty");
  Search search(room, samples, metric, options);
  PlanResult result = search.run();
  if (result.evaluation.visible_histogram.empty() || result.evaluation.p_at_least_k <= 0.0) {
    bool any_seen = false;
    for (const double p : result.evaluation.point_p_k) any_seen = any_seen || p > 0.0;
    if (!any_seen)
      throw std::invalid_argument(
          "infeasible plan: from the mounting surfaces no " + std::to_string(metric.k_cameras) +
          " cameras see any point of the working volume (check the mounts, lens depth range and obstacles)");
  }
  return result;
}

std::vector<double> removal_costs(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                                  std::span<const Box> obstacles, const MetricOptions& metric) {
  std::vector<double> costs;
  for (std::size_t skip = 0; skip < cameras.size(); ++skip) {
    std::vector<PlannedCamera> rest;
    for (std::size_t c = 0; c < cameras.size(); ++c)
      if (c != skip) rest.push_back(cameras[c]);
    costs.push_back(evaluate(rest, samples, obstacles, metric).quality);
  }
  return costs;
}

}  // namespace panoptes::planner
