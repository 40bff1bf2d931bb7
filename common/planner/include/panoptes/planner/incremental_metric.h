// SPDX-License-Identifier: Apache-2.0
// The objective of metric.h — the quality q, or the predicted tracker RMSE with gaps charged — for
// a configuration that changes one camera at a time, as the optimiser's moves do. Every camera's view of
// every sample point (visibility, ray, information, which occluder planes face it) is kept, so a move
// recomputes only the moved camera's views and the points it saw before or sees now; a point's occluder
// planes are grouped by the set of cameras they leave visible, and each set's uncertainty (or tracker cost)
// is computed once. Same figure as evaluate(...).quality or predict_tracking(...).rmse_gaps_charged_m up to
// rounding (tests/unit/planner/test_incremental_metric.cpp); one thread. docs/planner.md, "The optimiser".
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "panoptes/planner/metric.h"

namespace panoptes::planner {

class IncrementalMetric {
 public:
  // `slots` cameras at most (≤ 64), all empty at first. `samples` must outlive the object.
  // `tracker` is used by Objective::kTrackerRmse only.
  IncrementalMetric(const SampleSet& samples, std::span<const Box> obstacles, const MetricOptions& options,
                    std::size_t slots, Objective objective = Objective::kQuality,
                    const TrackerModel& tracker = {});

  // Puts `camera` in `slot` (replacing what was there) and returns the objective's new value.
  double place(std::size_t slot, const PlannedCamera& camera);
  // Empties `slot` and returns the objective's new value.
  double remove(std::size_t slot);
  // Reverts the last place() or remove() (one level).
  void undo();

  // q (metres) or the predicted tracker RMSE with gaps charged (metres): lower is better.
  double value() const { return value_; }
  Objective objective() const { return objective_; }
  std::size_t slots() const { return slots_; }

 private:
  using Mask = std::uint64_t;
  // One camera's view of one sample point.
  struct View {
    bool seen = false;
    Eigen::Vector3d to_camera = Eigen::Vector3d::Zero();  // unit, from the point to the camera
    double width_m = 0;                                   // ray pyramid half-width at the point
    std::array<double, 6> information{};                  // JᵀJ / σ²: xx, xy, xz, yy, yz, zz
  };

  double update(std::size_t slot, const PlannedCamera* camera);
  void compute_view(std::size_t point, std::size_t slot, const PlannedCamera* camera);
  void update_pairs(std::size_t point, std::size_t slot);
  double point_value(std::size_t point);
  Mask effective(std::size_t point, Mask mask) const;
  double mask_value(std::size_t point, Mask mask);
  std::array<double, 6> information(std::size_t point, Mask mask) const;
  double tracker_cost2(std::size_t point, Mask mask) const;
  double covariance_uncertainty(std::size_t point, Mask mask);
  double pyramid_uncertainty(std::size_t point, Mask mask);
  double aggregate_points() const;

  View& view(std::size_t point, std::size_t slot) { return views_[point * slots_ + slot]; }
  const View& view(std::size_t point, std::size_t slot) const { return views_[point * slots_ + slot]; }
  std::uint64_t* facing(std::size_t point, std::size_t slot) {
    return facing_.data() + (point * slots_ + slot) * words_;
  }

  const SampleSet& samples_;
  std::vector<Box> obstacles_;
  MetricOptions options_;
  Objective objective_ = Objective::kQuality;
  TrackerModel tracker_;
  std::size_t slots_ = 0;
  std::size_t words_ = 0;  // 64-bit words of occluder-plane flags per view
  double min_angle_cos_ = 1.0;

  std::vector<View> views_;            // by point, then slot
  std::vector<std::uint64_t> facing_;  // bit j: occluder plane j leaves the camera visible
  std::vector<Mask> wide_;             // by point, then slot: cameras far enough apart to triangulate
  // By point: U(P) for q; for the tracker objective the mean over its planes of the squared cost.
  std::vector<double> point_value_;
  double value_ = 0;

  // What undo() restores.
  bool can_undo_ = false;
  std::size_t undo_slot_ = 0;
  std::vector<View> undo_views_;
  std::vector<std::uint64_t> undo_facing_;
  std::vector<Mask> undo_wide_;
  std::vector<double> undo_point_value_;
  double undo_value_ = 0;

  // Scratch space of point_value(): distinct camera sets among a point's planes.
  std::vector<Mask> table_masks_;
  std::vector<int> table_counts_;
  std::vector<std::size_t> table_used_;
  std::vector<double> lengths_;
};

}  // namespace panoptes::planner
