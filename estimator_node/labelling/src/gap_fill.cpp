// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/gap_fill.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include <Eigen/Cholesky>

#include "panoptes/interpolation.h"
#include "panoptes/rigid_fit.h"

namespace panoptes::labelling {

namespace {

// Time runs in frames here: the gap's last sample before is at 0, the first after at `span`.
Eigen::Vector3d hermite(const Eigen::Vector3d& p0, const Eigen::Vector3d& m0, const Eigen::Vector3d& p1,
                        const Eigen::Vector3d& m1, double span, double at) {
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) out[i] = cubic_hermite(0.0, span, p0[i], m0[i], p1[i], m1[i], at);
  return out;
}

struct MarkerInModel {
  const SegmentLayout* segment = nullptr;
  std::size_t index = 0;
};

std::optional<MarkerInModel> find_marker(const SubjectModel& model, const std::string& name) {
  for (const auto& segment : model.segments) {
    for (std::size_t m = 0; m < segment.markers.size(); ++m) {
      if (segment.markers[m].name == name) return MarkerInModel{&segment, m};
    }
  }
  return std::nullopt;
}

std::vector<Eigen::Vector3d> positions_at(const MarkerSamples& samples,
                                          const std::vector<std::size_t>& columns, std::size_t f) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(columns.size());
  for (std::size_t c : columns) points.push_back(samples.position(f, c));
  return points;
}

// Of the candidate donors, the subset of >= 3 whose rigid motion from the frame before the gap to
// the frame after it carries the marker nearest to where it is seen after the gap (markers on soft
// tissue or across a joint are left out; Gait2392's midfoot markers move 28 mm against the toes).
std::vector<std::size_t> steadiest_donors(const MarkerSamples& samples, const Gap& gap,
                                          const std::vector<std::size_t>& candidates) {
  if (candidates.size() <= 3 || candidates.size() > 12) return candidates;
  std::vector<std::size_t> best = candidates;
  double best_error = std::numeric_limits<double>::infinity();
  for (unsigned subset = 0; subset < (1U << candidates.size()); ++subset) {
    std::vector<std::size_t> donors;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      if ((subset >> i) & 1U) donors.push_back(candidates[i]);
    }
    if (donors.size() < 3) continue;
    const auto T = fit_rigid_transform(positions_at(samples, donors, gap.first - 1),
                                       positions_at(samples, donors, gap.last));
    if (!T) continue;
    const double error =
        (T->apply(samples.position(gap.first - 1, gap.marker)) - samples.position(gap.last, gap.marker))
            .norm();
    if (error < best_error) {
      best_error = error;
      best = std::move(donors);
    }
  }
  return best;
}

// The marker in the frame of two donors: its distance along the axis a -> b and from it.
Eigen::Vector2d along_and_off(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d axis = (b - a).normalized();
  const double along = (p - a).dot(axis);
  return {along, (p - a - along * axis).norm()};
}

// A segment with two donors (three tracked markers, one missing) fixes the marker's distances to
// them but not its turn about their axis: the distances along and off the axis are blended from
// the frames either side, the turn taken from the spline fill.
std::vector<Eigen::Vector3d> two_donor_fill(const MarkerSamples& samples, const Gap& gap, std::size_t a,
                                            std::size_t b) {
  const std::size_t before = gap.first - 1;
  const Eigen::Vector2d r0 = along_and_off(samples.position(before, a), samples.position(before, b),
                                           samples.position(before, gap.marker));
  const Eigen::Vector2d r1 = along_and_off(samples.position(gap.last, a), samples.position(gap.last, b),
                                           samples.position(gap.last, gap.marker));
  const auto spline = spline_fill(samples, gap);
  const double span = static_cast<double>(gap.last - gap.first + 1);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t f = gap.first; f < gap.last; ++f) {
    const Eigen::Vector3d& pa = samples.position(f, a);
    const Eigen::Vector3d axis = (samples.position(f, b) - pa).normalized();
    const Eigen::Vector3d guess = spline[f - gap.first] - pa;
    const Eigen::Vector3d off = guess - guess.dot(axis) * axis;
    const double w = static_cast<double>(f - before) / span;
    const Eigen::Vector2d r = (1.0 - w) * r0 + w * r1;
    out.push_back(off.norm() > 1e-9 ? Eigen::Vector3d(pa + r.x() * axis + r.y() * off.normalized())
                                    : spline[f - gap.first]);
  }
  return out;
}

