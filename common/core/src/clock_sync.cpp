// SPDX-License-Identifier: Apache-2.0
#include "panoptes/clock_sync.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdlib>

namespace panoptes {
namespace {

std::int64_t floor_div(TimeNs value, TimeNs divisor) {
  const std::int64_t quotient = value / divisor;
  return (value % divisor != 0 && (value < 0) != (divisor < 0)) ? quotient - 1 : quotient;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  if (values.size() % 2 == 1) return *middle;
  const double upper = *middle;
  const double lower = *std::max_element(values.begin(), middle);
  return 0.5 * (lower + upper);
}

}  // namespace

TimeNs ClockEstimate::offset_at(TimeNs local_ns) const {
  if (samples == 0) return 0;
  return static_cast<TimeNs>(std::llround(offset_ns + drift * static_cast<double>(local_ns - reference_ns)));
}

TimeNs ClockEstimate::to_local(TimeNs server_ns) const {
  if (samples == 0) return server_ns;
  // server = local − (offset + drift·(local − reference)), solved for local.
  const double since_reference = (static_cast<double>(server_ns - reference_ns) + offset_ns) / (1.0 - drift);
  return reference_ns + static_cast<TimeNs>(std::llround(since_reference));
}

ClockSync::ClockSync(const ClockSyncOptions& options) : options_(options) {
  assert(options_.interval_ns > 0 && options_.keep_per_interval > 0 && options_.max_intervals > 0);
  assert(options_.min_sigma_ns > 0 && options_.drift_prior_ppm > 0);
}

void ClockSync::reset() {
  intervals_.clear();
  step_suspects_.clear();
  estimate_ = {};
}

bool ClockSync::wants_more_exchanges() const {
  return !estimate_.synchronised || estimate_.offset_sigma_ns > static_cast<double>(options_.target_sigma_ns);
}

std::size_t ClockSync::kept() const {
  std::size_t count = 0;
  for (const Interval& interval : intervals_) count += interval.samples.size();
  return count;
}

ClockSync::Sample ClockSync::to_sample(const ClockExchange& exchange) {
  return {exchange.local_mid_ns(), exchange.offset_ns(), exchange.round_trip_ns()};
}

ClockSync::Verdict ClockSync::add(const ClockExchange& exchange) {
  if (exchange.t4_ns < exchange.t1_ns || exchange.t3_ns < exchange.t2_ns || exchange.round_trip_ns() < 0) {
    return Verdict::kInvalid;
  }
  if (exchange.round_trip_ns() > options_.max_round_trip_ns) return Verdict::kTooSlow;
  const Sample sample = to_sample(exchange);

  if (contradicts_fit(sample)) {
    // Suspects only confirm a step if they agree with one another; one that does not is dropped
    // (the oldest first), so scattered corrupt replies never restart the estimate.
    step_suspects_.push_back(sample);
    const auto agree = [this] {
      const auto [low, high] =
          std::minmax_element(step_suspects_.begin(), step_suspects_.end(),
                              [](const Sample& a, const Sample& b) { return a.offset_ns < b.offset_ns; });
      return high->offset_ns - low->offset_ns <= options_.step_threshold_ns;
    };
    while (step_suspects_.size() > 1 && !agree()) step_suspects_.erase(step_suspects_.begin());
    if (step_suspects_.size() < options_.step_confirm) return Verdict::kStepSuspected;
    const std::vector<Sample> suspects = std::move(step_suspects_);
    reset();
    ++resets_;
    for (const Sample& suspect : suspects) store(suspect);
    fit();
    return Verdict::kStepped;
  }
  step_suspects_.clear();
  if (!store(sample)) return Verdict::kNotKept;
  fit();
  return Verdict::kKept;
}

bool ClockSync::contradicts_fit(const Sample& sample) const {
  if (!estimate_.synchronised) return false;
  // The true offset lies within round_trip/2 of the sample's: only a fit outside that interval
  // (by more than the threshold) is a contradiction.
  const TimeNs miss =
      std::llabs(sample.offset_ns - estimate_.offset_at(sample.local_ns)) - sample.round_trip_ns / 2;
  return miss > options_.step_threshold_ns;
}

bool ClockSync::store(const Sample& sample) {
  const std::int64_t index = floor_div(sample.local_ns, options_.interval_ns);
  auto it = std::lower_bound(intervals_.begin(), intervals_.end(), index,
                             [](const Interval& interval, std::int64_t i) { return interval.index < i; });
  if (it == intervals_.end() || it->index != index) {
    if (!intervals_.empty() &&
        index <= intervals_.back().index - static_cast<std::int64_t>(options_.max_intervals)) {
      return false;  // older than the whole history
    }
    it = intervals_.insert(it, Interval{index, {}});
  }
  std::vector<Sample>& samples = it->samples;
  if (samples.size() < options_.keep_per_interval) {
    samples.push_back(sample);
  } else {
    auto worst = std::max_element(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) {
      return a.round_trip_ns < b.round_trip_ns;
    });
    if (sample.round_trip_ns >= worst->round_trip_ns) return false;
    *worst = sample;
  }
  const std::int64_t newest = intervals_.back().index;
  while (intervals_.front().index <= newest - static_cast<std::int64_t>(options_.max_intervals)) {
    intervals_.pop_front();
  }
  return true;
}

