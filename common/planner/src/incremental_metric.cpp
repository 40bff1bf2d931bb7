// SPDX-License-Identifier: Apache-2.0
#include "panoptes/planner/incremental_metric.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace panoptes::planner {

namespace {

constexpr std::size_t kTableSize = 256;  // > 2 × the planes a point groups (64 words of 64)

std::size_t table_hash(std::uint64_t mask) {
  return static_cast<std::size_t>((mask * 0x9E3779B97F4A7C15ULL) >> 56U) & (kTableSize - 1);
}

// trace(A⁻¹) of a symmetric 3 × 3 matrix given as its upper triangle (xx, xy, xz, yy, yz, zz): its
// principal cofactors over its determinant.
double trace_of_inverse(const std::array<double, 6>& a) {
  const double c00 = a[3] * a[5] - a[4] * a[4];
  const double c11 = a[0] * a[5] - a[2] * a[2];
  const double c22 = a[0] * a[3] - a[1] * a[1];
  const double det = a[0] * c00 - a[1] * (a[1] * a[5] - a[2] * a[4]) + a[2] * (a[1] * a[4] - a[2] * a[3]);
  return (c00 + c11 + c22) / det;
}

}  // namespace

IncrementalMetric::IncrementalMetric(const SampleSet& samples, std::span<const Box> obstacles,
                                     const MetricOptions& options, std::size_t slots, Objective objective,
                                     const TrackerModel& tracker)
    : samples_(samples),
      obstacles_(obstacles.begin(), obstacles.end()),
      options_(options),
      objective_(objective),
      tracker_(tracker),
      slots_(slots) {
  if (slots == 0 || slots > 64)
    throw std::invalid_argument("planner: an incremental metric holds 1 to 64 cameras, not " +
                                std::to_string(slots));
  words_ = (samples.normals.size() + 63) / 64;
  min_angle_cos_ = std::cos(std::clamp(options.min_triangulation_deg, 0.0, 90.0) * std::numbers::pi / 180.0);
  const std::size_t points = samples.points.size();
  views_.assign(points * slots_, View{});
  facing_.assign(points * slots_ * words_, 0);
  wide_.assign(points * slots_, 0);
  table_masks_.assign(kTableSize, 0);
  table_counts_.assign(kTableSize, 0);
  point_value_.resize(points);
  for (std::size_t i = 0; i < points; ++i) point_value_[i] = point_value(i);
  value_ = aggregate_points();
}

double IncrementalMetric::place(std::size_t slot, const PlannedCamera& camera) {
  return update(slot, &camera);
}

double IncrementalMetric::remove(std::size_t slot) {
  return update(slot, nullptr);
}

double IncrementalMetric::update(std::size_t slot, const PlannedCamera* camera) {
  if (slot >= slots_) throw std::out_of_range("planner: incremental metric slot out of range");
  const std::size_t points = samples_.points.size();
  can_undo_ = true;
  undo_slot_ = slot;
  undo_views_.resize(points);
  undo_facing_.resize(points * words_);
  undo_wide_.resize(points);
  undo_point_value_ = point_value_;
  undo_value_ = value_;
  for (std::size_t i = 0; i < points; ++i) {
    undo_views_[i] = view(i, slot);
    std::copy_n(facing(i, slot), words_, undo_facing_.begin() + static_cast<std::ptrdiff_t>(i * words_));
    undo_wide_[i] = wide_[i * slots_ + slot];
    const bool was_seen = view(i, slot).seen;
    compute_view(i, slot, camera);
    update_pairs(i, slot);
    if (was_seen || view(i, slot).seen) point_value_[i] = point_value(i);
  }
  value_ = aggregate_points();
  return value_;
}

void IncrementalMetric::undo() {
  if (!can_undo_) return;
  can_undo_ = false;
  const std::size_t slot = undo_slot_;
  for (std::size_t i = 0; i < samples_.points.size(); ++i) {
    view(i, slot) = undo_views_[i];
    std::copy_n(undo_facing_.begin() + static_cast<std::ptrdiff_t>(i * words_), words_, facing(i, slot));
    const Mask pairs = undo_wide_[i];
    wide_[i * slots_ + slot] = pairs;
    for (std::size_t d = 0; d < slots_; ++d) {
      if (d == slot) continue;
      Mask& other = wide_[i * slots_ + d];
      other = (pairs >> d & 1U) != 0 ? (other | Mask{1} << slot) : (other & ~(Mask{1} << slot));
    }
  }
  point_value_.swap(undo_point_value_);
  value_ = undo_value_;
}

