// SPDX-License-Identifier: Apache-2.0
// Live mode of estimator_node: an EstimatorSession fed by rt/panoptes/features (DDS listener
// threads screen frames into the session's inbox) and run on one estimator thread that publishes
// rt/panoptes/tracks, predictions, body poses, chains and estimator_status, serves rt/panoptes/time_sync,
// applies calibrations announced by CameraInfo and reloads the bodies file when it changes.
#pragma once

#include <string>

#include "panoptes/dds/security.h"
#include "panoptes/session/body_file.h"
#include "panoptes/session/chain_stage.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/label_stage.h"
#include "panoptes/session/segment_stage.h"

namespace panoptes::estimator_app {

struct LiveOptions {
  std::string dds_profile;        // empty: the loopback profile
  dds::SecurityOptions security;  // DDS Security files (docs/security.md)
  bool shared_memory = false;     // keep the profile's shared-memory transport (BusOptions)
  std::string calibration_file;   // cameras in it are not recalibrated from their CameraInfo
  std::string out_tracks;         // optional Track JSONL
  std::string out_poses;          // optional Pose JSONL
  double duration_s = 0.0;        // 0: until a stop signal
  bool latency_probe = false;     // benchmark aid (latency_probe_echoer.h)
  bool quiet = false;
  // Articulated chains of the bodies file (docs/articulated.md): fed every processed frame and
  // published on rt/panoptes/chains. Null: none.
  session::ChainStage* chains = nullptr;
  // Auto-labelling (--subjects, docs/marker_sets.md): fed every processed frame. Null: none.
  session::LabelStage* labels = nullptr;
  // With labels: each frame's segment poses, published like bodies (docs/marker_sets.md,
  // "Segment poses live"). Null: none.
  const session::SegmentStage* segments = nullptr;
};

// Runs until a stop signal (panoptes::stop_requested) or the duration; returns the exit code.
int run_live(const LiveOptions& options, session::EstimatorSession& session, session::BodyFile& body_file);

}  // namespace panoptes::estimator_app
