// SPDX-License-Identifier: Apache-2.0
// Articulated chains in a session (docs/articulated.md): the `type: chain` entries of the bodies
// file tracked by an estimator::ChainTracker beside the point tracker. After each camera frame
// the tracker processed, untracked chains are searched for among the confirmed point tracks, the
// frame updates the tracked chains, and (with --out-chains) one Chain JSONL record per chain and
// one per grab/release event is written. Counts the statuses for the closing summary.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/chain_definition.h"
#include "panoptes/estimator/chain.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/jsonl.h"
#include "panoptes/records.h"

namespace panoptes::session {

class ChainStage {
 public:
  // `out_path` empty: nothing is written. Throws if the file cannot be opened.
  ChainStage(std::vector<ChainDefinition> chains, const SystemCalibration& calibration,
             const std::string& out_path, const estimator::ChainTrackerOptions& options = {});

  // A fixed camera learnt after the start (live: announced by its CameraInfo). A moving camera or
  // one without T_world_cam is ignored; a camera already known keeps its model.
  void add_camera(const CameraCalibration& camera);

  // One camera frame that `tracker` has just processed (stamp order; an older frame or one from
  // an uncalibrated camera is counted and skipped: false).
  bool observe(const FeatureFrame& frame, const estimator::Tracker& tracker);

  // After observe() returned true: every chain at that frame (bodies-file order), the same
  // predicted `prediction_horizon_s` ahead (empty when the horizon is 0), and the events that frame
  // caused. Live mode publishes them on rt/panoptes/chains.
  const std::vector<estimator::ChainOutput>& outputs() const { return outputs_; }
  const std::vector<estimator::ChainOutput>& predicted_outputs() const { return predicted_; }
  const std::vector<estimator::NamedGrabEvent>& events() const { return events_; }
  void set_prediction_horizon(double horizon_s) { prediction_horizon_s_ = horizon_s; }
  double prediction_horizon_s() const { return prediction_horizon_s_; }

  // Writes out what is buffered (the end of a run).
  void flush() {
    if (out_) out_->flush();
  }

  // "chains: <name> tracking N, ambiguous N, not identified N (frames); G grabs, R releases; ..."
  std::string summary() const;

 private:
  struct Counts {
    std::uint64_t tracking = 0;
    std::uint64_t ambiguous = 0;
    std::uint64_t not_identified = 0;
    std::uint64_t grabs = 0;
    std::uint64_t releases = 0;
  };
  void write(const std::vector<estimator::ChainOutput>& outputs,
             const std::vector<estimator::NamedGrabEvent>& events);

  std::vector<std::string> names_;
  estimator::ChainTracker tracker_;
  std::map<std::string, CameraModel> cameras_;
  std::optional<JsonlWriter> out_;
  std::map<std::string, Counts> counts_;
  TimeNs last_stamp_ns_ = 0;
  std::uint64_t frames_skipped_ = 0;
  std::uint64_t records_ = 0;
  bool all_tracking_ = false;
  double prediction_horizon_s_ = 0.0;
  std::vector<estimator::ChainOutput> outputs_;
  std::vector<estimator::ChainOutput> predicted_;
  std::vector<estimator::NamedGrabEvent> events_;
};

}  // namespace panoptes::session
