// SPDX-License-Identifier: Apache-2.0
// An articulated marker chain (a finger with markers on its joints, seed 000 §6.4.3): the plain
// definition read from the bodies file (`type: chain`) and its validation. The filter that tracks
// it lives in the estimator core (estimator/chain.h).
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace panoptes {

// Joints bend about the chain's own z axis: the markers lie in the chain's xy-plane (seed 000
// §6.4.4, Fig. 6.22), marker 0 (the base) at the origin and marker 1 on the x axis.
inline constexpr int kMinChainMarkers = 3;
inline constexpr int kMaxChainMarkers = 5;
inline constexpr double kMinChainLinkM = 0.005;
inline constexpr double kMaxChainLinkM = 0.5;

struct JointLimits {
  double min_rad = -0.3;
  double max_rad = 1.8;
};

struct ChainDefinition {
  std::string name;
  std::vector<double> link_lengths_m;     // between consecutive markers, base first
  std::vector<JointLimits> joint_limits;  // one per inner marker (link_lengths_m.size() - 1)
  // The "hot spot" (seed 000 §6.4.3) in the last link's frame: x along the link from the last
  // marker, y towards the side the joints bend to.
  Eigen::Vector3d tip_offset_m = Eigen::Vector3d::Zero();

  int marker_count() const { return static_cast<int>(link_lengths_m.size()) + 1; }
  int joint_count() const { return static_cast<int>(link_lengths_m.size()) - 1; }
};

// Why a definition cannot describe a chain (the first problem found, naming the field), or nullopt.
inline std::optional<std::string> chain_definition_error(const ChainDefinition& chain) {
  const int markers = chain.marker_count();
  if (markers < kMinChainMarkers || markers > kMaxChainMarkers)
    return "links: a chain has " + std::to_string(kMinChainMarkers) + " to " +
           std::to_string(kMaxChainMarkers) + " markers, i.e. " + std::to_string(kMinChainMarkers - 1) +
           " to " + std::to_string(kMaxChainMarkers - 1) + " link lengths; got " +
           std::to_string(chain.link_lengths_m.size());
  for (std::size_t i = 0; i < chain.link_lengths_m.size(); ++i) {
    const double length = chain.link_lengths_m[i];
    if (!std::isfinite(length) || length < kMinChainLinkM || length > kMaxChainLinkM)
      return "links[" + std::to_string(i) + "]: a link length must lie in [" +
             std::to_string(kMinChainLinkM) + ", " + std::to_string(kMaxChainLinkM) + "] m; got " +
             std::to_string(length);
  }
  if (static_cast<int>(chain.joint_limits.size()) != chain.joint_count())
    return "joint_limits: expected " + std::to_string(chain.joint_count()) +
           " [min, max] pairs (one per inner " + "marker); got " + std::to_string(chain.joint_limits.size());
  for (std::size_t j = 0; j < chain.joint_limits.size(); ++j) {
    const JointLimits& limits = chain.joint_limits[j];
    const bool finite = std::isfinite(limits.min_rad) && std::isfinite(limits.max_rad);
    // Past ±170° a link folds back onto its neighbour: the markers would collide.
    if (!finite || limits.min_rad >= limits.max_rad || limits.min_rad < -2.97 || limits.max_rad > 2.97)
      return "joint_limits[" + std::to_string(j) + "]: expected min < max within ±2.97 rad; got [" +
             std::to_string(limits.min_rad) + ", " + std::to_string(limits.max_rad) + "]";
  }
  if (!chain.tip_offset_m.allFinite() || chain.tip_offset_m.norm() > kMaxChainLinkM)
    return "tip_offset: must be finite and shorter than " + std::to_string(kMaxChainLinkM) + " m";
  return std::nullopt;
}

}  // namespace panoptes
