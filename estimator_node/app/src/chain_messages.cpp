// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/chain_messages.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/time.h"

namespace panoptes::estimator_app {

namespace {

namespace est = panoptes::estimator;

std::array<double, 3> xyz(const Eigen::Vector3d& p) {
  return {p.x(), p.y(), p.z()};
}

std::uint8_t status_code(est::ChainStatus status) {
  switch (status) {
    case est::ChainStatus::kTracking:
      return 0;
    case est::ChainStatus::kAmbiguous:
      return 1;
    case est::ChainStatus::kNotIdentified:
      break;
  }
  return 2;
}

// 1-based position of `name` among the chains (0 when it is not one of them).
std::uint32_t chain_id(const std::vector<est::ChainOutput>& outputs, const std::string& name) {
  const auto it = std::find_if(outputs.begin(), outputs.end(),
                               [&](const est::ChainOutput& output) { return output.name == name; });
  return it == outputs.end() ? 0 : static_cast<std::uint32_t>(it - outputs.begin() + 1);
}

msg::ChainState chain_state(const est::ChainOutput& output, const est::ChainOutput* predicted,
                            TimeNs frame_stamp_ns, TimeNs horizon_ns, std::uint32_t id) {
  msg::ChainState state;
  state.name(output.name);
  state.chain_id(id);
  state.status(status_code(output.status));
  state.stamp_ns(frame_stamp_ns);
  state.grabbing(output.grabbing);
  if (output.status != est::ChainStatus::kTracking) return state;
  state.stamp_ns(output.stamp_ns);
  const int joint_count = static_cast<int>(output.marker_valid.size()) - 2;
  state.angles().assign(output.pose.angles.data(), output.pose.angles.data() + std::max(joint_count, 0));
  for (const auto& marker : output.pose.markers) {
    msg::ChainMarker position;
    position.position(xyz(marker));
    state.markers().push_back(position);
  }
  state.marker_valid().assign(output.marker_valid.begin(), output.marker_valid.end());
  state.tip(xyz(output.pose.tip));
  state.predicted_tip(xyz(predicted ? predicted->pose.tip : output.pose.tip));
  state.prediction_horizon_ns(predicted ? horizon_ns : 0);
  return state;
}

}  // namespace

msg::ChainFrame to_chain_message(const session::ChainStage& chains, const FeatureFrame& frame) {
  msg::ChainFrame message;
  message.source_camera(frame.camera_id);
  message.source_frame(frame.frame);
  message.stamp_ns(frame.stamp_ns);
  const auto& outputs = chains.outputs();
  const auto& predicted = chains.predicted_outputs();
  const TimeNs horizon_ns = seconds_to_ns(chains.prediction_horizon_s());
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const est::ChainOutput* ahead = i < predicted.size() ? &predicted[i] : nullptr;
    message.chains().push_back(
        chain_state(outputs[i], ahead, frame.stamp_ns, horizon_ns, static_cast<std::uint32_t>(i + 1)));
  }
  for (const auto& named : chains.events()) {
    msg::ChainEvent event;
    event.chain(named.chain);
    event.chain_id(chain_id(outputs, named.chain));
    event.kind(named.event.kind == est::GrabEventKind::kGrab ? 0 : 1);
    event.stamp_ns(named.event.stamp_ns);
    event.tip(xyz(named.event.tip));
    event.bend(named.event.bend_rad);
    message.events().push_back(event);
  }
  return message;
}

}  // namespace panoptes::estimator_app
