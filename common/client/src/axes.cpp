// SPDX-License-Identifier: Apache-2.0
// The client's up axis (ClientOptions::up_axis, docs/clients.md "Axis conventions"): the wire is
// z-up; each frame and chain update is turned once, after its checks, before anyone sees it.
#include <cstdlib>
#include <string>

#include "conversion.h"

namespace panoptes::client::detail {

UpAxis choose_up_axis(const std::string& option) {
  if (!option.empty()) return parse_up_axis(option, "ClientOptions::up_axis");
  const char* variable = std::getenv("PANOPTES_UP_AXIS");
  if (variable == nullptr || *variable == '\0') return UpAxis::kZ;
  return parse_up_axis(variable, "PANOPTES_UP_AXIS");
}

namespace {

void turn_body(RigidBody& body, UpAxis axis) {
  body.position = vector_to_up_axis(axis, body.position);
  body.orientation = orientation_to_up_axis(axis, body.orientation);
  body.linear_velocity = vector_to_up_axis(axis, body.linear_velocity);
  body.angular_velocity = vector_to_up_axis(axis, body.angular_velocity);
  const auto position_sigma = sigmas_to_up_axis(axis, {body.sigma[0], body.sigma[1], body.sigma[2]});
  const auto rotation_sigma = sigmas_to_up_axis(axis, {body.sigma[3], body.sigma[4], body.sigma[5]});
  body.sigma = {position_sigma[0], position_sigma[1], position_sigma[2],
                rotation_sigma[0], rotation_sigma[1], rotation_sigma[2]};
}

}  // namespace

void turn_to_up_axis(Frame& frame, UpAxis axis) {
  if (axis == UpAxis::kZ) return;
  for (auto& marker : frame.markers) {
    marker.position = vector_to_up_axis(axis, marker.position);
    marker.velocity = vector_to_up_axis(axis, marker.velocity);
    marker.covariance = covariance_to_up_axis(axis, marker.covariance);
  }
  for (auto& body : frame.bodies) turn_body(body, axis);
}

void turn_to_up_axis(ChainUpdate& update, UpAxis axis) {
  if (axis == UpAxis::kZ) return;
  for (auto& chain : update.chains) {
    for (auto& marker : chain.markers) marker = vector_to_up_axis(axis, marker);
    chain.tip = vector_to_up_axis(axis, chain.tip);
    chain.predicted_tip = vector_to_up_axis(axis, chain.predicted_tip);
  }
  for (auto& event : update.events) event.tip = vector_to_up_axis(axis, event.tip);
}

}  // namespace panoptes::client::detail
