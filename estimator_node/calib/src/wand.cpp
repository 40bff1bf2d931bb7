// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/wand.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace panoptes::calib {

std::string WandDefinition::validate() const {
  if (positions.empty()) return "the wand has no markers";
  if (positions.size() > 5) return "at most 5 markers on the wand";
  for (std::size_t i = 1; i < positions.size(); ++i)
    if (!(positions[i] > positions[i - 1])) return "wand positions must be strictly ascending";
  if (positions.size() >= 2 && length() < 0.01) return "wand shorter than 1 cm";
  return "";
}

bool WandDefinition::ends_indistinguishable() const {
  if (positions.size() < 2) return false;
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (std::abs((positions[i] - positions.front()) -
                 (positions.back() - positions[positions.size() - 1 - i])) > 1e-3 * length())
      return false;
  return true;
}

WandDefinition parse_wand(const std::string& text) {
  WandDefinition wand;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      std::size_t used = 0;
      const double value = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(value)) throw std::invalid_argument(item);
      wand.positions.push_back(value);
    } catch (const std::exception&) {
      throw std::invalid_argument("--wand: '" + item + "' is not a number (expected e.g. 0,0.18,0.5)");
    }
  }
  if (const std::string problem = wand.validate(); !problem.empty())
    throw std::invalid_argument("--wand: " + problem);
  return wand;
}

namespace {

struct Candidate {
  std::vector<int> blobs;  // in wand order
  double error = 0;        // largest spacing error
  bool symmetric = false;  // both orientations fit about equally well
};

Eigen::Vector2d undistorted_pixel(const CameraModel& model, const Blob& blob) {
  const auto& k = model.intrinsics();
  const Eigen::Vector2d xn = model.pixel_to_normalized({blob.x, blob.y});
  return {k.fx * xn.x() + k.cx, k.fy * xn.y() + k.cy};
}

// Orders `picked` (two blobs) or keeps one blob consistent with the previous frame.
double continuity_cost(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  double cost = 0;
  for (std::size_t i = 0; i < a.size(); ++i) cost += (a[i] - b[i]).norm();
  return cost;
}

// A single LED or a 2-marker bar has no shape to recognise: take the frame only when it shows
// exactly the wand, or the blobs nearest to the previous frame's.
std::optional<std::vector<Eigen::Vector2d>> identify_short_wand(const std::vector<Blob>& blobs,
                                                                std::size_t marker_count,
                                                                const IdentifyOptions& options,
                                                                const WandFrame* previous,
                                                                IdentifyCounters& count) {
  const auto raw = [&](int i) { return Eigen::Vector2d(blobs[i].x, blobs[i].y); };
  const int n = static_cast<int>(blobs.size());
  std::vector<int> picked;
  if (n == static_cast<int>(marker_count)) {
    for (int i = 0; i < n; ++i) picked.push_back(i);
  } else if (previous != nullptr && n <= 64) {
    for (const auto& last : previous->pixels) {
      int best = -1;
      double best_distance = options.max_jump_px;
      for (int i = 0; i < n; ++i) {
        const double distance = (raw(i) - last).norm();
        if (distance < best_distance && std::find(picked.begin(), picked.end(), i) == picked.end()) {
          best = i;
          best_distance = distance;
        }
      }
      if (best < 0) return std::nullopt;
      picked.push_back(best);
    }
  } else {
    return std::nullopt;
  }
  ++count.collinear_candidates;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(picked.size());
  for (int i : picked) pixels.push_back(raw(i));
  if (marker_count == 2) {
    std::vector<Eigen::Vector2d> swapped{pixels[1], pixels[0]};
    if (previous != nullptr && previous->pixels.size() == 2) {
      if (continuity_cost(swapped, previous->pixels) < continuity_cost(pixels, previous->pixels))
        pixels = swapped;
    } else if (pixels[1].x() < pixels[0].x()) {
      pixels = swapped;
    }
  }
  if (previous != nullptr && previous->pixels.size() == pixels.size() &&
      continuity_cost(pixels, previous->pixels) > options.max_jump_px * static_cast<double>(marker_count) &&
      n != static_cast<int>(marker_count))
    return std::nullopt;
  ++count.identified;
  return pixels;
}

// Every pair of blobs as the ends of the bar: the candidates whose inner blobs lie on the line
// between them at the wand's relative positions (undistorted pixels `u`).
struct Candidates {
  std::vector<Candidate> fitting;
  bool any_collinear = false;
  double mismatch_spacing = 0;  // relative position of the 2nd marker of the best mismatch
};

Candidates collinear_candidates(const std::vector<Eigen::Vector2d>& u, const WandDefinition& wand,
                                const IdentifyOptions& options) {
  const std::size_t marker_count = wand.marker_count();
  const int n = static_cast<int>(u.size());
  std::vector<double> relative(marker_count);
  for (std::size_t m = 0; m < marker_count; ++m)
    relative[m] = (wand.positions[m] - wand.positions[0]) / wand.length();
  Candidates out;
  double best_mismatch = 1e9;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const Eigen::Vector2d axis = u[j] - u[i];
      const double length = axis.norm();
      if (length < 4.0) continue;
      const Eigen::Vector2d direction = axis / length;
      std::vector<std::pair<double, int>> inner;
      for (int k = 0; k < n; ++k) {
        if (k == i || k == j) continue;
        const Eigen::Vector2d d = u[k] - u[i];
        const double along = d.dot(direction) / length;
        const double across = std::abs(d.x() * direction.y() - d.y() * direction.x());
        if (across < options.collinearity_px && along > 0.0 && along < 1.0) inner.emplace_back(along, k);
      }
      if (inner.size() != marker_count - 2) continue;
      out.any_collinear = true;
      std::sort(inner.begin(), inner.end());
      double forward = 0, backward = 0;
      for (std::size_t m = 1; m + 1 < marker_count; ++m) {
        forward = std::max(forward, std::abs(inner[m - 1].first - relative[m]));
        backward = std::max(backward, std::abs((1.0 - inner[marker_count - 2 - m].first) - relative[m]));
      }
      const double error = std::min(forward, backward);
      if (error > options.spacing_tolerance) {
        if (error < best_mismatch) {
          best_mismatch = error;
          out.mismatch_spacing = inner[0].first;
        }
        continue;
      }
      Candidate candidate;
      candidate.error = error;
      candidate.symmetric = std::abs(forward - backward) < 0.03;
      candidate.blobs.push_back(i);
      for (const auto& [along, k] : inner) candidate.blobs.push_back(k);
      candidate.blobs.push_back(j);
      if (backward < forward) std::reverse(candidate.blobs.begin(), candidate.blobs.end());
      out.fitting.push_back(std::move(candidate));
    }
  }
  return out;
}

}  // namespace

