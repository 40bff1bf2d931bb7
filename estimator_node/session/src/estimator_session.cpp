// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/estimator_session.h"

#include <algorithm>

#include "panoptes/session/log.h"

namespace panoptes::session {

EstimatorSession::EstimatorSession(const EstimatorConfig& config)
    : config_(config),
      tracker_(config_.tracker),
      intake_(tracker_, config_.screen, config_.node.latency_window_ms),
      inbox_(config_.node.inbox_capacity, seconds_to_ns(config_.node.latency_window_ms * 1e-3)),
      pose_horizon_ns_(seconds_to_ns(config_.node.prediction_horizon_ms * 1e-3)) {
  intake_.set_lost_after(seconds_to_ns(config_.node.camera_lost_after_s));
}

void EstimatorSession::process_due(std::vector<FeatureFrame>& due,
                                   const std::function<void(FeatureFrame&, estimator::FrameOutcome)>& each,
                                   const std::function<void()>& before) {
  const auto ahead = [&] {
    if (before) before();
  };
  if (!inside_out_.empty()) {
    // Moving cameras' frames go to their rigs' trackers, in the order taken; the rest as below.
    const auto moving = std::stable_partition(due.begin(), due.end(), [&](const FeatureFrame& frame) {
      return inside_out_.handles(frame.camera_id);
    });
    for (auto it = due.begin(); it != moving; ++it) {
      ahead();
      each(*it, inside_out_.process(*it));
    }
    due.erase(due.begin(), moving);
  }
  const TimeNs newest = tracker_.last_stamp_ns();
  std::size_t late = 0;
  while (late < due.size() && due[late].stamp_ns < newest) ++late;
  if (late == 1) {
    ahead();
    each(due[0], process(due[0]));
  } else if (late > 1) {
    ahead();
    const auto outcomes = intake_.process_batch({due.data(), late});
    for (std::size_t i = 0; i < late; ++i) {
      if (!inside_out_.empty()) inside_out_.observe_fixed(due[i]);
      each(due[i], outcomes[i]);
    }
  }
  for (std::size_t i = late; i < due.size(); ++i) {
    ahead();
    each(due[i], process(due[i]));
  }
}

void EstimatorSession::print_summary(std::size_t bad_lines) const {
  intake_.print_summary(inbox_.drops(), bad_lines, inside_out_.camera_counters());
  for (const auto& line : inside_out_.summary_lines()) log(line);
}

std::vector<PoseRecord> EstimatorSession::current_poses() const {
  std::vector<PoseRecord> poses = tracker_.current_poses(pose_horizon_ns_);
  if (inside_out_.empty()) return poses;
  const TimeNs newest = std::max(tracker_.last_stamp_ns(), inside_out_.last_stamp_ns());
  for (auto& pose : inside_out_.poses_at(newest, pose_horizon_ns_)) poses.push_back(std::move(pose));
  return poses;
}

std::vector<PoseRecord> EstimatorSession::poses_at(TimeNs instant_ns) const {
  std::vector<PoseRecord> poses = tracker_.poses_at(instant_ns, pose_horizon_ns_);
  if (inside_out_.empty()) return poses;
  for (auto& pose : inside_out_.poses_at(instant_ns, pose_horizon_ns_)) poses.push_back(std::move(pose));
  return poses;
}

}  // namespace panoptes::session
