// SPDX-License-Identifier: Apache-2.0
#include "panoptes/planner/optimizer.h"

#include "panoptes/planner/incremental_metric.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
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

using Genes = std::array<double, kGenes>;

// The search's clocks: wall time, and this process's CPU time for a loaded machine.
class Stopwatch {
 public:
  Stopwatch() : wall_begin_(Clock::now()), cpu_begin_(std::clock()) {}
  double wall() const { return std::chrono::duration<double>(Clock::now() - wall_begin_).count(); }
  double cpu() const { return static_cast<double>(std::clock() - cpu_begin_) / CLOCKS_PER_SEC; }

 private:
  Clock::time_point wall_begin_;
  std::clock_t cpu_begin_;
};

class Search {
 public:
  Search(const Room& room, const SampleSet& samples, const MetricOptions& metric, const PlanOptions& options)
      : room_(room),
        options_(options),
        fixed_(options.fixed.size()),
        metric_(samples, room.obstacles, metric,
                options.fixed.size() + static_cast<std::size_t>(options.cameras), options.objective,
                options.tracker),
        genes_(static_cast<std::size_t>(options.cameras)) {
    for (std::size_t f = 0; f < fixed_; ++f) metric_.place(f, options.fixed[f]);
    current_ = metric_.value();
  }

  PlanResult run() {
    std::mt19937_64 rng(options_.seed);
    const int starts = std::max(1, options_.starts);
    // Half of the budget for the starts, each until its share is spent or it has converged; the
    // rest for the iterated search from the best of them.
    for (start_ = 0; start_ < starts && !out_of_budget(); ++start_) {
      const double share_end = 0.5 * static_cast<double>(start_ + 1) / static_cast<double>(starts);
      greedy_start(rng);
      descend(rng, share_end);
    }
    start_ = starts;
    iterate(rng);
    if (best_genes_.empty()) best_genes_ = genes_;  // out of budget before a whole layout
    PlanResult result;
    result.cameras = options_.fixed;
    for (std::size_t c = 0; c < genes_.size(); ++c)
      result.cameras.push_back(
          decode_camera(room_, best_genes_[c].data(), "plan" + std::to_string(fixed_ + c)));
    result.history = history_;
    result.evaluations = evaluations_;
    result.seconds = clock_.wall();
    result.cpu_seconds = clock_.cpu();
    result.stopped_by_time = stopped_by_time_;
    return result;
  }

 private:
  // Camera `c` with `genes`: the metric after the move. Keep it with accept(), or undo().
  double try_move(std::size_t c, const Genes& genes) {
    ++evaluations_;
    const double q = metric_.place(fixed_ + c, decode_camera(room_, genes.data(), ""));
    report_progress();
    return q;
  }
  void accept(std::size_t c, const Genes& genes, double q) {
    genes_[c] = genes;
    current_ = q;
    if (complete_ && q < best_) {
      best_ = q;
      best_genes_ = genes_;
    }
  }
  // Moves camera `c` to `genes` if that improves the layout; true when it did.
  bool improve(std::size_t c, const Genes& genes) {
    const double q = try_move(c, genes);
    if (q < current_) {
      accept(c, genes, q);
      return true;
    }
    metric_.undo();
    return false;
  }

