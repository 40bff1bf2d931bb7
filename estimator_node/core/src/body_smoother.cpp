// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/body_smoother.h"

#include <Eigen/Cholesky>

namespace panoptes::estimator {

namespace {

// C_kᵀ = P_{k+1|k}⁻¹ A_{k+1} P_k|k (P_{k+1|k} symmetric positive definite).
BodyMatrix gain_t(const BodyFilterStep& step, const BodyFilterStep& next) {
  const BodyMatrix AP = next.A * step.filtered.P.matrix();
  return next.predicted.P.matrix().ldlt().solve(AP);
}

// The step's previous gain from the newest step before it (none for the first step).
void set_previous_gain(const BodyFilterStep* newest, BodyFilterStep& step) {
  if (newest == nullptr) return;
  step.previous_gain_t = gain_t(*newest, step);
  step.has_previous_gain = true;
}

}  // namespace

void append_step(std::vector<BodyFilterStep>& steps, BodyFilterStep step) {
  set_previous_gain(steps.empty() ? nullptr : &steps.back(), step);
  steps.push_back(std::move(step));
}

void BodyFilterHistory::append(BodyFilterStep step) {
  set_previous_gain(steps_.empty() ? nullptr : steps_.back().get(), step);
  steps_.push_back(std::make_shared<const BodyFilterStep>(std::move(step)));
}

void BodyFilterHistory::keep_from(TimeNs oldest_ns) {
  std::size_t first = 0;
  while (first + 1 < steps_.size() && steps_[first + 1]->filtered.stamp_ns <= oldest_ns) ++first;
  steps_.erase(steps_.begin(), steps_.begin() + static_cast<std::ptrdiff_t>(first));
}

namespace {

// smoothed_state's pass over either container of steps (size(), operator[], back()).
template <typename Steps>
BodyState smoothed(const Steps& steps, std::size_t index) {
  BodyState smoothed = steps.back().filtered;
  for (std::size_t k = steps.size() - 1; k-- > index;) {
    const BodyFilterStep& next = steps[k + 1];
    const BodyVector correction =
        (next.has_previous_gain ? next.previous_gain_t : gain_t(steps[k], next)).transpose() *
        body_difference(smoothed, next.predicted);
    BodyState previous = steps[k].filtered;
    inject(previous, correction);
    smoothed = std::move(previous);
  }
  return smoothed;
}

}  // namespace

BodyState smoothed_state(const std::vector<BodyFilterStep>& steps, std::size_t index) {
  return smoothed(steps, index);
}

BodyState smoothed_state(const BodyFilterHistory& steps, std::size_t index) {
  return smoothed(steps, index);
}

}  // namespace panoptes::estimator
