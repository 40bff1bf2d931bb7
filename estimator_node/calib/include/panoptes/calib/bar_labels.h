// SPDX-License-Identifier: Apache-2.0
// The ends of a bar that look alike (a 2-marker bar, seed 000 §4.5.8; any symmetric wand): no
// frame tells them apart, so each camera labels them by continuity in runs (WandFrame::label_run)
// whose end order is a guess of its own. The runs are reconciled across cameras before the
// pairwise poses: an approximate essential matrix per camera pair from the bar's midpoints (which
// need no labels), a vote per common instant between the two labellings by their epipolar error,
// and a two-colouring of the runs by a maximum-weight spanning tree of the votes
// (docs/calibration.md, "Bar ends").
#pragma once

#include <vector>

#include "panoptes/calib/wand.h"
#include "panoptes/camera_model.h"

namespace panoptes::calib {

struct BarLabelOptions {
  double sample_rate_hz = 0.0;  // instants compared; 0: the fastest camera's rate
  double max_gap_frames = 1.6;  // a run is interpolated only between frames this close
  int min_pair_samples = 25;    // common instants for a camera pair's essential matrix
  int max_pair_samples = 400;   // subsampled for its RANSAC
  // RANSAC threshold on the midpoints, normalised image units (radians). The midpoint of the
  // projected ends misses the projected midpoint by up to (L/2)^2 sin(2a) / (2 Z^2) (a: the bar's
  // angle to the image plane): 5 mrad for a 0.5 m bar 2.5 m away at 45 degrees, so it is loose.
  // The pair's votes then label the ends, and a second essential matrix from the labelled ends
  // (threshold a quarter of this) votes again.
  double midpoint_threshold = 0.008;
  // A vote counts if the worse labelling's epipolar error exceeds the better's by this factor and
  // by the threshold (a bar along the epipolar lines fits both labellings).
  double decisive_ratio = 3.0;
  int min_votes = 3;  // net decisive votes for a run pair to join the spanning tree
};

struct BarLabelReport {
  int runs = 0;               // label runs over all cameras
  int flipped_runs = 0;       // runs whose end order was reversed to agree with the others
  int dropped_runs = 0;       // runs without decisive overlap with the largest group: removed
  int dropped_frames = 0;     // their frames
  int camera_pairs = 0;       // pairs with an essential matrix from the midpoints
  int votes = 0;              // decisive votes between runs that were kept
  int conflicting_votes = 0;  // of those, votes against the final labelling
};

// Reverses the marker order of the runs that disagree with the largest consistent group and removes
// the runs that could not be related to it. `intrinsics[i]` belongs to `tracks[i]`.
BarLabelReport resolve_bar_labels(std::vector<CameraWandTrack>& tracks,
                                  const std::vector<CameraIntrinsics>& intrinsics,
                                  const BarLabelOptions& options = {});

}  // namespace panoptes::calib
