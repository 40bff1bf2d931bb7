// SPDX-License-Identifier: Apache-2.0
// The instants at which the wand is estimated, and what each camera saw of it there: every camera's
// 2D track evaluated on one grid of instants (docs/calibration.md, "Pipeline", step 2). The input of
// the solver's stages (two_view.h, view_graph.h, bundle_adjustment.h, solve_finish.h).
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calib/wand.h"
#include "panoptes/time.h"

namespace panoptes::calib {

// One camera's view of the wand at one instant: the piece of its track around the instant.
struct InstantObservation {
  int camera = 0;        // index into the solve's cameras
  TrackSegment segment;  // looked up at the instant + shift_s on the camera's clock
  double shift_s = 0;    // how far the lookup was moved (clock offsets, bundle_adjustment.h)
  bool active = true;    // false: left out (an outlier, a camera that failed)
};

struct WandInstant {
  TimeNs t_ns = 0;
  std::vector<InstantObservation> observations;  // two or more cameras
};

struct WandInstants {
  std::vector<WandInstant> instants;  // ascending, one step apart (gaps where < 2 cameras saw it)
  // The instants are the cameras' own frames (every frame of every camera on one grid), not
  // interpolations between them.
  bool synchronised = false;
};

struct InstantOptions {
  double sample_rate_hz = 0.0;  // 0: the fastest camera's rate
  double max_gap_frames = 1.6;  // a track is interpolated only between frames this close
};

// `tracks` one per camera (empty where a camera has none); only cameras with usable[c] take part.
// Instants with fewer than two observations are left out.
WandInstants sample_wand_instants(const std::vector<CameraWandTrack>& tracks, const std::vector<bool>& usable,
                                  const InstantOptions& options);

// The pixel of `marker` an observation shows when its camera's clock is `offset_s` ahead of the
// reference clock.
inline Eigen::Vector2d observed_pixel(const InstantObservation& observation, std::size_t marker,
                                      double offset_s) {
  return evaluate_segment(observation.segment, marker, offset_s - observation.shift_s);
}

}  // namespace panoptes::calib
