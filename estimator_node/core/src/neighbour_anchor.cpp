// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/neighbour_anchor.h"

#include <algorithm>
#include <vector>

#include "panoptes/rigid_fit.h"

namespace panoptes::estimator {

NeighbourAnchor make_anchor(TimeNs stamp_ns, const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                            std::span<const AnchorPoint> others, double radius_m, double horizon_s) {
  NeighbourAnchor anchor;
  anchor.stamp_ns = stamp_ns;
  anchor.position = position;
  std::array<double, kAnchorNeighbours> rank{};
  for (const AnchorPoint& other : others) {
    const double distance = (other.position - position).norm();
    if (distance > radius_m) continue;
    const double r = distance + horizon_s * (other.velocity - velocity).norm();
    if (anchor.count == kAnchorNeighbours && r >= rank[kAnchorNeighbours - 1]) continue;
    // Insertion into the sorted arrays; the last falls off the end when they are full.
    int k = std::min(anchor.count, kAnchorNeighbours - 1);
    for (; k > 0 && rank[k - 1] > r; --k) {
      rank[k] = rank[k - 1];
      anchor.neighbours[k] = anchor.neighbours[k - 1];
    }
    rank[k] = r;
    anchor.neighbours[k] = other;
    anchor.count = std::min(anchor.count + 1, kAnchorNeighbours);
  }
  return anchor;
}

std::optional<CarriedPosition> carried_position(const NeighbourAnchor& anchor,
                                                std::span<const AnchorPoint> now, double trim_above_m) {
  std::vector<Eigen::Vector3d> from, to;
  for (int k = 0; k < anchor.count; ++k) {
    const AnchorPoint& then = anchor.neighbours[k];
    const auto found =
        std::find_if(now.begin(), now.end(), [&](const AnchorPoint& p) { return p.id == then.id; });
    if (found == now.end()) continue;
    from.push_back(then.position);
    to.push_back(found->position);
  }
  CarriedPosition carried;
  auto motion = fit_rigid_transform(from, to, &carried.fit_rms_m);
  // A neighbour that moved against the others (the other leg's marker beside a foot) leaves the
  // fit, the worst first, while more than three are left.
  while (motion && carried.fit_rms_m > trim_above_m && from.size() > 3) {
    std::size_t worst = 0;
    double worst_residual = -1.0;
    for (std::size_t k = 0; k < from.size(); ++k) {
      const double residual = (motion->apply(from[k]) - to[k]).squaredNorm();
      if (residual > worst_residual) {
        worst_residual = residual;
        worst = k;
      }
    }
    from.erase(from.begin() + static_cast<std::ptrdiff_t>(worst));
    to.erase(to.begin() + static_cast<std::ptrdiff_t>(worst));
    motion = fit_rigid_transform(from, to, &carried.fit_rms_m);
  }
  if (!motion) return std::nullopt;  // fewer than three, or collinear: the rotation is undetermined
  carried.position = motion->apply(anchor.position);
  carried.neighbours = static_cast<int>(from.size());
  return carried;
}

}  // namespace panoptes::estimator
