// SPDX-License-Identifier: Apache-2.0
// Marker labels for the application output (docs/clients.md): which published point tracks are the
// markers of which tracked rigid body. A body's layout, placed at its pose, predicts where each of
// its markers is; tracks within `max_distance_m` of a predicted marker are paired with it by a
// minimum-cost assignment over all bodies at once (assignment.h), so one track labels at most one
// body marker. What is left unpaired is an unlabelled (loose) marker. The mean distance of a body's
// labelled markers from their predicted positions is its mean marker error (NatNet's MeanError).
#pragma once

#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/records.h"

namespace panoptes::estimator {

struct MarkerLabel {
  int body = -1;    // index into the definitions; -1: unlabelled
  int marker = -1;  // index in that body's layout
};

struct MarkerLabelling {
  std::vector<MarkerLabel> labels;    // one per track, in the tracks' order
  std::vector<double> mean_error_m;   // one per definition; 0 for a body with no labelled marker
  std::vector<int> labelled_markers;  // one per definition: how many of its markers are labelled
};

// `poses` are the tracked bodies' poses at the tracks' stamp (not predicted ahead); a definition
// without a pose is not tracked and labels nothing.
MarkerLabelling label_markers(const std::vector<TrackRecord>& tracks, const std::vector<PoseRecord>& poses,
                              const std::vector<BodyDefinition>& definitions, double max_distance_m = 0.01);

}  // namespace panoptes::estimator
