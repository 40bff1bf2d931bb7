// SPDX-License-Identifier: Apache-2.0
#include "panoptes/clock_sync.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <vector>

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

// The kept samples as a weighted line fit, in numbers kept small: x = local − reference (s),
// y = offset − the newest sample's offset (ns).
struct LineData {
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> sigma;     // ns
  std::vector<double> weight;    // age decay / σ²
  double prior_information = 0;  // of the Gaussian prior on the drift, (ns/s)⁻²
  double max_drift = 0;          // ns/s
  std::size_t size() const { return x.size(); }
};

// offset = a + b·x, and the normal equations' sums that give its standard errors.
struct Line {
  double a = 0;  // ns
  double b = 0;  // ns/s
  double sum_w = 0;
  double sum_wx = 0;
  double sum_wxx = 0;
  double determinant = 1;
};

// Weighted least squares over the samples marked in `fitted`, with the drift prior; a drift beyond
// max_drift is clamped and the offset refitted.
Line least_squares_line(const LineData& data, const std::vector<bool>& fitted) {
  Line line;
  double sum_wy = 0, sum_wxy = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (!fitted[i]) continue;
    line.sum_w += data.weight[i];
    line.sum_wx += data.weight[i] * data.x[i];
    line.sum_wxx += data.weight[i] * data.x[i] * data.x[i];
    sum_wy += data.weight[i] * data.y[i];
    sum_wxy += data.weight[i] * data.x[i] * data.y[i];
  }
  line.determinant = line.sum_w * (line.sum_wxx + data.prior_information) - line.sum_wx * line.sum_wx;
  line.a = ((line.sum_wxx + data.prior_information) * sum_wy - line.sum_wx * sum_wxy) / line.determinant;
  line.b = (line.sum_w * sum_wxy - line.sum_wx * sum_wy) / line.determinant;
  if (std::abs(line.b) > data.max_drift) {
    line.b = std::copysign(data.max_drift, line.b);
    line.a = (sum_wy - line.sum_wx * line.b) / line.sum_w;
  }
  return line;
}

// Every sample's normalised residual |y − a − b·x| / σ about a line, into `z`; returns their median.
double median_residual(const LineData& data, double a, double b, std::vector<double>& z) {
  for (std::size_t i = 0; i < data.size(); ++i)
    z[i] = std::abs(data.y[i] - a - b * data.x[i]) / data.sigma[i];
  return median(z);
}

// Robust start (least median of residuals): a least-squares line can be dragged onto an outlier
// that has a short round trip and hence a large weight, and then hide it. Candidate lines go
// through the best-timed samples, singly with the previous drift and in pairs; the one with the
// smallest median normalised residual replaces `line`'s a and b.
void robust_start(const LineData& data, double previous_drift, Line& line) {
  constexpr std::size_t kRobustStartCandidates = 16;
  const std::size_t n = data.size();
  std::vector<std::size_t> best(n);
  for (std::size_t i = 0; i < n; ++i) best[i] = i;
  const std::size_t m = std::min<std::size_t>(n, kRobustStartCandidates);
  std::partial_sort(best.begin(), best.begin() + static_cast<std::ptrdiff_t>(m), best.end(),
                    [&data](std::size_t i, std::size_t j) { return data.sigma[i] < data.sigma[j]; });
  std::vector<double> z(n);
  double best_cost = median_residual(data, line.a, line.b, z);
  const auto consider = [&](double line_a, double line_b) {
    const double cost = median_residual(data, line_a, line_b, z);
    if (cost < best_cost) {
      best_cost = cost;
      line.a = line_a;
      line.b = line_b;
    }
  };
  const auto& x = data.x;
  const auto& y = data.y;
  for (std::size_t j = 0; j < m; ++j) {
    const std::size_t p = best[j];
    consider(y[p] - previous_drift * x[p], previous_drift);
    for (std::size_t k = j + 1; k < m; ++k) {
      const std::size_t q = best[k];
      if (x[p] == x[q]) continue;
      const double slope = std::clamp((y[q] - y[p]) / (x[q] - x[p]), -data.max_drift, data.max_drift);
      consider(y[p] - slope * x[p], slope);
    }
  }
}

