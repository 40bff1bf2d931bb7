// SPDX-License-Identifier: Apache-2.0
// Intake: everything between a received frame and the tracker, the same in offline and live mode:
// the screen for bad input (frame_screen.h), the usage statistics (usage.h), the tracker's time per
// frame and the warning about uncalibrated cameras. admit() may run on DDS listener threads,
// process() on the one thread that owns the tracker; the lock covers only the screen and the
// statistics, so listeners never wait for a tracker update.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "panoptes/estimator/frame_screen.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/estimator/usage.h"
#include "panoptes/records.h"

namespace panoptes::session {

// Warns once per camera (up to 64 cameras) about frames the tracker cannot use.
class UnknownCameraWarnings {
 public:
  void note(const std::string& camera_id);

 private:
  std::set<std::string> warned_;
};

class Intake {
 public:
  Intake(estimator::Tracker& tracker, const estimator::FrameScreenOptions& screen, double latency_window_ms);

  // Screens a frame that arrived at `frame.received_ns` (0: unknown) against `reference_ns`.
  // False: rejected and counted. Live frames are also rejected when stamped ahead of the wall
  // clock (`live`). Any thread.
  bool admit(FeatureFrame& frame, TimeNs reference_ns, bool live);

  // Tracker update, timed. The tracker's thread only.
  estimator::FrameOutcome process(const FeatureFrame& frame);
  // Tracker::process_batch, timed as one update. The tracker's thread only.
  std::vector<estimator::FrameOutcome> process_batch(std::span<const FeatureFrame> frames);

  // Usage so far: the monitor's summary plus the screen's drop reasons and inbox overflows (the
  // tracker's thread only: reads the tracker).
  // `other_cameras`: counters of cameras whose frames bypass the tracker (inside-out rigs).
  // `wall_now_ns`: the wall time for the cameras' health (0: unknown).
  estimator::EstimatorUsage usage(TimeNs stamp_ns, std::uint64_t inbox_drops,
                                  const std::map<std::string, estimator::CameraCounters>& other_cameras = {},
                                  TimeNs wall_now_ns = 0) const;
  // Camera health (usage.h): the lost threshold, refused frames, and the lost count. Any thread.
  void set_lost_after(TimeNs lost_after_ns);
  void note_refused(const std::string& camera_id, bool new_writer);
  std::size_t cameras_lost(TimeNs wall_now_ns) const;

  std::uint64_t frames_rejected() const;

  // The closing lines of a run (processed, usage per camera, bodies).
  void print_summary(std::uint64_t inbox_drops, std::size_t bad_lines,
                     const std::map<std::string, estimator::CameraCounters>& other_cameras = {}) const;

 private:
  estimator::Tracker& tracker_;
  estimator::FrameScreen screen_;
  estimator::UsageMonitor monitor_;
  UnknownCameraWarnings warnings_;
  double latency_window_ms_;
  mutable std::mutex mutex_;  // screen_ and monitor_
};

}  // namespace panoptes::session
