// SPDX-License-Identifier: Apache-2.0
// The world's up axis as applications see it (docs/contracts.md, "Axis conventions"). Panoptes
// computes, publishes and records in one world frame, z up (as ROS REP-103); an application that
// wants y up (as Motive and Vicon users often choose) gets every world quantity turned by one
// proper rotation, at the client library and in the exports, never on the wire.
#pragma once

#include <array>
#include <string>
#include <string_view>

namespace panoptes {

enum class UpAxis {
  kZ,  // Panoptes' world: x, y on the floor, z up (the default)
  kY,  // y up: (x, y, z) -> (x, z, -y), a rotation of -90 degrees about x (right-handed kept)
};

// "z" or "y" (any case) as an UpAxis; a ConfigError naming `source` and the text otherwise
// ("--up-axis=up: not an up axis (z or y)").
UpAxis parse_up_axis(std::string_view text, const std::string& source);

// "z" or "y".
const char* up_axis_name(UpAxis axis);

// A world point, velocity or direction from z-up into `axis`.
std::array<double, 3> vector_to_up_axis(UpAxis axis, const std::array<double, 3>& v);

// A body -> world orientation (x, y, z, w) into `axis`: the world rotation before it, so the body
// frame (and a body's marker layout) stays as defined.
std::array<double, 4> orientation_to_up_axis(UpAxis axis, const std::array<double, 4>& q);

// A world covariance (xx xy xz yy yz zz) into `axis`: R C R^T.
std::array<double, 6> covariance_to_up_axis(UpAxis axis, const std::array<double, 6>& c);

// Per-axis world standard deviations (x, y, z) into `axis`: the axes swap, the signs do not matter.
std::array<double, 3> sigmas_to_up_axis(UpAxis axis, const std::array<double, 3>& s);

}  // namespace panoptes