// The markers seen in every frame from the one before the gap to the one after it (the pattern
// fill's donors), and the frames where they and the gap's marker are all seen (its training set).
// Where other markers have gaps too, few frames show them all: donors are dropped, the one missing
// from most of the marker's frames first, until the training set holds `wanted` frames.
struct PatternData {
  std::vector<std::size_t> columns;  // the gap's marker first, then the donors
  std::vector<std::size_t> frames;
};

PatternData pattern_data(const MarkerSamples& samples, const Gap& gap, std::size_t wanted) {
  PatternData data;
  data.columns.push_back(gap.marker);
  for (std::size_t c = 0; c < samples.point_count(); ++c) {
    bool seen = c != gap.marker;
    for (std::size_t f = gap.first - 1; f <= gap.last && seen; ++f) seen = samples.is_valid(f, c);
    if (seen) data.columns.push_back(c);
  }
  std::vector<std::size_t> marker_frames;
  for (std::size_t f = 0; f < samples.frame_count(); ++f) {
    if (samples.is_valid(f, gap.marker)) marker_frames.push_back(f);
  }
  wanted = std::min(wanted, marker_frames.size());
  while (true) {
    data.frames.clear();
    std::vector<std::size_t> missing(data.columns.size(), 0);
    for (std::size_t f : marker_frames) {
      bool seen = true;
      for (std::size_t j = 1; j < data.columns.size(); ++j) {
        if (!samples.is_valid(f, data.columns[j])) {
          seen = false;
          ++missing[j];
        }
      }
      if (seen) data.frames.push_back(f);
    }
    if (data.frames.size() >= wanted || data.columns.size() <= 4) return data;
    const auto worst = std::max_element(missing.begin() + 1, missing.end()) - missing.begin();
    data.columns.erase(data.columns.begin() + worst);
  }
}

// Each column's weight: exp(-(d / weight_distance_m)^2) of its marker's mean distance d to the
// gap's marker over the training frames (the gap's marker itself: 1), so that the principal
// components describe the marker's neighbourhood first.
Eigen::VectorXd pattern_weights(const MarkerSamples& samples, const PatternData& data,
                                double weight_distance_m) {
  Eigen::VectorXd weights(3 * data.columns.size());
  for (std::size_t j = 0; j < data.columns.size(); ++j) {
    double distance = 0.0;
    for (std::size_t f : data.frames)
      distance += (samples.position(f, data.columns[j]) - samples.position(f, data.columns[0])).norm();
    distance /= static_cast<double>(data.frames.size());
    const double ratio = distance / weight_distance_m;
    weights.segment<3>(static_cast<Eigen::Index>(3 * j)).setConstant(std::exp(-ratio * ratio));
  }
  return weights;
}

void add(FillCount& count, const Gap& gap) {
  ++count.gaps;
  count.frames += gap.last - gap.first;
}

}  // namespace

std::vector<Gap> find_gaps(const MarkerSamples& samples, std::vector<Gap>* open_end) {
  std::vector<Gap> gaps;
  const std::size_t frames = samples.frame_count();
  for (std::size_t m = 0; m < samples.point_count(); ++m) {
    std::size_t f = 0;
    while (f < frames) {
      if (samples.is_valid(f, m)) {
        ++f;
        continue;
      }
      Gap gap{m, f, f};
      while (gap.last < frames && !samples.is_valid(gap.last, m)) ++gap.last;
      f = gap.last;
      const bool interior = gap.first > 0 && gap.last < frames;
      if (interior) {
        gaps.push_back(gap);
      } else if (open_end != nullptr && gap.last - gap.first < frames) {
        open_end->push_back(gap);
      }
    }
  }
  return gaps;
}

std::vector<Eigen::Vector3d> linear_fill(const MarkerSamples& samples, const Gap& gap) {
  const Eigen::Vector3d& before = samples.position(gap.first - 1, gap.marker);
  const Eigen::Vector3d& after = samples.position(gap.last, gap.marker);
  const double span = static_cast<double>(gap.last - gap.first + 1);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t f = gap.first; f < gap.last; ++f)
    out.push_back(before + (after - before) * (static_cast<double>(f - gap.first + 1) / span));
  return out;
}

