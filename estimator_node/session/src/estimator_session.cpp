// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/estimator_session.h"

namespace panoptes::session {

EstimatorSession::EstimatorSession(const EstimatorConfig& config)
    : config_(config),
      tracker_(config_.tracker),
      intake_(tracker_, config_.screen, config_.node.latency_window_ms),
      inbox_(config_.node.inbox_capacity, seconds_to_ns(config_.node.latency_window_ms * 1e-3)),
      pose_horizon_ns_(seconds_to_ns(config_.node.prediction_horizon_ms * 1e-3)) {}

}  // namespace panoptes::session
