// SPDX-License-Identifier: Apache-2.0
// Where a lost marker's neighbours have carried it. An anchor keeps a marker's position and those of
// its nearest neighbours at one instant (its last two-camera update); later, the least-squares rigid
// motion of the neighbours still followed, applied to the anchored position, predicts where the
// marker is now: markers on one limb or one side of a pelvis move nearly rigidly together for the
// second a marker may be out of view. Used by the tracker's reacquisition by neighbours
// (docs/estimator.md, "Reacquisition by neighbours").
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>

#include <Eigen/Core>

#include "panoptes/time.h"

namespace panoptes::estimator {

inline constexpr int kAnchorNeighbours = 6;

// A track's point: a neighbour's position (and velocity) at the anchor's instant, or now.
struct AnchorPoint {
  std::int64_t id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
};

struct NeighbourAnchor {
  TimeNs stamp_ns = 0;  // the instant anchored; 0: none
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int count = 0;  // neighbours kept: the first `count`, nearest first
  std::array<AnchorPoint, kAnchorNeighbours> neighbours{};
};

// The anchor of a marker at `position` moving at `velocity`, at `stamp_ns`: the kAnchorNeighbours
// of `others` within `radius_m` of it that are nearest by distance plus `horizon_s` times their
// difference in velocity. With a horizon, a marker of another limb passing close by (the other foot
// across a stride, metres per second faster) ranks behind its own limb's markers farther off.
NeighbourAnchor make_anchor(TimeNs stamp_ns, const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                            std::span<const AnchorPoint> others, double radius_m, double horizon_s);

struct CarriedPosition {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double fit_rms_m = 0.0;  // the neighbours' RMS residual under the fitted motion
  int neighbours = 0;      // how many were found in `now` and used
};

// Where the anchor's neighbours found in `now` (by id) carry its position: the rigid motion fitted
// to at least three of them (not collinear), applied to the anchored position. nullopt with fewer.
// While the fit's RMS residual is above `trim_above_m` and more than three are left, the neighbour
// with the largest residual is dropped and the motion fitted again.
std::optional<CarriedPosition> carried_position(
    const NeighbourAnchor& anchor, std::span<const AnchorPoint> now,
    double trim_above_m = std::numeric_limits<double>::infinity());

}  // namespace panoptes::estimator