std::vector<Eigen::Vector3d> spline_fill(const MarkerSamples& samples, const Gap& gap) {
  const std::size_t m = gap.marker;
  const Eigen::Vector3d& p0 = samples.position(gap.first - 1, m);
  const Eigen::Vector3d& p1 = samples.position(gap.last, m);
  const double span = static_cast<double>(gap.last - gap.first + 1);
  const Eigen::Vector3d chord = (p1 - p0) / span;
  const bool before = gap.first >= 2 && samples.is_valid(gap.first - 2, m);
  const bool after = gap.last + 1 < samples.frame_count() && samples.is_valid(gap.last + 1, m);
  const Eigen::Vector3d m0 = before ? Eigen::Vector3d(p0 - samples.position(gap.first - 2, m)) : chord;
  const Eigen::Vector3d m1 = after ? Eigen::Vector3d(samples.position(gap.last + 1, m) - p1) : chord;
  std::vector<Eigen::Vector3d> out;
  for (std::size_t f = gap.first; f < gap.last; ++f)
    out.push_back(hermite(p0, m0, p1, m1, span, static_cast<double>(f - gap.first + 1)));
  return out;
}

std::optional<std::vector<Eigen::Vector3d>> relational_fill(const SubjectModel& model,
                                                            const MarkerSamples& samples, const Gap& gap) {
  const auto marker = find_marker(model, samples.names[gap.marker]);
  if (!marker) return std::nullopt;
  // Donors: the segment's other tracked markers seen from the frame before the gap to the one after.
  std::vector<std::size_t> donors;
  for (std::size_t k = 0; k < marker->segment->markers.size(); ++k) {
    const ModelMarker& other = marker->segment->markers[k];
    if (k == marker->index || other.calibration_only) continue;
    for (std::size_t c = 0; c < samples.point_count(); ++c) {
      if (samples.names[c] != other.name) continue;
      bool seen = true;
      for (std::size_t f = gap.first - 1; f <= gap.last && seen; ++f) seen = samples.is_valid(f, c);
      if (seen) donors.push_back(c);
    }
  }
  if (donors.size() == 2) return two_donor_fill(samples, gap, donors[0], donors[1]);
  donors = steadiest_donors(samples, gap, donors);
  if (donors.size() < 3) return std::nullopt;
  const auto donors_at = [&](std::size_t f) { return positions_at(samples, donors, f); };
  const std::size_t before = gap.first - 1;
  const auto from_before = donors_at(before);
  const auto from_after = donors_at(gap.last);
  const double span = static_cast<double>(gap.last - gap.first + 1);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t f = gap.first; f < gap.last; ++f) {
    const auto now = donors_at(f);
    const auto T_before = fit_rigid_transform(from_before, now);
    const auto T_after = fit_rigid_transform(from_after, now);
    if (!T_before || !T_after) return std::nullopt;
    const double along = static_cast<double>(f - before) / span;
    out.push_back((1.0 - along) * T_before->apply(samples.position(before, gap.marker)) +
                  along * T_after->apply(samples.position(gap.last, gap.marker)));
  }
  return out;
}

