// SPDX-License-Identifier: Apache-2.0
// Multi-point tracker: one-camera-at-a-time EKF over asynchronous cameras (seed 003 §2.2.3).
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/estimator/point_ekf.h"
#include "panoptes/records.h"

namespace panoptes::estimator {

struct TrackerOptions {
  double process_noise = 50.0;         // σ² of white acceleration, m²/s³ (seed 003 A.48)
  double measurement_noise_px = 0.5;   // σ of a centroid, px (seed 003 A.30)
  double gate_chi2 = 18.42;            // χ²₂ at p = 0.9999: the verify region (seed 003 §2.2.3.2)
  TimeNs init_window_ns = 30'000'000;  // unmatched blobs of other cameras this recent may pair
  double init_reprojection_px = 3.0;   // a candidate must reproject this well in every camera used
  double init_position_sigma_m = 0.01;
  double init_velocity_sigma_mps = 2.0;
  int confirm_cameras = 3;             // distinct cameras that must update a track to confirm it
  TimeNs coast_after_ns = 50'000'000;  // no update for this long: coasting
  TimeNs delete_after_ns = 300'000'000;
  TimeNs tentative_delete_after_ns = 100'000'000;
  double merge_distance_m = 0.005;               // two tracks closer than this are one marker
  TimeNs recent_camera_window_ns = 500'000'000;  // for TrackRecord::cameras
  double min_depth_m = 0.05;                     // candidates closer to a camera are rejected

  void print(std::ostream& out) const;
};

struct TrackerStats {
  std::uint64_t frames = 0;
  std::uint64_t frames_unknown_camera = 0;  // no calibration for the camera: ignored
  std::uint64_t frames_late = 0;            // older than the last processed frame: dropped
  std::uint64_t blobs = 0;
  std::uint64_t blobs_associated = 0;
  std::uint64_t tracks_created = 0;
  std::uint64_t tracks_confirmed = 0;
  std::uint64_t tracks_deleted = 0;
  std::uint64_t tracks_merged = 0;
};

enum class FrameOutcome { kProcessed, kUnknownCamera, kLate };

class Tracker {
 public:
  explicit Tracker(TrackerOptions options = {});

  // Cameras without T_world_cam are ignored (their frames count as unknown).
  void set_calibration(const SystemCalibration& calibration);
  void set_camera(const CameraCalibration& camera);
  bool has_camera(const std::string& camera_id) const;

  // Processes one camera frame (stamps must not decrease; an older frame is counted and dropped).
  FrameOutcome process(const FeatureFrame& frame);

  // Published tracks (confirmed or coasting), predicted to `stamp_ns`.
  std::vector<TrackRecord> tracks_at(TimeNs stamp_ns) const;
  // Published tracks at the last processed frame's stamp.
  std::vector<TrackRecord> current_tracks() const { return tracks_at(last_stamp_ns_); }
  TimeNs last_stamp_ns() const { return last_stamp_ns_; }
  std::size_t live_track_count() const { return tracks_.size(); }

  const TrackerStats& stats() const { return stats_; }
  const TrackerOptions& options() const { return options_; }

 private:
  struct Track {
    std::int64_t id = 0;
    PointState state;
    TimeNs created_ns = 0;
    TimeNs last_update_ns = 0;
    std::uint64_t updates = 0;
    bool confirmed = false;
    std::map<std::string, TimeNs> camera_last_update;  // camera id -> stamp
  };
  struct PendingBlob {
    std::string camera_id;
    TimeNs stamp_ns = 0;
    Eigen::Vector2d pixel;
  };

  void associate_and_update(const FeatureFrame& frame, const CameraModel& camera, std::vector<bool>& used);
  void initiate(const FeatureFrame& frame, const CameraModel& camera, const std::vector<bool>& used);
  void note_update(Track& track, const std::string& camera_id, TimeNs stamp_ns);
  void prune(TimeNs now_ns);
  TrackRecord to_record(const Track& track, TimeNs stamp_ns) const;

  TrackerOptions options_;
  std::map<std::string, CameraModel> cameras_;
  std::vector<Track> tracks_;
  std::deque<PendingBlob> pending_;
  std::int64_t next_id_ = 1;
  TimeNs last_stamp_ns_ = 0;
  TrackerStats stats_;
};

}  // namespace panoptes::estimator
