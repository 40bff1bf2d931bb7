// SPDX-License-Identifier: Apache-2.0
// The calibration wand and its observations: identification of the wand's markers in one camera
// frame, per-camera 2D tracks, and their interpolation in time so that asynchronous cameras can be
// paired at any instant (seed 003 §3.3.1 discretises time into 36 ms bins; we interpolate).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"
#include "panoptes/interpolation.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::calib {

// Markers along a straight bar, metres from its first marker, strictly ascending. One marker is a
// single LED (seed 003): no metric scale. Two or more give scale (seed 000 §4.5.8).
struct WandDefinition {
  std::vector<double> positions;

  std::size_t marker_count() const { return positions.size(); }
  double length() const { return positions.empty() ? 0.0 : positions.back() - positions.front(); }
  // Two or more markers spaced the same from either end (a 2-marker bar always): an image cannot
  // tell the ends apart, only continuity within a camera can (docs/calibration.md, "Bar ends").
  bool ends_indistinguishable() const;
  // "" if usable, otherwise the reason (names the problem, e.g. "positions not ascending").
  std::string validate() const;
};

// Parses "0,0.18,0.5"; throws std::invalid_argument naming the bad item.
WandDefinition parse_wand(const std::string& text);

struct IdentifyOptions {
  // A blob belongs to the bar if it lies within this distance of the line through the two end
  // blobs (pixels, in undistorted pixel coordinates).
  double collinearity_px = 2.0;
  // Largest difference between a marker's relative position along the bar in the image and its
  // true relative position. Perspective moves it: a bar pointing at the camera shortens its far
  // part.
  double spacing_tolerance = 0.12;
  // Largest jump of a single LED or a 2-marker bar between consecutive frames used to keep
  // marker labels (pixels).
  double max_jump_px = 80.0;
  // Labels of a wand whose ends look alike carry over from the previous frame only if swapping
  // them would move the markers by this much more than keeping them (and at least twice as much);
  // otherwise a new label run starts.
  double label_margin_px = 6.0;
};

// Why a frame gave no wand: counted per camera so that "lengths never match" can be told apart
// from "never saw the wand".
struct IdentifyCounters {
  int frames = 0;
  int frames_with_enough_blobs = 0;  // at least marker_count() blobs
  int collinear_candidates = 0;      // frames with a collinear set of the right size
  int spacing_mismatches = 0;        // ... whose spacing matched no orientation of the wand
  int ambiguous = 0;                 // two or more equally good candidates
  int identified = 0;
  double mean_mismatch_spacing = 0;  // mean relative position of the 2nd marker when mismatched
};

// One camera frame with the wand identified: pixels (as measured, distorted) in wand order.
struct WandFrame {
  TimeNs stamp_ns = 0;
  std::vector<Eigen::Vector2d> pixels;
  // Frames of one camera with the same label run were labelled by continuity from each other.
  // For a wand whose ends look alike, each run's end order is a guess of its own, which the solver
  // reconciles across cameras (resolve_bar_labels); for other wands it is always 0.
  int label_run = 0;
};

struct CameraWandTrack {
  std::string camera_id;
  std::vector<WandFrame> frames;  // ascending stamps
  IdentifyCounters counters;
  double frame_period_s = 0.0;  // median stamp difference of the input frames
};

// Identifies the wand among `blobs`, whose positions are first undistorted with `intrinsics`.
// Returns the pixels (distorted, as measured) in wand order, or nullopt. For 1 or 2 markers,
// `previous` (the last identified frame, if any) keeps labels consistent.
std::optional<std::vector<Eigen::Vector2d>> identify_wand(const std::vector<Blob>& blobs,
                                                          const CameraIntrinsics& intrinsics,
                                                          const WandDefinition& wand,
                                                          const IdentifyOptions& options,
                                                          const WandFrame* previous = nullptr,
                                                          IdentifyCounters* counters = nullptr);

// Runs identify_wand over one camera's frames (any order; sorted by stamp here).
CameraWandTrack extract_wand_track(const std::string& camera_id, const std::vector<FeatureFrame>& frames,
                                   const CameraIntrinsics& intrinsics, const WandDefinition& wand,
                                   const IdentifyOptions& options = {});

// A piece of a track around one instant: the cubic Hermite segment between two frames, with
// tangents from the neighbouring frames (a non-uniform Catmull-Rom spline). It can be evaluated
// at a shifted time, which is how per-camera clock offsets enter the bundle adjustment.
struct TrackSegment {
  double t0_s = 0;  // time of the segment's first frame relative to the query instant, s (<= 0)
  double h_s = 0;   // segment duration, s
  std::vector<Eigen::Vector2d> p0, p1, m0, m1;  // per marker: end points (px), tangents (px/s)
};

// The segment of `track` containing stamp `t_ns` (relative times use `t_ns` as origin), if its
// frames are at most `max_gap_s` apart. nullopt outside the track or across a gap, except that a
// frame stamped exactly `t_ns` gives a constant segment at its pixels (synchronised cameras).
std::optional<TrackSegment> find_segment(const CameraWandTrack& track, TimeNs t_ns, double max_gap_s);

// Position of marker `m` at time `dt_s` after the query instant (usually a small clock offset).
template <class T>
Eigen::Matrix<T, 2, 1> evaluate_segment(const TrackSegment& segment, std::size_t m, const T& dt_s) {
  Eigen::Matrix<T, 2, 1> p;
  for (int i = 0; i < 2; ++i)
    p[i] = cubic_hermite(segment.t0_s, segment.h_s, segment.p0[m][i], segment.m0[m][i], segment.p1[m][i],
                         segment.m1[m][i], dt_s);
  return p;
}

}  // namespace panoptes::calib