// Visibility as in metric.cpp: in front, within the depth range, in the image, not behind an
// obstacle; then which occluder planes leave the camera visible.
void IncrementalMetric::compute_view(std::size_t point, std::size_t slot, const PlannedCamera* camera) {
  View& v = view(point, slot);
  std::uint64_t* flags = facing(point, slot);
  v.seen = false;
  std::fill_n(flags, words_, 0);
  if (camera == nullptr) return;
  const Eigen::Vector3d& p = samples_.points[point];
  const Eigen::Vector3d p_cam = camera->model.T_cam_world().apply(p);
  const double distance = p_cam.norm();
  if (p_cam.z() <= 0.0 || distance < camera->min_depth_m || distance > camera->max_depth_m) return;
  Eigen::Matrix<double, 2, 3> J;
  const auto pixel = camera->model.project(p, &J);
  if (!pixel || !camera->model.in_image(*pixel)) return;
  const Eigen::Vector3d centre = camera->model.center_world();
  for (const Box& box : obstacles_)
    if (box.blocks(p, centre)) return;
  const double sigma = options_.pixel_sigma;
  const auto& K = camera->model.intrinsics();
  v.seen = true;
  v.to_camera = (centre - p) / distance;
  v.width_m = sigma * p_cam.z() / (0.5 * (K.fx + K.fy));
  const Eigen::Matrix3d information = J.transpose() * J / (sigma * sigma);
  v.information = {information(0, 0), information(0, 1), information(0, 2),
                   information(1, 1), information(1, 2), information(2, 2)};
  for (std::size_t j = 0; j < samples_.normals.size(); ++j)
    if (samples_.normals[j].dot(v.to_camera) > samples_.facing_cos)
      flags[j / 64] |= std::uint64_t{1} << (j % 64);
}

// Which other cameras see `point` from far enough (as lines) from `slot` to triangulate with it.
void IncrementalMetric::update_pairs(std::size_t point, std::size_t slot) {
  const View& v = view(point, slot);
  Mask pairs = 0;
  for (std::size_t d = 0; d < slots_; ++d) {
    if (d == slot) continue;
    const View& other = view(point, d);
    Mask& other_pairs = wide_[point * slots_ + d];
    if (v.seen && other.seen && std::abs(v.to_camera.dot(other.to_camera)) <= min_angle_cos_) {
      pairs |= Mask{1} << d;
      other_pairs |= Mask{1} << slot;
    } else {
      other_pairs &= ~(Mask{1} << slot);
    }
  }
  wide_[point * slots_ + slot] = pairs;
}

// The rule of metric.cpp: cameras none of which are far enough apart count as the first of them.
IncrementalMetric::Mask IncrementalMetric::effective(std::size_t point, Mask mask) const {
  if ((mask & (mask - 1)) == 0 || options_.min_triangulation_deg <= 0.0) return mask;  // < 2 cameras
  for (Mask rest = mask; rest != 0; rest &= rest - 1)
    if ((wide_[point * slots_ + static_cast<std::size_t>(std::countr_zero(rest))] & mask) != 0) return mask;
  return mask & (~mask + 1);
}

// The point's share of the objective: U(P) (eq. 4.5), or the mean squared tracker cost over its
// planes; the planes grouped by the set of cameras they leave visible.
double IncrementalMetric::point_value(std::size_t point) {
  Mask seen = 0;
  for (std::size_t c = 0; c < slots_; ++c)
    if (view(point, c).seen) seen |= Mask{1} << c;
  seen = effective(point, seen);  // as metric.cpp: the planes hide cameras of the effective set
  const std::size_t planes = samples_.normals.size();
  if (planes == 0) return mask_value(point, seen);
  table_used_.clear();
  std::array<Mask, 64> masks{};
  for (std::size_t w = 0; w < words_; ++w) {
    masks.fill(0);
    for (Mask rest = seen; rest != 0; rest &= rest - 1) {
      const auto c = static_cast<std::size_t>(std::countr_zero(rest));
      for (std::uint64_t bits = facing(point, c)[w]; bits != 0; bits &= bits - 1)
        masks[static_cast<std::size_t>(std::countr_zero(bits))] |= Mask{1} << c;
    }
    const std::size_t in_word = std::min<std::size_t>(64, planes - w * 64);
    for (std::size_t j = 0; j < in_word; ++j) {
      std::size_t h = table_hash(masks[j]);
      while (table_counts_[h] != 0 && table_masks_[h] != masks[j]) h = (h + 1) & (kTableSize - 1);
      if (table_counts_[h] == 0) {
        table_masks_[h] = masks[j];
        table_used_.push_back(h);
      }
      ++table_counts_[h];
    }
  }
  double sum = 0.0, worst = 0.0;
  const bool squared = options_.over_planes == Norm::kRms && objective_ == Objective::kQuality;
  for (const std::size_t h : table_used_) {
    const double u = mask_value(point, effective(point, table_masks_[h]));
    const double count = table_counts_[h];
    table_counts_[h] = 0;
    worst = std::max(worst, u);
    sum += count * (squared ? u * u : u);
  }
  if (objective_ == Objective::kTrackerRmse) return sum / static_cast<double>(planes);  // a mean of squares
  switch (options_.over_planes) {
    case Norm::kMax:
      return worst;
    case Norm::kMean:
      return sum / static_cast<double>(planes);
    case Norm::kRms:
      break;
  }
  return std::sqrt(sum / static_cast<double>(planes));
}

