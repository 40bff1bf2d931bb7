// SPDX-License-Identifier: Apache-2.0
// estimator_node in surface mode (docs/surface.md): camera features -> SurfaceTracker -> strokes.
// Offline over feature files (--no-dds --in-features ... --out-strokes), or live: features from
// rt/panoptes/features, strokes on rt/panoptes/strokes, counters in rt/panoptes/estimator_status,
// the time service for the cameras. A thin adapter over panoptes_surface.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "panoptes/dds/security.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/offline_replay.h"
#include "panoptes/surface_app/surface_settings.h"

namespace panoptes::surface_app {

// A stroke event as one JSON line: {"stamp_ns", "phase": "begin"|"continue"|"end", "id",
// "p": [s, t], "v": [.., ..], "a": [.., ..], "cameras", "camera"} (metres, m/s, m/s²).
std::string stroke_json_line(const surface::StrokeEvent& event, const std::string& camera_id);

// The counters as estimator_status names them ("surface_off_surface", ...).
std::map<std::string, std::uint64_t> surface_counters(const surface::SurfaceCounters& counters);
// A frame's blob centroids.
std::vector<Eigen::Vector2d> spot_pixels(const FeatureFrame& frame);

// Every frame in stamp order through the tracker; strokes to `out_strokes` (empty: none).
// Returns the exit code.
int run_surface_offline(SurfaceSetup& setup, session::FeatureFiles input, const std::string& out_strokes,
                        bool quiet);

struct SurfaceLiveOptions {
  std::string dds_profile;        // empty: the loopback profile
  dds::SecurityOptions security;  // docs/security.md
  std::string out_strokes;        // optional Stroke JSONL
  double duration_s = 0.0;        // 0: until a stop signal
  double latency_window_ms = 10.0;
  bool quiet = false;
};

// Runs until a stop signal or the duration; `session` screens the received frames (bad input is
// counted, as in tracking mode). Returns the exit code.
int run_surface_live(const SurfaceLiveOptions& options, SurfaceSetup& setup,
                     session::EstimatorSession& session);

}  // namespace panoptes::surface_app
