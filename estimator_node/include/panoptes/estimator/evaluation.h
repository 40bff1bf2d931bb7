// SPDX-License-Identifier: Apache-2.0
// Compares estimated tracks with simulator ground truth: per-marker RMSE, coverage, ID switches,
// false tracks.
#pragma once

#include <string>
#include <vector>

#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes {
class Scene;
}

namespace panoptes::estimator {

struct EvaluationOptions {
  TimeNs epoch_ns = 0;               // absolute stamp of scene time 0
  TimeNs warmup_ns = kNsPerSecond;   // ignore the first second (acquisition)
  double match_distance_m = 0.02;    // a track within this of a marker observes it
  int false_track_min_samples = 10;  // tracks with fewer samples are not judged
};

struct IdSwitch {
  TimeNs stamp_ns = 0;
  std::int64_t from_id = 0;
  std::int64_t to_id = 0;
};

struct MarkerEvaluation {
  std::string name;
  std::size_t steps = 0;    // evaluation instants at which the marker had ground truth
  std::size_t tracked = 0;  // of those, instants with a track matched to it
  double rmse_m = 0;
  double max_error_m = 0;
  std::vector<IdSwitch> id_switches;
  double tracked_fraction() const { return steps == 0 ? 0.0 : static_cast<double>(tracked) / steps; }
};

struct Evaluation {
  std::vector<MarkerEvaluation> markers;
  std::size_t instants = 0;
  std::size_t track_ids = 0;
  std::vector<std::int64_t> false_tracks;  // ids mostly matched to no marker
  double rmse_m = 0;                       // over all matched samples
  double worst_marker_rmse_m = 0;
  double min_tracked_fraction = 0;
  std::size_t id_switch_count = 0;

  std::string to_json() const;  // pretty-printed JSON object
  std::string summary() const;  // human-readable table
};

// `tracks` may come in any order; records sharing a stamp form one evaluation instant.
Evaluation evaluate(const Scene& scene, const std::vector<TrackRecord>& tracks,
                    const EvaluationOptions& options);

}  // namespace panoptes::estimator
