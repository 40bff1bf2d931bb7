// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/wand_samples.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace panoptes::calib {

WandInstants sample_wand_instants(const std::vector<CameraWandTrack>& tracks, const std::vector<bool>& usable,
                                  const InstantOptions& options) {
  WandInstants out;
  TimeNs first = std::numeric_limits<TimeNs>::max(), last = std::numeric_limits<TimeNs>::min();
  double period = 1e9;
  for (std::size_t c = 0; c < tracks.size(); ++c) {
    if (!usable[c]) continue;
    first = std::min(first, tracks[c].frames.front().stamp_ns);
    last = std::max(last, tracks[c].frames.back().stamp_ns);
    if (tracks[c].frame_period_s > 0) period = std::min(period, tracks[c].frame_period_s);
  }
  if (first >= last) return out;
  const double rate = options.sample_rate_hz > 0 ? options.sample_rate_hz : 1.0 / period;
  const auto step = static_cast<TimeNs>(std::llround(1e9 / rate));
  // Synchronised cameras (every frame stamped on one grid of that period): the instants are the
  // frames themselves, so every observation is a raw frame, not an interpolation.
  bool synchronised = options.sample_rate_hz <= 0 && step > 0;
  for (std::size_t c = 0; c < tracks.size() && synchronised; ++c) {
    if (!usable[c]) continue;
    for (const auto& frame : tracks[c].frames)
      synchronised = synchronised && (frame.stamp_ns - first) % step == 0;
  }
  out.synchronised = synchronised;
  // Otherwise start half a step in so that instants fall between frames of cameras running at that
  // rate, where interpolation is well conditioned on both sides.
  for (TimeNs t = first + (synchronised ? 0 : step / 2); synchronised ? t <= last : t < last; t += step) {
    WandInstant instant;
    instant.t_ns = t;
    for (std::size_t c = 0; c < tracks.size(); ++c) {
      if (!usable[c]) continue;
      const double max_gap = options.max_gap_frames * tracks[c].frame_period_s;
      if (auto segment = find_segment(tracks[c], t, max_gap))
        instant.observations.push_back({static_cast<int>(c), std::move(*segment), 0.0, true});
    }
    if (instant.observations.size() >= 2) out.instants.push_back(std::move(instant));
  }
  return out;
}

}  // namespace panoptes::calib