std::optional<std::vector<Eigen::Vector2d>> identify_wand(
    const std::vector<Blob>& blobs, const CameraIntrinsics& intrinsics, const WandDefinition& wand,
    const IdentifyOptions& options, const WandFrame* previous, IdentifyCounters* counters) {
  IdentifyCounters scratch;
  IdentifyCounters& count = counters != nullptr ? *counters : scratch;
  ++count.frames;
  const std::size_t marker_count = wand.marker_count();
  if (marker_count == 0 || blobs.size() < marker_count) return std::nullopt;
  ++count.frames_with_enough_blobs;
  if (marker_count <= 2) return identify_short_wand(blobs, marker_count, options, previous, count);

  const int n = static_cast<int>(blobs.size());
  if (n > 48) return std::nullopt;  // a flood of blobs: not a wand frame
  const CameraModel model(intrinsics, RigidTransform{});
  std::vector<Eigen::Vector2d> u(n);
  for (int i = 0; i < n; ++i) u[i] = undistorted_pixel(model, blobs[i]);
  Candidates found = collinear_candidates(u, wand, options);
  auto& candidates = found.fitting;
  if (found.any_collinear) ++count.collinear_candidates;
  if (candidates.empty()) {
    if (found.any_collinear) {
      ++count.spacing_mismatches;
      count.mean_mismatch_spacing += (found.mismatch_spacing - count.mean_mismatch_spacing) /
                                     static_cast<double>(count.spacing_mismatches);
    }
    return std::nullopt;
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.error < b.error; });
  if (candidates.size() >= 2 && candidates[1].error < candidates[0].error + 0.03) {
    ++count.ambiguous;
    return std::nullopt;
  }
  std::vector<Eigen::Vector2d> pixels;
  for (int index : candidates[0].blobs) pixels.emplace_back(blobs[index].x, blobs[index].y);
  if (candidates[0].symmetric) {
    // A symmetric bar: the image cannot tell its ends apart, the previous frame can. Without one,
    // a wand symmetric by definition starts a new label run (resolved across cameras later); an
    // asymmetric wand seen so that both orientations fit is skipped.
    std::vector<Eigen::Vector2d> reversed(pixels.rbegin(), pixels.rend());
    if (previous == nullptr || previous->pixels.size() != pixels.size()) {
      if (!wand.ends_indistinguishable()) {
        ++count.ambiguous;
        return std::nullopt;
      }
    } else if (continuity_cost(reversed, previous->pixels) < continuity_cost(pixels, previous->pixels)) {
      pixels = reversed;
    }
  }
  ++count.identified;
  return pixels;
}

