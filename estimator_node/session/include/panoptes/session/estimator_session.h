// SPDX-License-Identifier: Apache-2.0
// EstimatorSession: admit frames -> screen -> inbox -> tracker (and its bodies). The one object
// that live mode (app/), offline mode (offline_replay.h), tests and benchmarks drive, so they all
// see the same screening, ordering and statistics. Outputs are the caller's: it reads the tracker
// after each processed frame and writes to its sinks (JSONL here, DDS in the app).
#pragma once

#include <functional>
#include <vector>

#include <cstddef>
#include <cstdint>

#include "panoptes/estimator/inbox.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/records.h"
#include "panoptes/session/estimator_config.h"
#include "panoptes/session/inside_out_cameras.h"
#include "panoptes/session/intake.h"

namespace panoptes::session {

class EstimatorSession {
 public:
  explicit EstimatorSession(const EstimatorConfig& config);
  EstimatorSession(const EstimatorSession&) = delete;
  EstimatorSession& operator=(const EstimatorSession&) = delete;

  const EstimatorConfig& config() const { return config_; }
  // For calibration and bodies before the run; the owning thread only once frames flow.
  estimator::Tracker& tracker() { return tracker_; }
  const estimator::Tracker& tracker() const { return tracker_; }

  // Any thread. Screens `frame` against `reference_ns` (see Intake::admit); false: rejected.
  bool admit(FeatureFrame& frame, TimeNs reference_ns, bool live) {
    return intake_.admit(frame, reference_ns, live);
  }
  // Any thread. Screens, then queues an admitted frame for ordering by stamp.
  bool offer(FeatureFrame&& frame, TimeNs reference_ns, bool live) {
    if (!intake_.admit(frame, reference_ns, live)) return false;
    inbox_.push(std::move(frame));
    return true;
  }
  estimator::FrameInbox& inbox() { return inbox_; }

  // Moving cameras and their landmarks (inside-out mode); before the run.
  InsideOutCameras& inside_out() { return inside_out_; }
  const InsideOutCameras& inside_out() const { return inside_out_; }

  // The owning thread: one tracker update (a moving camera's frame: its rig's update).
  estimator::FrameOutcome process(const FeatureFrame& frame) {
    if (inside_out_.handles(frame.camera_id)) return inside_out_.process(frame);
    const auto outcome = intake_.process(frame);
    if (!inside_out_.empty()) inside_out_.observe_fixed(frame);
    return outcome;
  }
  // The owning thread: frames taken from the inbox together (oldest first). Those older than the
  // newest processed frame go to the tracker as one batch (one rewind and replay for the burst);
  // then the others one at a time. `each` sees every frame right after its update, so the outputs
  // of in-order frames follow their own update; `before`, if given, runs before each update (the
  // batch's one included): the live loop's fixed-rate frame goes out there rather than wait for it.
  void process_due(std::vector<FeatureFrame>& due,
                   const std::function<void(FeatureFrame&, estimator::FrameOutcome)>& each,
                   const std::function<void()>& before = {});

  // `wall_now_ns`: the wall time for the cameras' health (0: unknown, offline).
  estimator::EstimatorUsage usage(TimeNs stamp_ns, TimeNs wall_now_ns = 0) const {
    return intake_.usage(stamp_ns, inbox_.drops(), inside_out_.camera_counters(), wall_now_ns);
  }
  // Any thread. A frame refused because another writer owns its camera id (camera_ownership.h).
  void note_refused(const std::string& camera_id, bool new_writer) {
    intake_.note_refused(camera_id, new_writer);
  }
  // Any thread. Cameras lost at wall time `now_ns`.
  std::size_t cameras_lost(TimeNs now_ns) const { return intake_.cameras_lost(now_ns); }
  void print_summary(std::size_t bad_lines) const;

  // Body poses at the newest frame, predicted node.prediction_horizon_ms ahead; then the poses of
  // the rigs of moving cameras at the newest frame of any camera.
  std::vector<PoseRecord> current_poses() const;
  // The same at `instant_ns` (a fixed-rate frame's instant, docs/frames.md), predicted from the
  // newest state.
  std::vector<PoseRecord> poses_at(TimeNs instant_ns) const;

 private:
  EstimatorConfig config_;
  estimator::Tracker tracker_;
  Intake intake_;
  estimator::FrameInbox inbox_;
  TimeNs pose_horizon_ns_;
  InsideOutCameras inside_out_;
};

}  // namespace panoptes::session
