// SPDX-License-Identifier: Apache-2.0
// Re-sampling the estimator's asynchronous track and pose updates to a fixed rate
// (docs/recording.md, "Export").
//
// Method: the sample times are t0 + k / rate, t0 the earliest stamp of all records (or a given
// start). A marker (track) or body at sample time t takes the two updates bracketing t, a <= t <= b,
// and interpolates linearly between them (positions; orientations by spherical linear
// interpolation, shortest path). It is invalid at t when there is no update at or before t, none at
// or after t, or the bracketing updates are more than max_gap apart (an update exactly at t is
// always used). Nothing is extrapolated.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/formats/marker_trajectories.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes {

struct ResampleOptions {
  double rate_hz = 100.0;
  TimeNs max_gap_ns = 100 * kNsPerMillisecond;  // longer gaps between updates are left invalid
  std::optional<TimeNs> start_ns;               // default: the earliest stamp
  std::optional<TimeNs> end_ns;                 // default: the latest stamp
  bool include_tentative = false;               // tentative tracks are usually clutter
  // Names of the markers by track id; an id not in the map is named "track_<id>".
  std::map<std::int64_t, std::string> marker_names;
};

// The fixed-rate grid shared by the markers and the bodies of one export.
struct SampleGrid {
  TimeNs start_ns = 0;
  double rate_hz = 0.0;
  std::size_t count = 0;
  // Explicit sample times (count of them, from start_ns, increasing), e.g. the instants of a
  // recording's fixed-rate frames (docs/frames.md); empty: start_ns + k / rate_hz.
  std::vector<TimeNs> times;
  TimeNs time_ns(std::size_t k) const;
};

// The instants of the estimator's fixed-rate frame clock (docs/frames.md: period k of second s at
// s * 10^9 + floor(k * 10^9 / rate)) from `first_ns` to `last_ns`, both included if on the grid.
// Throws std::invalid_argument for a rate that is not a whole number of Hz in 1..10000.
SampleGrid fixed_rate_grid(TimeNs first_ns, TimeNs last_ns, int rate_hz);

// The grid covering every stamp of `tracks` and `poses` (or options.start_ns/end_ns). Throws
// std::invalid_argument for a rate that is not positive and finite or when there is no record.
SampleGrid make_grid(const std::vector<TrackRecord>& tracks, const std::vector<PoseRecord>& poses,
                     const ResampleOptions& options);

// One marker per track id, named "track_<id>" (or options.marker_names), in increasing id order; positions in
// metres, times_s relative to grid.start_ns. Residual: the root mean of the position variances of the nearer
// update (0 while the track coasts: predicted, not measured, C3D's convention); camera mask: the low
// min(cameras, 7) bits (track records count cameras, they do not name them).
MarkerTrajectories resample_tracks(const std::vector<TrackRecord>& tracks, const SampleGrid& grid,
                                   const ResampleOptions& options);

struct BodyTrajectories {
  double data_rate_hz = 0.0;
  std::vector<std::string> body_names;       // sorted
  std::vector<double> times_s;               // relative to the grid start
  std::vector<Eigen::Vector3d> positions;    // frame-major [frame * body_count() + body], metres
  std::vector<Eigen::Vector4d> quaternions;  // x, y, z, w; same layout
  std::vector<std::uint8_t> valid;

  std::size_t frame_count() const { return times_s.size(); }
  std::size_t body_count() const { return body_names.size(); }
};

BodyTrajectories resample_poses(const std::vector<PoseRecord>& poses, const SampleGrid& grid,
                                const ResampleOptions& options);

// Appends the bodies' origins to `markers` as points named after the bodies (same grid).
void append_body_origins(MarkerTrajectories& markers, const BodyTrajectories& bodies);

}  // namespace panoptes