CameraWandTrack extract_wand_track(const std::string& camera_id, const std::vector<FeatureFrame>& frames,
                                   const CameraIntrinsics& intrinsics, const WandDefinition& wand,
                                   const IdentifyOptions& options) {
  CameraWandTrack track;
  track.camera_id = camera_id;
  std::vector<const FeatureFrame*> ordered;
  ordered.reserve(frames.size());
  for (const auto& frame : frames) ordered.push_back(&frame);
  std::sort(ordered.begin(), ordered.end(),
            [](const FeatureFrame* a, const FeatureFrame* b) { return a->stamp_ns < b->stamp_ns; });
  std::vector<TimeNs> differences;
  for (std::size_t i = 1; i < ordered.size(); ++i)
    if (ordered[i]->stamp_ns > ordered[i - 1]->stamp_ns)
      differences.push_back(ordered[i]->stamp_ns - ordered[i - 1]->stamp_ns);
  if (!differences.empty()) {
    std::nth_element(differences.begin(), differences.begin() + differences.size() / 2, differences.end());
    track.frame_period_s = static_cast<double>(differences[differences.size() / 2]) * 1e-9;
  }
  const WandFrame* previous = nullptr;
  TimeNs previous_stamp = 0;
  const bool look_alike = wand.ends_indistinguishable();
  int label_run = 0;
  for (const FeatureFrame* frame : ordered) {
    // Labels carry over only across a short gap.
    const bool recent =
        previous != nullptr && track.frame_period_s > 0 &&
        static_cast<double>(frame->stamp_ns - previous_stamp) * 1e-9 < 3.5 * track.frame_period_s;
    auto pixels =
        identify_wand(frame->blobs, intrinsics, wand, options, recent ? previous : nullptr, &track.counters);
    if (!pixels) continue;
    if (!track.frames.empty() && track.frames.back().stamp_ns == frame->stamp_ns) continue;  // duplicate
    if (look_alike && !track.frames.empty()) {
      // The run goes on only where continuity told the ends apart clearly.
      bool carried = recent;
      if (carried) {
        const std::vector<Eigen::Vector2d> reversed(pixels->rbegin(), pixels->rend());
        const double kept = continuity_cost(*pixels, previous->pixels);
        const double swapped = continuity_cost(reversed, previous->pixels);
        carried = swapped > 2.0 * kept && swapped - kept > options.label_margin_px;
      }
      if (!carried) ++label_run;
    }
    track.frames.push_back({frame->stamp_ns, std::move(*pixels), label_run});
    previous = &track.frames.back();
    previous_stamp = frame->stamp_ns;
  }
  return track;
}

std::optional<TrackSegment> find_segment(const CameraWandTrack& track, TimeNs t_ns, double max_gap_s) {
  const auto& frames = track.frames;
  if (frames.size() < 2) return std::nullopt;
  auto after = std::upper_bound(frames.begin(), frames.end(), t_ns,
                                [](TimeNs t, const WandFrame& frame) { return t < frame.stamp_ns; });
  if (after == frames.begin()) return std::nullopt;
  std::size_t i = static_cast<std::size_t>(after - frames.begin()) - 1;
  const auto seconds = [&](std::size_t k) { return static_cast<double>(frames[k].stamp_ns - t_ns) * 1e-9; };
  const double h = i + 1 < frames.size() ? seconds(i + 1) - seconds(i) : 0.0;
  if (!(h > 0) || h > max_gap_s) {
    // A frame exactly at the instant (synchronised cameras) is its own observation even without a
    // neighbour to interpolate towards: a constant segment.
    if (frames[i].stamp_ns != t_ns || !(max_gap_s > 0)) return std::nullopt;
    TrackSegment still;
    still.t0_s = 0;
    still.h_s = max_gap_s;
    still.p0 = still.p1 = frames[i].pixels;
    still.m0.assign(frames[i].pixels.size(), Eigen::Vector2d::Zero());
    still.m1 = still.m0;
    return still;
  }
  TrackSegment segment;
  segment.t0_s = seconds(i);
  segment.h_s = h;
  const std::size_t markers = frames[i].pixels.size();
  const bool has_before = i >= 1 && seconds(i) - seconds(i - 1) <= max_gap_s;
  const bool has_after = i + 2 < frames.size() && seconds(i + 2) - seconds(i + 1) <= max_gap_s;
  for (std::size_t m = 0; m < markers; ++m) {
    const Eigen::Vector2d& p0 = frames[i].pixels[m];
    const Eigen::Vector2d& p1 = frames[i + 1].pixels[m];
    const Eigen::Vector2d chord = (p1 - p0) / h;
    segment.p0.push_back(p0);
    segment.p1.push_back(p1);
    segment.m0.push_back(
        has_before ? Eigen::Vector2d((p1 - frames[i - 1].pixels[m]) / (seconds(i + 1) - seconds(i - 1)))
                   : chord);
    segment.m1.push_back(
        has_after ? Eigen::Vector2d((frames[i + 2].pixels[m] - p0) / (seconds(i + 2) - seconds(i))) : chord);
  }
  return segment;
}

}  // namespace panoptes::calib
