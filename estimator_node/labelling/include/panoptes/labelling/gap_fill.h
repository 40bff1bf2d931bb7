// SPDX-License-Identifier: Apache-2.0
// Gap filling of labelled trajectories (issue 33 item 3, docs/marker_sets.md "Gap filling"), as
// studios expect: linear and cubic spline across short gaps, and relational (rigid-body) fill
// from the other markers of the marker's segment. Only gaps with a sample on both sides are filled
// (nothing is extrapolated), and only up to a maximum length.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

enum class FillMethod { kNone, kLinear, kSpline, kRelational, kPattern };

struct FillOptions {
  FillMethod method = FillMethod::kPattern;
  std::size_t max_gap_frames = 18;  // 0.3 s at 60 Hz
};

struct FillCount {
  std::size_t gaps = 0;
  std::size_t frames = 0;
};

struct FillReport {
  FillCount linear, spline, relational, pattern;
  FillCount too_long;  // gaps left open: longer than the maximum
  FillCount open_end;  // gaps left open: at the start or end of the trial
};

// A gap of one marker: frames [first, last) invalid, first - 1 and last valid.
struct Gap {
  std::size_t marker = 0;
  std::size_t first = 0;
  std::size_t last = 0;
};

// Every invalid stretch of every marker, with `open_end` ones (touching the trial's start or end)
// apart.
std::vector<Gap> find_gaps(const MarkerSamples& samples, std::vector<Gap>* open_end = nullptr);

// The gap's samples by straight line between the samples either side.
std::vector<Eigen::Vector3d> linear_fill(const MarkerSamples& samples, const Gap& gap);
// By cubic Hermite interpolation between the samples either side, the tangents from their
// neighbours (one-sided differences; a lone sample gives the linear tangent).
std::vector<Eigen::Vector3d> spline_fill(const MarkerSamples& samples, const Gap& gap);
// Rigid-body fill from the marker's segment in `model` (its donors: the segment's other tracked
// markers seen from the frame before the gap to the frame after it). With >= 3 donors (the subset
// whose motion across the gap best carries the marker to where it is seen after it): in every frame
// of the gap the donors' rigid motion from the frame before (fit_rigid_transform) carries the
// marker's position there, and the motion from the frame after carries the position there; the two
// are blended linearly across the gap, so the fill meets the samples at both ends. The layout comes
// from the neighbouring frames, not the static model (soft tissue moves markers from the static
// layout by 1-9 mm). With 2 donors the marker's distances along and off their axis are blended so,
// its turn about the axis taken from spline_fill. nullopt with fewer donors.
std::optional<std::vector<Eigen::Vector3d>> relational_fill(const SubjectModel& model,
                                                            const MarkerSamples& samples, const Gap& gap);

// Pattern fill, from how this subject's markers move together over the whole trial (the idea of
// PCA gap filling, Federolf 2013, and its distance-weighted form, Gloersen & Federolf 2016, as a
// regularised Gaussian regression): the marker and every marker seen throughout the gap (the
// donors), over the trial's frames where all of them are seen, each marker's coordinates weighted
// by its closeness to the marker; in each gap frame the marker's coordinates are their conditional
// mean given the donors' (the donors' covariance plus noise_m^2, which keeps the weakest components
// out). The reconstruction's error at the samples either side is taken off linearly across the
// gap, so the fill meets them. Needs no segment model. Where other markers have gaps too, the
// donors missing from most frames are left out until enough frames show the rest. nullopt with
// fewer than 3 donors or min_training_frames frames.
struct PatternOptions {
  double weight_distance_m = 0.4;  // a donor this far from the marker (mean distance) weighs exp(-1)
  double noise_m = 0.001;          // the regulariser, in weighted metres
  std::size_t min_training_frames = 20;
  // Donors missing from many frames are dropped until the training frames reach this (or every
  // frame where the marker is seen).
  std::size_t wanted_training_frames = 40;
};
std::optional<std::vector<Eigen::Vector3d>> pattern_fill(const MarkerSamples& samples, const Gap& gap,
                                                         const PatternOptions& options = {});
// Fills every gap up to options.max_gap_frames with options.method (pattern falls back to
// relational, relational to spline where the segment cannot be fitted), on the samples as given
// (filled samples do not feed other fills). `filled` gets 1 per filled sample (same layout as
// samples.valid).
FillReport fill_gaps(const SubjectModel& model, MarkerSamples& samples, std::vector<std::uint8_t>& filled,
                     const FillOptions& options);

}  // namespace panoptes::labelling