double IncrementalMetric::mask_value(std::size_t point, Mask mask) {
  if (objective_ == Objective::kTrackerRmse) return tracker_cost2(point, mask);
  return options_.resolution == ResolutionModel::kPyramid ? pyramid_uncertainty(point, mask)
                                                          : covariance_uncertainty(point, mask);
}

// The information of the cameras in `mask` with the prior of `unseen_m` in every direction, as its
// upper triangle: xx, xy, xz, yy, yz, zz.
std::array<double, 6> IncrementalMetric::information(std::size_t point, Mask mask) const {
  const double prior = 1.0 / (options_.unseen_m * options_.unseen_m);
  std::array<double, 6> a{prior, 0.0, 0.0, prior, 0.0, prior};
  for (Mask rest = mask; rest != 0; rest &= rest - 1) {
    const std::array<double, 6>& add =
        view(point, static_cast<std::size_t>(std::countr_zero(rest))).information;
    for (std::size_t k = 0; k < 6; ++k) a[k] += add[k];
  }
  return a;
}

// The tracker objective's squared cost of a sample seen by the cameras in `mask`.
double IncrementalMetric::tracker_cost2(std::size_t point, Mask mask) const {
  const int cameras = std::popcount(mask);
  return tracker_sample_cost2(cameras, cameras >= 2 ? trace_of_inverse(information(point, mask)) : 0.0,
                              tracker_);
}

double IncrementalMetric::covariance_uncertainty(std::size_t point, Mask mask) {
  const std::array<double, 6> a = information(point, mask);
  if (options_.over_directions == Norm::kRms) return std::sqrt(std::max(0.0, trace_of_inverse(a) / 3.0));
  Eigen::Matrix3d information;
  information << a[0], a[1], a[2], a[1], a[3], a[4], a[2], a[4], a[5];
  const Eigen::Matrix3d covariance = information.inverse();
  if (options_.over_directions == Norm::kMax)
    return std::sqrt(
        std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
                          .eigenvalues()
                          .maxCoeff()));
  double sum = 0.0;
  for (const Eigen::Vector3d& d : samples_.directions) sum += std::sqrt(d.dot(covariance * d));
  return samples_.directions.empty() ? 0.0 : sum / static_cast<double>(samples_.directions.size());
}

// Eq. 4.2: per direction the shortest extent of any camera's ray pyramid, then norm_k.
double IncrementalMetric::pyramid_uncertainty(std::size_t point, Mask mask) {
  const double huge = options_.unseen_m;
  lengths_.assign(samples_.directions.size(), huge);
  for (Mask rest = mask; rest != 0; rest &= rest - 1) {
    const View& v = view(point, static_cast<std::size_t>(std::countr_zero(rest)));
    for (std::size_t k = 0; k < lengths_.size(); ++k) {
      const double cosine = samples_.directions[k].dot(v.to_camera);
      const double sine = std::sqrt(std::max(0.0, 1.0 - cosine * cosine));
      if (sine * huge > v.width_m) lengths_[k] = std::min(lengths_[k], v.width_m / sine);
    }
  }
  return aggregate(lengths_, {}, options_.over_directions);
}

double IncrementalMetric::aggregate_points() const {
  if (objective_ == Objective::kTrackerRmse)  // as predict_tracking aggregates it
    return std::sqrt(aggregate(point_value_, samples_.weights, Norm::kMean));
  return aggregate(point_value_, samples_.weights, options_.over_points);
}

}  // namespace panoptes::planner