std::optional<std::vector<Eigen::Vector3d>> pattern_fill(const MarkerSamples& samples, const Gap& gap,
                                                         const PatternOptions& options) {
  const PatternData data = pattern_data(samples, gap, options.wanted_training_frames);
  if (data.columns.size() < 4 || data.frames.size() < options.min_training_frames) return std::nullopt;
  const auto dims = static_cast<Eigen::Index>(3 * data.columns.size());
  const auto rows = static_cast<Eigen::Index>(data.frames.size());
  const Eigen::VectorXd weights = pattern_weights(samples, data, options.weight_distance_m);
  const auto weighted_row = [&](std::size_t f) {
    Eigen::VectorXd row(dims);
    for (std::size_t j = 0; j < data.columns.size(); ++j)
      row.segment<3>(static_cast<Eigen::Index>(3 * j)) = samples.position(f, data.columns[j]);
    return Eigen::VectorXd(row.cwiseProduct(weights));
  };
  Eigen::MatrixXd X(rows, dims);
  for (Eigen::Index r = 0; r < rows; ++r)
    X.row(r) = weighted_row(data.frames[static_cast<std::size_t>(r)]).transpose();
  const Eigen::VectorXd mean = X.colwise().mean().transpose();
  X.rowwise() -= mean.transpose();
  // The marker's coordinates given the donors' under the trial's Gaussian: mean + S_md (S_dd +
  // noise^2 I)^-1 (donors - mean). The noise term keeps the weak components (tissue wobble, noise)
  // from being fitted: the principal components' regression with a soft cut.
  const Eigen::MatrixXd covariance = X.transpose() * X / static_cast<double>(rows);
  const Eigen::Index donor_dims = dims - 3;
  Eigen::MatrixXd donors = covariance.bottomRightCorner(donor_dims, donor_dims);
  donors.diagonal().array() += options.noise_m * options.noise_m;
  const Eigen::LDLT<Eigen::MatrixXd> factor(donors);
  if (factor.info() != Eigen::Success) return std::nullopt;
  const Eigen::MatrixXd gain = factor.solve(covariance.bottomLeftCorner(donor_dims, 3)).transpose();
  const auto reconstruct = [&](std::size_t f) -> Eigen::Vector3d {
    const Eigen::VectorXd centred = weighted_row(f) - mean;
    return (mean.head<3>() + gain * centred.tail(donor_dims)).cwiseQuotient(weights.head<3>());
  };
  // The reconstruction's error where the marker is seen, either side of the gap, is taken off
  // linearly across it, so the fill meets the samples at both ends.
  const std::size_t before = gap.first - 1;
  const Eigen::Vector3d error_before = reconstruct(before) - samples.position(before, gap.marker);
  const Eigen::Vector3d error_after = reconstruct(gap.last) - samples.position(gap.last, gap.marker);
  const double span = static_cast<double>(gap.last - gap.first + 1);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t f = gap.first; f < gap.last; ++f) {
    const double along = static_cast<double>(f - before) / span;
    out.push_back(reconstruct(f) - (1.0 - along) * error_before - along * error_after);
  }
  return out;
}

namespace {

// One gap by `method`, falling back (pattern -> relational -> spline), counted by the method used.
std::vector<Eigen::Vector3d> fill_one(const SubjectModel& model, const MarkerSamples& samples, const Gap& gap,
                                      FillMethod method, FillReport& report) {
  if (method == FillMethod::kPattern) {
    if (auto fill = pattern_fill(samples, gap)) {
      add(report.pattern, gap);
      return std::move(*fill);
    }
  }
  if (method == FillMethod::kPattern || method == FillMethod::kRelational) {
    if (auto fill = relational_fill(model, samples, gap)) {
      add(report.relational, gap);
      return std::move(*fill);
    }
  }
  if (method == FillMethod::kLinear) {
    add(report.linear, gap);
    return linear_fill(samples, gap);
  }
  add(report.spline, gap);
  return spline_fill(samples, gap);
}

}  // namespace

FillReport fill_gaps(const SubjectModel& model, MarkerSamples& samples, std::vector<std::uint8_t>& filled,
                     const FillOptions& options) {
  FillReport report;
  filled.assign(samples.valid.size(), 0);
  std::vector<Gap> open_end;
  const auto gaps = find_gaps(samples, &open_end);
  for (const auto& gap : open_end) add(report.open_end, gap);
  if (options.method == FillMethod::kNone) return report;
  std::vector<std::pair<Gap, std::vector<Eigen::Vector3d>>> fills;  // applied after all are computed
  for (const auto& gap : gaps) {
    if (gap.last - gap.first > options.max_gap_frames) {
      add(report.too_long, gap);
      continue;
    }
    fills.emplace_back(gap, fill_one(model, samples, gap, options.method, report));
  }
  const std::size_t markers = samples.point_count();
  for (const auto& [gap, points] : fills) {
    for (std::size_t f = gap.first; f < gap.last; ++f) {
      samples.positions[f * markers + gap.marker] = points[f - gap.first];
      samples.valid[f * markers + gap.marker] = 1;
      filled[f * markers + gap.marker] = 1;
    }
  }
  return report;
}

}  // namespace panoptes::labelling