// Weighted least squares line through the kept samples, offset = a + b·(local − reference), with
// weights 1/σ² (σ grows with the round trip's excess over the shortest) times an age decay, a
// Gaussian prior on the drift b, and iterated rejection of samples beyond `outlier_sigmas`
// robust standard deviations.
void ClockSync::fit() {
  // The previous drift (ns/s) seeds the robust start.
  const double previous_drift = estimate_.samples > 0 ? estimate_.drift * 1e9 : 0.0;
  std::vector<Sample> all;
  for (const Interval& interval : intervals_)
    all.insert(all.end(), interval.samples.begin(), interval.samples.end());
  estimate_ = {};
  if (all.empty()) return;

  const auto newest = std::max_element(
      all.begin(), all.end(), [](const Sample& a, const Sample& b) { return a.local_ns < b.local_ns; });
  const TimeNs reference = newest->local_ns;
  const TimeNs offset_base = newest->offset_ns;  // keeps the fitted numbers small
  TimeNs min_round_trip = all.front().round_trip_ns;
  for (const Sample& s : all) min_round_trip = std::min(min_round_trip, s.round_trip_ns);

  const double best_sigma = std::max(static_cast<double>(options_.min_sigma_ns),
                                     options_.sigma_per_round_trip * static_cast<double>(min_round_trip));
  const std::size_t n = all.size();
  std::vector<double> x(n), y(n), sigma(n), weight(n);
  const double half_life = static_cast<double>(options_.age_half_life_ns);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = static_cast<double>(all[i].local_ns - reference) * 1e-9;  // s
    y[i] = static_cast<double>(all[i].offset_ns - offset_base);      // ns
    sigma[i] = best_sigma + 0.5 * static_cast<double>(all[i].round_trip_ns - min_round_trip);
    const double age = static_cast<double>(reference - all[i].local_ns);
    weight[i] = std::exp2(-age / half_life) / (sigma[i] * sigma[i]);
  }
  const double drift_prior = options_.drift_prior_ppm * 1e3;  // ns/s
  const double prior_information = 1.0 / (drift_prior * drift_prior);
  const double max_drift = options_.max_drift_ppm * 1e3;

  constexpr int kMaxRejectionRounds = 6;
  constexpr std::size_t kMinSamplesToReject = 4;
  constexpr std::size_t kRobustStartCandidates = 16;
  std::vector<bool> fitted(n, true);
  double a = 0, b = 0, sum_w = 0, sum_wx = 0, sum_wxx = 0, determinant = 1;
  const auto solve = [&] {
    sum_w = sum_wx = sum_wxx = 0;
    double sum_wy = 0, sum_wxy = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!fitted[i]) continue;
      sum_w += weight[i];
      sum_wx += weight[i] * x[i];
      sum_wxx += weight[i] * x[i] * x[i];
      sum_wy += weight[i] * y[i];
      sum_wxy += weight[i] * x[i] * y[i];
    }
    determinant = sum_w * (sum_wxx + prior_information) - sum_wx * sum_wx;
    a = ((sum_wxx + prior_information) * sum_wy - sum_wx * sum_wxy) / determinant;
    b = (sum_w * sum_wxy - sum_wx * sum_wy) / determinant;
    if (std::abs(b) > max_drift) {
      b = std::copysign(max_drift, b);
      a = (sum_wy - sum_wx * b) / sum_w;
    }
  };

  solve();
  if (n >= kMinSamplesToReject) {
    // Robust start (least median of residuals): a least-squares line can be dragged onto an
    // outlier that has a short round trip and hence a large weight, and then hide it. Candidate
    // lines go through the best-timed samples, singly with the previous drift and in pairs; the
    // one with the smallest median normalised residual starts the rejection.
    std::vector<std::size_t> best(n);
    for (std::size_t i = 0; i < n; ++i) best[i] = i;
    const std::size_t m = std::min<std::size_t>(n, kRobustStartCandidates);
    std::partial_sort(best.begin(), best.begin() + static_cast<std::ptrdiff_t>(m), best.end(),
                      [&sigma](std::size_t i, std::size_t j) { return sigma[i] < sigma[j]; });
    std::vector<double> z(n);
    const auto median_z = [&](double line_a, double line_b) {
      for (std::size_t i = 0; i < n; ++i) z[i] = std::abs(y[i] - line_a - line_b * x[i]) / sigma[i];
      return median(z);
    };
    double best_cost = median_z(a, b);
    const auto consider = [&](double line_a, double line_b) {
      const double cost = median_z(line_a, line_b);
      if (cost < best_cost) {
        best_cost = cost;
        a = line_a;
        b = line_b;
      }
    };
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t p = best[j];
      consider(y[p] - previous_drift * x[p], previous_drift);
      for (std::size_t k = j + 1; k < m; ++k) {
        const std::size_t q = best[k];
        if (x[p] == x[q]) continue;
        const double slope = std::clamp((y[q] - y[p]) / (x[q] - x[p]), -max_drift, max_drift);
        consider(y[p] - slope * x[p], slope);
      }
    }
    // Rejection: samples beyond `outlier_sigmas` robust standard deviations of the current line
    // are left out and the line refitted, until the set is stable. 1.4826 · median |z| estimates
    // the standard deviation of Gaussian residuals; below 1 the assumed sigmas are already
    // pessimistic and are kept.
    for (int round = 0; round < kMaxRejectionRounds; ++round) {
      const double scale = std::max(1.0, 1.4826 * median_z(a, b));
      std::vector<bool> next(n);
      for (std::size_t i = 0; i < n; ++i) next[i] = z[i] <= options_.outlier_sigmas * scale;
      if (next == fitted) break;
      fitted = next;
      solve();
    }
    solve();  // the start line is only a start: the estimate is the least-squares line
  }

  double chi2 = 0;
  std::size_t count = 0;
  TimeNs oldest = reference;
  TimeNs fitted_min_round_trip = -1;
  for (std::size_t i = 0; i < n; ++i) {
    if (!fitted[i]) continue;
    const double residual = y[i] - a - b * x[i];
    chi2 += weight[i] * residual * residual;
    ++count;
    oldest = std::min(oldest, all[i].local_ns);
    if (fitted_min_round_trip < 0 || all[i].round_trip_ns < fitted_min_round_trip)
      fitted_min_round_trip = all[i].round_trip_ns;
  }
  // Standard errors from the normal equations, inflated when the residuals are larger than the
  // assumed sigmas.
  const double inflation = count > 2 ? std::max(1.0, chi2 / static_cast<double>(count - 2)) : 1.0;

  estimate_.reference_ns = reference;
  estimate_.offset_ns = static_cast<double>(offset_base) + a;
  estimate_.drift = b * 1e-9;
  estimate_.samples = count;
  estimate_.outliers = n - count;
  estimate_.span_ns = reference - oldest;
  estimate_.residual_rms_ns = std::sqrt(chi2 / sum_w);
  estimate_.offset_sigma_ns = std::sqrt((sum_wxx + prior_information) / determinant * inflation);
  estimate_.drift_sigma_ppm = std::sqrt(sum_w / determinant * inflation) * 1e-3;
  estimate_.min_round_trip_ns = fitted_min_round_trip;
  estimate_.synchronised = count >= options_.min_samples;
}

}  // namespace panoptes
