// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/neighbour_anchor.h"

#include <algorithm>
#include <cmath>
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

namespace {

// The depth-first search of carried_with_stand_ins: neighbour `missing[depth]` is left out or placed
// at each stand-in not used yet whose distances agree with every point placed so far.
class StandInSearch {
 public:
  StandInSearch(const NeighbourAnchor& anchor, std::span<const Eigen::Vector3d> stand_ins, double tolerance_m,
                double max_fit_rms_m, double agree_m)
      : anchor_(anchor),
        stand_ins_(stand_ins),
        tolerance_m_(tolerance_m),
        max_fit_rms_m_(max_fit_rms_m),
        agree_m_(agree_m),
        used_(stand_ins.size(), 0) {}

  void place(const Eigen::Vector3d& then, const Eigen::Vector3d& now) {
    from_.push_back(then);
    to_.push_back(now);
  }
  void add_missing(int k) { missing_.push_back(k); }

  std::optional<CarriedPosition> run() {
    search(0, 0);
    if (overflow_ || !best_ || ambiguous_) return std::nullopt;
    return best_;
  }

 private:
  bool agrees(const Eigen::Vector3d& then, const Eigen::Vector3d& now) const {
    for (std::size_t k = 0; k < from_.size(); ++k)
      if (std::abs((then - from_[k]).norm() - (now - to_[k]).norm()) > tolerance_m_) return false;
    return true;
  }

  void search(std::size_t depth, int stood_in) {
    if (overflow_) return;
    const int reachable = static_cast<int>(from_.size() + missing_.size() - depth);
    if (best_ && reachable < best_->neighbours) return;  // cannot place as many as the best
    if (depth == missing_.size()) {
      evaluate(stood_in);
      return;
    }
    const Eigen::Vector3d& then = anchor_.neighbours[static_cast<std::size_t>(missing_[depth])].position;
    for (std::size_t s = 0; s < stand_ins_.size(); ++s) {
      if (used_[s] || !agrees(then, stand_ins_[s])) continue;
      used_[s] = 1;
      place(then, stand_ins_[s]);
      search(depth + 1, stood_in + 1);
      from_.pop_back();
      to_.pop_back();
      used_[s] = 0;
    }
    search(depth + 1, stood_in);
  }

  void evaluate(int stood_in) {
    if (stood_in == 0 || from_.size() < 3) return;
    if (++placements_ > kMaxStandInPlacements) {
      overflow_ = true;
      return;
    }
    double rms = 0.0;
    const auto motion = fit_rigid_transform(from_, to_, &rms);
    if (!motion || rms > max_fit_rms_m_) return;
    CarriedPosition carried;
    carried.position = motion->apply(anchor_.position);
    carried.fit_rms_m = rms;
    carried.neighbours = static_cast<int>(from_.size());
    carried.stood_in = stood_in;
    if (best_ && carried.neighbours == best_->neighbours) {
      // As many placed: another reading of the same group. Ambiguous when it puts the marker
      // elsewhere, whichever fits better (the ambiguity holds for every smaller placement).
      if ((carried.position - best_->position).norm() > agree_m_) ambiguous_ = true;
      if (carried.fit_rms_m < best_->fit_rms_m) best_ = carried;
      return;
    }
    if (!best_ || carried.neighbours > best_->neighbours) {
      best_ = carried;
      ambiguous_ = false;
    }
  }

  const NeighbourAnchor& anchor_;
  std::span<const Eigen::Vector3d> stand_ins_;
  double tolerance_m_, max_fit_rms_m_, agree_m_;
  std::vector<char> used_;
  std::vector<int> missing_;
  std::vector<Eigen::Vector3d> from_, to_;
  std::optional<CarriedPosition> best_;
  bool ambiguous_ = false;
  bool overflow_ = false;
  int placements_ = 0;
};

}  // namespace

std::optional<CarriedPosition> carried_with_stand_ins(const NeighbourAnchor& anchor,
                                                      std::span<const AnchorPoint> now,
                                                      std::span<const Eigen::Vector3d> stand_ins,
                                                      double tolerance_m, double max_fit_rms_m,
                                                      double agree_m) {
  if (stand_ins.empty()) return std::nullopt;
  StandInSearch search(anchor, stand_ins, tolerance_m, max_fit_rms_m, agree_m);
  for (int k = 0; k < anchor.count; ++k) {
    const AnchorPoint& then = anchor.neighbours[static_cast<std::size_t>(k)];
    const auto found =
        std::find_if(now.begin(), now.end(), [&](const AnchorPoint& p) { return p.id == then.id; });
    if (found != now.end())
      search.place(then.position, found->position);
    else
      search.add_missing(k);
  }
  return search.run();
}

}  // namespace panoptes::estimator
