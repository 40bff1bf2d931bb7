// SPDX-License-Identifier: Apache-2.0
// Compares estimated tracks with simulator ground truth: per-marker RMSE and maximum error,
// coverage of the marker-time the cameras made trackable, ID switches, false track records
// (docs/estimator.md, "Evaluation").
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes {
class Scene;
}

namespace panoptes::estimator {

struct EvaluationOptions {
  TimeNs epoch_ns = 0;              // absolute stamp of scene time 0
  TimeNs warmup_ns = kNsPerSecond;  // ignore the first second (acquisition)
  // Judge scene time up to this (and up to the scene's end); a window [warmup, until] of the scene.
  TimeNs until_ns = std::numeric_limits<TimeNs>::max();
  double match_distance_m = 0.02;    // a track within this of a marker observes it
  int false_track_min_samples = 10;  // tracks with fewer samples are not judged as false tracks
  // A marker is trackable at an instant when at least trackable_min_cameras cameras showed it
  // (CameraSimulator::visible_markers) in frames with mid-exposure within the window before it.
  TimeNs trackable_window_ns = 100 * kNsPerMillisecond;
  int trackable_min_cameras = 2;
  bool keep_series = false;  // fill Evaluation::series (plots)
  // Judge every frame time of the scene's cameras too, not only the stamps the tracks carry: the
  // estimator publishes a TrackFrame at each frame it applies, and a tracks file lists records,
  // so a frame at which no track was published leaves no line (a thrown ball's single track
  // unpublished at a catch was never judged). Off (the default): only the records' stamps.
  bool judge_every_frame = false;
};

struct IdSwitch {
  TimeNs stamp_ns = 0;
  std::int64_t from_id = 0;
  std::int64_t to_id = 0;
  double t_s = 0.0;  // seconds from the scene start
  // The new track had been matched to another marker before: an identity that moved between
  // markers (a swap, or a track that left its marker for this one), not a new track for a marker
  // whose own was lost.
  bool swap = false;
};

struct MarkerEvaluation {
  std::string name;
  std::size_t steps = 0;              // evaluation instants at which the marker had ground truth
  std::size_t tracked = 0;            // of those, instants with a track matched to it
  std::size_t trackable = 0;          // of the steps, instants at which the marker was trackable
  std::size_t tracked_trackable = 0;  // instants both trackable and tracked
  double rmse_m = 0;
  double max_error_m = 0;
  std::vector<IdSwitch> id_switches;
  double tracked_fraction() const { return steps == 0 ? 0.0 : static_cast<double>(tracked) / steps; }
  // Tracked share of the trackable instants; 1 when the marker was never trackable.
  double coverage() const {
    return trackable == 0 ? 1.0 : static_cast<double>(tracked_trackable) / static_cast<double>(trackable);
  }
};

// Records of one track id that matched no marker at their instant.
struct FalseRecords {
  std::int64_t id = 0;
  std::size_t records = 0;        // judged records of this id
  std::size_t false_records = 0;  // of those, matched to no marker
};

// Per-instant detail for plots (EvaluationOptions::keep_series).
struct EvaluationSeries {
  enum Flags : std::uint8_t { kHasTruth = 1, kTrackable = 2, kTracked = 4 };
  std::vector<TimeNs> scene_time_ns;             // the evaluation instants, ascending
  std::vector<std::vector<float>> error_m;       // [marker][instant]; NaN where untracked
  std::vector<std::vector<std::uint8_t>> flags;  // [marker][instant]; Flags
};

struct Evaluation {
  std::vector<MarkerEvaluation> markers;
  std::size_t instants = 0;
  std::size_t track_ids = 0;
  std::vector<std::int64_t> false_tracks;  // ids with at least false_track_min_samples records, mostly false
  double rmse_m = 0;                       // over all matched samples
  double max_error_m = 0;                  // over all matched samples
  double worst_marker_rmse_m = 0;
  double min_tracked_fraction = 0;
  std::size_t id_switch_count = 0;
  std::size_t id_swap_count = 0;  // of those, IdSwitch::swap

  // Coverage of trackable marker-time, summed over markers.
  std::size_t trackable = 0;
  std::size_t tracked_trackable = 0;
  double min_coverage = 1.0;  // over markers that were ever trackable
  // Of those, the marker-instants at the edge of the trackable volume: shown by exactly
  // trackable_min_cameras cameras (2 by default: the region a third camera no longer reaches).
  std::size_t edge_trackable = 0;
  std::size_t edge_tracked = 0;

  // Track records at the judged instants; a false one matched no marker (a ghost, or a second
  // track on a marker another track took: a duplicate).
  std::size_t records = 0;
  std::size_t false_records = 0;
  std::size_t duplicate_records = 0;           // false records within match distance of a marker
  std::vector<FalseRecords> false_record_ids;  // ids with at least one false record, by id

  TimeNs max_instant_gap_ns = 0;  // longest time between consecutive instants (silence)
  EvaluationOptions options;      // what produced this
  EvaluationSeries series;        // empty unless options.keep_series

  double coverage() const {
    return trackable == 0 ? 1.0 : static_cast<double>(tracked_trackable) / static_cast<double>(trackable);
  }
  double edge_coverage() const {
    return edge_trackable == 0 ? 1.0
                               : static_cast<double>(edge_tracked) / static_cast<double>(edge_trackable);
  }
  double false_record_fraction() const {
    return records == 0 ? 0.0 : static_cast<double>(false_records) / static_cast<double>(records);
  }

  std::string to_json() const;  // pretty-printed JSON object
  std::string summary() const;  // human-readable table
};

// `tracks` may come in any order; records sharing a stamp form one evaluation instant. Instants
// before the warmup or after the scene's duration are not judged.
Evaluation evaluate(const Scene& scene, const std::vector<TrackRecord>& tracks,
                    const EvaluationOptions& options);

// Body poses against the scene's body truth. A pose record is compared with the truth at its
// stamp plus its prediction horizon; it is correct within 2 cm and 5 degrees (else "wrong": a
// confusion or a lost pose still published). Tracked: the fraction of 10 ms bins of scene time
// (after the warmup) in which the body had a correct pose.
struct BodyEvaluation {
  std::string body;
  std::size_t records = 0, wrong = 0;
  double rmse_m = 0, max_m = 0, rmse_deg = 0, max_deg = 0;
  double tracked_fraction = 0;
};

struct PoseEvaluation {
  std::vector<BodyEvaluation> bodies;  // every body of the scene, in scene order
  std::string to_json() const;
  std::string summary() const;
};

PoseEvaluation evaluate_poses(const Scene& scene, const std::vector<PoseRecord>& poses,
                              const EvaluationOptions& options);

}  // namespace panoptes::estimator
