// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/estimator_session.h"

namespace panoptes::session {

EstimatorSession::EstimatorSession(const EstimatorConfig& config)
    : config_(config),
      tracker_(config_.tracker),
      intake_(tracker_, config_.screen, config_.node.latency_window_ms),
      inbox_(config_.node.inbox_capacity, seconds_to_ns(config_.node.latency_window_ms * 1e-3)),
      pose_horizon_ns_(seconds_to_ns(config_.node.prediction_horizon_ms * 1e-3)) {}

void EstimatorSession::process_due(std::vector<FeatureFrame>& due,
                                   const std::function<void(FeatureFrame&, estimator::FrameOutcome)>& each) {
  const TimeNs newest = tracker_.last_stamp_ns();
  std::size_t late = 0;
  while (late < due.size() && due[late].stamp_ns < newest) ++late;
  if (late == 1) {
    each(due[0], intake_.process(due[0]));
  } else if (late > 1) {
    const auto outcomes = intake_.process_batch({due.data(), late});
    for (std::size_t i = 0; i < late; ++i) each(due[i], outcomes[i]);
  }
  for (std::size_t i = late; i < due.size(); ++i) each(due[i], intake_.process(due[i]));
}

}  // namespace panoptes::session
