// SPDX-License-Identifier: Apache-2.0
// What the estimator did with each camera's frames: received, used (in order or replayed), late,
// dropped by reason, latency from stamp to arrival, and the tracker's time per frame. The node
// publishes it as rt/panoptes/estimator_status and prints it at exit. Camera health (live or lost)
// is judged from the wall time of each camera's last arrival, which the caller passes in: no DDS
// and no clock reads here.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "panoptes/estimator/calibration_health.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

class Tracker;
struct CameraCounters;

// Quantiles of positive durations in log-spaced bins (0.1 µs to 1000 s, 2% wide): constant memory.
class DurationHistogram {
 public:
  void add(double milliseconds);
  double quantile_ms(double q) const;  // 0 when empty
  std::uint64_t count() const { return count_; }

 private:
  static constexpr int kBins = 1200;
  std::array<std::uint64_t, kBins> bins_{};
  std::uint64_t count_ = 0;
};

// Whether a camera's frames still reach the estimator (docs/estimator.md, "Camera health").
enum class CameraState : std::uint8_t {
  kLive = 0,     // a frame arrived within the lost threshold
  kLost = 1,     // none for longer than the threshold
  kUnknown = 2,  // no arrival times (offline runs) or no `now` given
};
const char* to_string(CameraState state);

struct CameraUsage {
  std::string camera_id;
  std::uint64_t frames = 0;  // received by the estimator
  std::uint64_t used = 0;
  std::uint64_t late = 0;
  std::uint64_t dropped = 0;   // screened out, too late, uncalibrated or lost in the inbox
  std::uint64_t too_late = 0;  // of those, older than the rewind horizon
  std::uint64_t blobs = 0;
  std::uint64_t associated = 0;
  double utilisation = 0;  // used / frames
  double latency_p50_ms = 0;
  double latency_p99_ms = 0;
  TimeNs last_stamp_ns = 0;
  CameraState state = CameraState::kUnknown;
  double since_last_frame_s = -1;     // wall time since its last arrival; -1: unknown
  std::uint64_t refused_frames = 0;   // from a second writer claiming this id (camera_ownership.h)
  std::uint32_t refused_writers = 0;  // such writers
};

struct EstimatorUsage {
  TimeNs stamp_ns = 0;
  std::size_t tracks_tentative = 0, tracks_confirmed = 0, tracks_coasting = 0;
  // Cameras by state (health known only with a `now`), and the tracks held while every known
  // camera is lost: predictions that no camera can confirm.
  std::size_t cameras_live = 0, cameras_lost = 0, tracks_unobserved = 0;
  std::uint64_t frames = 0;
  std::uint64_t replays = 0;          // rewinds (one per burst of late frames)
  std::uint64_t replayed_frames = 0;  // frames applied again by them
  // Rates over the last status period and the process's CPU, set by the live node (0 offline).
  double replays_per_s = 0, replayed_frames_per_s = 0, cpu_percent = 0;
  double update_p50_ms = 0, update_p99_ms = 0;
  double latency_window_ms = 0;
  std::vector<CameraUsage> cameras;
  std::map<std::string, std::uint64_t> counters;  // dropped frames and blobs by reason
  // Each camera's calibration health (empty with continuous calibration off).
  std::vector<CameraCalibrationHealth> calibration;

  // One line per camera: "camera <id>: frames N used N late N dropped N utilisation U latency
  // p50 X ms p99 Y ms" (tests parse it), then "calibration <id>: <state> <reason>" for each camera
  // not ok, then one with the drop reasons.
  std::vector<std::string> lines() const;
};

class UsageMonitor {
 public:
  // A frame reached the estimator `latency_ms` after its stamp (negative: clocks disagree; NaN:
  // unknown, not part of the latency statistics).
  // `arrival_ns`: the wall time it arrived (0: unknown, as offline), for the camera's health.
  void note_received(const std::string& camera_id, double latency_ms, TimeNs arrival_ns = 0);
  // A frame refused because another writer owns its camera id; `new_writer`: the first from it.
  void note_refused(const std::string& camera_id, bool new_writer);
  // A camera is lost after this long without a frame (wall time).
  void set_lost_after(TimeNs lost_after_ns) { lost_after_ns_ = lost_after_ns; }
  // Cameras lost at wall time `now_ns` (cheap: no tracker), for prompt status on a loss.
  std::size_t cameras_lost(TimeNs now_ns) const;
  // A frame or blob did not reach the tracker (screen, inbox overflow), by reason.
  void note_dropped(const std::string& camera_id, const std::string& reason, std::uint64_t frames = 1);
  void note_reason(const std::string& reason, std::uint64_t n);
  void note_update_time(double milliseconds) { update_.add(milliseconds); }

  // The tracker's per-camera counters, and `other_cameras`' (cameras whose frames bypass the
  // point tracker: the moving cameras of inside-out mode) counted the same way. `now_ns`: the wall
  // time for the cameras' health (0: health unknown).
  EstimatorUsage summarize(const Tracker& tracker, TimeNs stamp_ns, double latency_window_ms,
                           const std::map<std::string, CameraCounters>& other_cameras = {},
                           TimeNs now_ns = 0) const;

 private:
  struct PerCamera {
    std::uint64_t received = 0;
    std::uint64_t dropped_before_tracker = 0;
    std::uint64_t refused_frames = 0;
    std::uint32_t refused_writers = 0;
    TimeNs last_arrival_ns = 0;
    DurationHistogram latency;
  };
  PerCamera& camera(const std::string& camera_id);
  // Fills the health of `usage`'s cameras and the counts by state at `now_ns`.
  void judge_health(EstimatorUsage& usage, TimeNs now_ns) const;
  std::map<std::string, PerCamera> cameras_;
  std::map<std::string, std::uint64_t> reasons_;
  DurationHistogram update_;
  TimeNs lost_after_ns_ = 500'000'000;
};

}  // namespace panoptes::estimator
