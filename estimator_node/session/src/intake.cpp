// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/intake.h"

#include <chrono>
#include <limits>

#include "panoptes/session/log.h"

namespace panoptes::session {

namespace est = panoptes::estimator;

void UnknownCameraWarnings::note(const std::string& camera_id) {
  if (warned_.size() < 64 && warned_.insert(camera_id).second) {
    log("camera '" + camera_id + "' has no calibration (T_world_cam): its frames are counted and ignored");
  }
}

Intake::Intake(est::Tracker& tracker, const est::FrameScreenOptions& screen, double latency_window_ms)
    : tracker_(tracker), screen_(screen), latency_window_ms_(latency_window_ms) {}

bool Intake::admit(FeatureFrame& frame, TimeNs reference_ns, bool live) {
  // In double: garbage stamps must not overflow.
  const double latency_ms =
      frame.received_ns != 0
          ? (static_cast<double>(frame.received_ns) - static_cast<double>(frame.stamp_ns)) * 1e-6
          : std::numeric_limits<double>::quiet_NaN();  // unknown
  std::lock_guard<std::mutex> lock(mutex_);
  monitor_.note_received(frame.camera_id, latency_ms, frame.received_ns);
  if (live ? screen_.screen_live(frame, reference_ns) : screen_.screen(frame, reference_ns)) return true;
  monitor_.note_dropped(frame.camera_id, "", 1);  // the reason is in the screen's counts
  return false;
}

est::FrameOutcome Intake::process(const FeatureFrame& frame) {
  return process_batch({&frame, 1}).front();
}

std::vector<est::FrameOutcome> Intake::process_batch(std::span<const FeatureFrame> frames) {
  const auto start = std::chrono::steady_clock::now();
  auto outcomes = tracker_.process_batch(frames);
  const double elapsed_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    monitor_.note_update_time(elapsed_ms);
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (outcomes[i] == est::FrameOutcome::kUnknownCamera) warnings_.note(frames[i].camera_id);
  }
  return outcomes;
}

void Intake::set_lost_after(TimeNs lost_after_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  monitor_.set_lost_after(lost_after_ns);
}

void Intake::note_refused(const std::string& camera_id, bool new_writer) {
  std::lock_guard<std::mutex> lock(mutex_);
  monitor_.note_refused(camera_id, new_writer);
}

std::size_t Intake::cameras_lost(TimeNs wall_now_ns) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return monitor_.cameras_lost(wall_now_ns);
}

est::EstimatorUsage Intake::usage(TimeNs stamp_ns, std::uint64_t inbox_drops,
                                  const std::map<std::string, est::CameraCounters>& other_cameras,
                                  TimeNs wall_now_ns) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto usage = monitor_.summarize(tracker_, stamp_ns, latency_window_ms_, other_cameras, wall_now_ns);
  for (const auto& [reason, n] : screen_.counts()) usage.counters[reason] += n;
  if (inbox_drops) usage.counters["inbox_overflow"] += inbox_drops;
  return usage;
}

std::uint64_t Intake::frames_rejected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return screen_.stats().frames_rejected;
}

void Intake::print_summary(std::uint64_t inbox_drops, std::size_t bad_lines,
                           const std::map<std::string, est::CameraCounters>& other_cameras) const {
  const auto& s = tracker_.stats();
  const std::uint64_t rejected = frames_rejected();
  log("processed " + std::to_string(s.frames) + " frames (" + std::to_string(s.frames_late) +
      " late and replayed, " + std::to_string(s.frames_too_late) + " too late, " +
      std::to_string(s.frames_unknown_camera) + " from uncalibrated cameras, " + std::to_string(rejected) +
      " rejected, " + std::to_string(bad_lines) + " malformed lines); tracks created " +
      std::to_string(s.tracks_created) + ", confirmed " + std::to_string(s.tracks_confirmed) +
      ", ghosts removed " + std::to_string(s.ghosts_deleted) +
      (s.one_view_ghosts_deleted > 0
           ? " (and one-view ghosts " + std::to_string(s.one_view_ghosts_deleted) + ")"
           : std::string()) +
      ", reacquired " + std::to_string(s.tracks_reacquired) + " (" +
      std::to_string(s.tracks_reacquired_by_neighbours) + " by neighbours), re-anchored " +
      std::to_string(s.tracks_reanchored) +
      (s.input_pauses > 0
           ? "; input paused " + std::to_string(s.input_pauses) + " times (every camera at once)"
           : std::string()) +
      (s.manoeuvres_recovered + s.fast_tracks_rejoined + s.runaway_tracks_deleted > 0
           ? "; fast tracks: manoeuvres recovered " + std::to_string(s.manoeuvres_recovered) + ", rejoined " +
                 std::to_string(s.fast_tracks_rejoined) + ", runaways deleted " +
                 std::to_string(s.runaway_tracks_deleted)
           : std::string()) +
      (s.return_velocities_capped > 0
           ? "; velocities capped at a return to two views " + std::to_string(s.return_velocities_capped)
           : std::string()) +
      (s.ray_twin_waits > 0 ? "; blobs left to ray twins " + std::to_string(s.ray_twin_waits)
                            : std::string()) +
      (s.owned_blobs_kept > 0 ? "; blobs kept for their owners " + std::to_string(s.owned_blobs_kept)
                              : std::string()) +
      (s.returns_beyond_reach > 0 ? "; second views beyond reach " + std::to_string(s.returns_beyond_reach)
                                  : std::string()) +
      (s.returns_far_from_carried > 0
           ? "; second views far from the carried point " + std::to_string(s.returns_far_from_carried)
           : std::string()) +
      (s.returns_fresh_far > 0 ? "; fresh second views too far " + std::to_string(s.returns_fresh_far)
                               : std::string()) +
      (s.one_view_depths_pinned > 0
           ? "; one-view depths from the neighbours " + std::to_string(s.one_view_depths_pinned)
           : std::string()) +
      (s.fast_off_partner > 0
           ? "; blobs off a fast track's rigid partner " + std::to_string(s.fast_off_partner)
           : std::string()) +
      (s.views_disputed > 0 ? "; odd views disputed " + std::to_string(s.views_disputed) : std::string()));
  for (const auto& line : usage(tracker_.last_stamp_ns(), inbox_drops, other_cameras).lines()) log(line);
  if (tracker_.body_count() > 0) {
    const auto& b = tracker_.body_stats();
    log("bodies: identified " + std::to_string(b.identified) + ", acquired by one camera " +
        std::to_string(b.acquired_monocular) + ", re-identified " + std::to_string(b.reidentified) +
        ", lost " + std::to_string(b.lost) + ", marker updates " + std::to_string(b.marker_updates) +
        "; tracked now " + std::to_string(tracker_.current_poses().size()) + "/" +
        std::to_string(tracker_.body_count()));
  }
}

}  // namespace panoptes::session
