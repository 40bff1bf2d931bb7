// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/body_smoother.h"

#include <Eigen/Cholesky>

namespace panoptes::estimator {

BodyState smoothed_state(const std::vector<BodyFilterStep>& steps, std::size_t index) {
  BodyState smoothed = steps.back().filtered;
  for (std::size_t k = steps.size() - 1; k-- > index;) {
    const BodyFilterStep& next = steps[k + 1];
    // C_kᵀ = P_{k+1|k}⁻¹ A_{k+1} P_k|k (P_{k+1|k} symmetric positive definite).
    const BodyMatrix AP = next.A * steps[k].filtered.P.matrix();
    const BodyMatrix Ct = next.predicted.P.matrix().ldlt().solve(AP);
    const BodyVector correction = Ct.transpose() * body_difference(smoothed, next.predicted);
    BodyState previous = steps[k].filtered;
    inject(previous, correction);
    smoothed = std::move(previous);
  }
  return smoothed;
}

}  // namespace panoptes::estimator
