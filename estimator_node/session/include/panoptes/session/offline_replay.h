// SPDX-License-Identifier: Apache-2.0
// Offline mode (architecture.md, Contracts: --no-dds --in-features <files...> --out-tracks <file>):
// reads FeatureFrame JSONL files and delivers every frame to an EstimatorSession, by stamp or, as
// live mode would (--replay-arrival), by the time each frame reached the estimator through the
// session's time-ordered inbox with simulated time.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "panoptes/jsonl.h"
#include "panoptes/session/chain_stage.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/label_stage.h"
#include "panoptes/session/output_sinks.h"

namespace panoptes::session {

struct FeatureFiles {
  std::vector<FeatureFrame> frames;  // in file order
  std::size_t bad_lines = 0;         // malformed lines, skipped (the first five are logged)
};
// Throws (naming the file) when a file cannot be read.
FeatureFiles read_feature_files(const std::vector<std::string>& paths);

// Stamp order; ties broken by camera and frame number so a run is deterministic.
void sort_by_stamp(std::vector<FeatureFrame>& frames);

// Order of delivery of `frames` (indices): as they are, or by arrival (received_ns; a frame
// without one arrives at its stamp), stable among equal arrivals.
std::vector<std::size_t> delivery_order(const std::vector<FeatureFrame>& frames, bool by_arrival);

struct OfflineReplayOptions {
  bool by_arrival = false;  // --replay-arrival
  bool show_progress = true;
  // Articulated chains of the bodies file (docs/articulated.md; --out-chains): fed every frame
  // the tracker processed. Null: none.
  ChainStage* chains = nullptr;
  // Live auto-labelling (--subjects, docs/marker_sets.md): fed every frame the tracker processed.
  LabelStage* labels = nullptr;
  // Called before each frame is offered with the replay's clock: the frame's arrival
  // (received_ns) with by_arrival, else its stamp (the offline timing model of docs/frames.md).
  std::function<void(TimeNs)> clock = nullptr;
};

// Every frame the tracker was given, with what it did with it.
using DeliveredFrame = std::function<void(const FeatureFrame&, estimator::FrameOutcome)>;

// Screens `frames` (sorted by stamp) against their neighbours' stamps and delivers them to
// `session` in delivery order (through the inbox with `by_arrival`, drained at the end).
void replay_frames(EstimatorSession& session, std::vector<FeatureFrame>& frames,
                   const OfflineReplayOptions& options, const DeliveredFrame& delivered);

// The whole offline run: read, replay, write tracks and poses (JsonlOutputs: an empty path writes
// nothing) as each frame is processed, print the summary. Returns the exit code (kExitBadInput for
// an unreadable input file; then no output file is created).
int run_offline(EstimatorSession& session, const std::vector<std::string>& feature_files,
                const OfflineReplayOptions& options, const std::string& out_tracks,
                const std::string& out_poses);
// Fixed-rate output offline (docs/frames.md): with node.frames "fixed", before each frame reaches
// the tracker, every grid instant up to the replay's clock gets its tracks and poses predicted
// from the newest state (FrameClock::next_due).
// The same run over frames already read (estimator_node --in-recording reads them from MCAP).
int run_offline(EstimatorSession& session, FeatureFiles input, const OfflineReplayOptions& options,
                const std::string& out_tracks, const std::string& out_poses);

}  // namespace panoptes::session