  // Every camera placed in turn where the best of `kCandidates` random genes puts it, the cameras
  // after it not yet in the room.
  void greedy_start(std::mt19937_64& rng) {
    complete_ = false;
    for (std::size_t c = 0; c < genes_.size(); ++c) metric_.remove(fixed_ + c);
    current_ = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < genes_.size() && !out_of_budget(); ++c) {
      complete_ = c + 1 == genes_.size();
      place_best_of_random(c, rng);
    }
  }

  void place_best_of_random(std::size_t c, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const double before = current_;
    current_ = std::numeric_limits<double>::infinity();  // the first candidate is always taken
    bool placed = false;
    for (int k = 0; k < kCandidates && !out_of_budget(); ++k) {
      Genes genes;
      for (double& g : genes) g = uniform(rng);
      placed = improve(c, genes) || placed;
    }
    if (!placed) current_ = before;
  }

  // A (1+1) evolution strategy on each camera in turn, a few trials each per sweep, with its own
  // step (grown 1.5× on success, shrunk on failure: the 1/5 success rule), until every step is
  // below kMinStep or the budget reaches `share_end`.
  void descend(std::mt19937_64& rng, double share_end) {
    std::vector<double> step(genes_.size(), kFirstStep);
    std::vector<std::size_t> order(genes_.size());
    std::iota(order.begin(), order.end(), 0);
    while (!out_of_budget() && used_share() < share_end) {
      std::shuffle(order.begin(), order.end(), rng);
      bool moving = false;
      for (const std::size_t c : order) {
        for (int t = 0; t < kTrialsPerSweep && step[c] >= kMinStep && !out_of_budget(); ++t) {
          moving = true;
          step[c] =
              improve(c, mutate(genes_[c], step[c], rng)) ? std::min(0.5, step[c] * 1.5) : step[c] * kShrink;
        }
      }
      if (std::isfinite(best_)) history_.push_back(best_);
      if (!moving) break;
    }
  }

  Genes mutate(const Genes& genes, double step, std::mt19937_64& rng) {
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    Genes trial = genes;
    for (int g = 1; g <= 5; ++g) trial[g] = std::clamp(trial[g] + step * gauss(rng), 0.0, 1.0);
    // The surface and the lens are choices: another one now and then, more often while steps are
    // large.
    for (const int g : {0, 6})
      if (uniform(rng) < std::min(0.15, step)) trial[g] = uniform(rng);
    return trial;
  }

  // Iterated local search: from the best layout, re-place one camera (every third round two) at
  // the best of random positions, descend, and keep the result if it beats the best.
  void iterate(std::mt19937_64& rng) {
    if (best_genes_.empty() || evaluations_ + static_cast<int>(genes_.size()) > options_.evaluations) return;
    restore_best();
    std::uniform_int_distribution<std::size_t> pick(0, genes_.size() - 1);
    for (int round = 0; !out_of_budget(); ++round) {
      const int moved = round % 3 == 2 && genes_.size() > 1 ? 2 : 1;
      for (int m = 0; m < moved; ++m) place_best_of_random(pick(rng), rng);
      descend(rng, 1.0);
      if (current_ > best_) {
        if (evaluations_ + static_cast<int>(genes_.size()) > options_.evaluations) break;
        restore_best();
      }
    }
  }

  void restore_best() {
    for (std::size_t c = 0; c < genes_.size(); ++c) {
      if (genes_[c] == best_genes_[c]) continue;
      ++evaluations_;
      genes_[c] = best_genes_[c];
      metric_.place(fixed_ + c, decode_camera(room_, genes_[c].data(), ""));
    }
    current_ = metric_.value();
  }

  // The larger of the shares of the evaluation and time budgets spent.
  double used_share() const {
    return std::max(static_cast<double>(evaluations_) / std::max(1, options_.evaluations),
                    seconds() / options_.seconds);
  }

  bool out_of_budget() {
    if (evaluations_ >= options_.evaluations) return true;
    if (seconds() > options_.seconds) {
      stopped_by_time_ = true;
      return true;
    }
    return false;
  }

  double seconds() const { return options_.cpu_clock ? clock_.cpu() : clock_.wall(); }

  void report_progress() {
    if (!options_.progress) return;
    const double now = clock_.wall();
    if (evaluations_ % std::max(1, options_.evaluations / 50) != 0 && now < last_progress_ + 1.0) return;
    last_progress_ = now;
    options_.progress({evaluations_, start_, best_, now});
  }

  static constexpr int kCandidates = 24;
  static constexpr int kTrialsPerSweep = 4;
  static constexpr double kFirstStep = 0.1;
  static constexpr double kMinStep = 2e-3;
  static constexpr double kShrink = 0.9036;  // 1.5^(-1/4): steady at one success in five

  const Room& room_;
  const PlanOptions& options_;
  std::size_t fixed_ = 0;
  IncrementalMetric metric_;
  std::vector<Genes> genes_;  // the layout in metric_
  double current_ = 0;        // its quality
  std::vector<Genes> best_genes_;
  double best_ = std::numeric_limits<double>::infinity();
  Stopwatch clock_;
  int evaluations_ = 0;
  int start_ = 0;
  bool complete_ = false;  // every camera placed: a layout that may become the best
  std::vector<double> history_;
  double last_progress_ = 0;
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
  result.evaluation = evaluate(result.cameras, samples, room.obstacles, metric);
  result.objective_value = options.objective == Objective::kQuality
                               ? result.evaluation.quality
                               : objective_value(result.cameras, samples, room.obstacles, metric,
                                                 options.objective, options.tracker);
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

double objective_value(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                       std::span<const Box> obstacles, const MetricOptions& metric, Objective objective,
                       const TrackerModel& tracker) {
  if (objective == Objective::kQuality) return evaluate(cameras, samples, obstacles, metric).quality;
  return predict_tracking(cameras, samples, obstacles, metric, tracker).rmse_gaps_charged_m;
}

std::vector<double> removal_costs(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                                  std::span<const Box> obstacles, const MetricOptions& metric,
                                  Objective objective, const TrackerModel& tracker) {
  std::vector<double> costs;
  for (std::size_t skip = 0; skip < cameras.size(); ++skip) {
    std::vector<PlannedCamera> rest;
    for (std::size_t c = 0; c < cameras.size(); ++c)
      if (c != skip) rest.push_back(cameras[c]);
    costs.push_back(objective_value(rest, samples, obstacles, metric, objective, tracker));
  }
  return costs;
}

const char* objective_name(Objective objective) {
  return objective == Objective::kQuality ? "q" : "tracker_rmse";
}

std::optional<Objective> objective_from_name(const std::string& name) {
  if (name == "q") return Objective::kQuality;
  if (name == "tracker_rmse") return Objective::kTrackerRmse;
  return std::nullopt;
}

}  // namespace panoptes::planner
