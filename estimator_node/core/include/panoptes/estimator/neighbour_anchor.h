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
  int stood_in = 0;        // of those, how many were unnamed stand-ins (carried_with_stand_ins)
};

// Where the anchor's neighbours found in `now` (by id) carry its position: the rigid motion fitted
// to at least three of them (not collinear), applied to the anchored position. nullopt with fewer.
// While the fit's RMS residual is above `trim_above_m` and more than three are left, the neighbour
// with the largest residual is dropped and the motion fitted again.
std::optional<CarriedPosition> carried_position(
    const NeighbourAnchor& anchor, std::span<const AnchorPoint> now,
    double trim_above_m = std::numeric_limits<double>::infinity());

// Where the anchor's neighbours carried its marker when some of them were lost with it and came
// back as tracks without a name yet (a foot's markers out of every view together): a neighbour
// missing from `now` may be stood in for by one of `stand_ins`, each used once, whose distances
// from the neighbours already placed (found or stood in for) agree with the anchor's within
// `tolerance_m`. The placement with the most neighbours (at least three, one stood in for), then
// the smallest fit residual, carries the position; nullopt when none fits within `max_fit_rms_m`
// RMS, or another placement of as many neighbours within that limit carries it more than
// `agree_m` elsewhere (a symmetric group: which is which is not known), or the search passes
// kMaxStandInPlacements placements.
inline constexpr int kMaxStandInPlacements = 4096;
std::optional<CarriedPosition> carried_with_stand_ins(const NeighbourAnchor& anchor,
                                                      std::span<const AnchorPoint> now,
                                                      std::span<const Eigen::Vector3d> stand_ins,
                                                      double tolerance_m, double max_fit_rms_m,
                                                      double agree_m);

}  // namespace panoptes::estimator