// Rejection from the start line: samples beyond `outlier_sigmas` robust standard deviations of the
// current line are left out and the line refitted, until the set is stable. 1.4826 · median |z|
// estimates the standard deviation of Gaussian residuals; below 1 the assumed sigmas are already
// pessimistic and are kept. Returns the samples to fit.
std::vector<bool> reject_outliers(const LineData& data, double outlier_sigmas, Line line) {
  constexpr int kMaxRejectionRounds = 6;
  const std::size_t n = data.size();
  std::vector<bool> fitted(n, true);
  std::vector<double> z(n);
  for (int round = 0; round < kMaxRejectionRounds; ++round) {
    const double scale = std::max(1.0, 1.4826 * median_residual(data, line.a, line.b, z));
    std::vector<bool> next(n);
    for (std::size_t i = 0; i < n; ++i) next[i] = z[i] <= outlier_sigmas * scale;
    if (next == fitted) break;
    fitted = next;
    line = least_squares_line(data, fitted);
  }
  return fitted;
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
  LineData data;
  data.x.resize(n);
  data.y.resize(n);
  data.sigma.resize(n);
  data.weight.resize(n);
  const double half_life = static_cast<double>(options_.age_half_life_ns);
  for (std::size_t i = 0; i < n; ++i) {
    data.x[i] = static_cast<double>(all[i].local_ns - reference) * 1e-9;  // s
    data.y[i] = static_cast<double>(all[i].offset_ns - offset_base);      // ns
    data.sigma[i] = best_sigma + 0.5 * static_cast<double>(all[i].round_trip_ns - min_round_trip);
    const double age = static_cast<double>(reference - all[i].local_ns);
    data.weight[i] = std::exp2(-age / half_life) / (data.sigma[i] * data.sigma[i]);
  }
  const double drift_prior = options_.drift_prior_ppm * 1e3;  // ns/s
  data.prior_information = 1.0 / (drift_prior * drift_prior);
  data.max_drift = options_.max_drift_ppm * 1e3;

  constexpr std::size_t kMinSamplesToReject = 4;
  std::vector<bool> fitted(n, true);
  Line line = least_squares_line(data, fitted);
  if (n >= kMinSamplesToReject) {
    robust_start(data, previous_drift, line);
    fitted = reject_outliers(data, options_.outlier_sigmas, line);
    // The start line is only a start: the estimate is the least-squares line.
    line = least_squares_line(data, fitted);
  }

  double chi2 = 0;
  std::size_t count = 0;
  TimeNs oldest = reference;
  TimeNs fitted_min_round_trip = -1;
  for (std::size_t i = 0; i < n; ++i) {
    if (!fitted[i]) continue;
    const double residual = data.y[i] - line.a - line.b * data.x[i];
    chi2 += data.weight[i] * residual * residual;
    ++count;
    oldest = std::min(oldest, all[i].local_ns);
    if (fitted_min_round_trip < 0 || all[i].round_trip_ns < fitted_min_round_trip)
      fitted_min_round_trip = all[i].round_trip_ns;
  }
  // Standard errors from the normal equations, inflated when the residuals are larger than the
  // assumed sigmas.
  const double inflation = count > 2 ? std::max(1.0, chi2 / static_cast<double>(count - 2)) : 1.0;

  estimate_.reference_ns = reference;
  estimate_.offset_ns = static_cast<double>(offset_base) + line.a;
  estimate_.drift = line.b * 1e-9;
  estimate_.samples = count;
  estimate_.outliers = n - count;
  estimate_.span_ns = reference - oldest;
  estimate_.residual_rms_ns = std::sqrt(chi2 / line.sum_w);
  estimate_.offset_sigma_ns =
      std::sqrt((line.sum_wxx + data.prior_information) / line.determinant * inflation);
  estimate_.drift_sigma_ppm = std::sqrt(line.sum_w / line.determinant * inflation) * 1e-3;
  estimate_.min_round_trip_ns = fitted_min_round_trip;
  estimate_.synchronised = count >= options_.min_samples;
}

}  // namespace panoptes
