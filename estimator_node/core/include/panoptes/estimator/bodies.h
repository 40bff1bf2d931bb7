// SPDX-License-Identifier: Apache-2.0
// Rigid-body tracking (issue 5; design in docs/bodies.md). BodySet owns every defined body's
// state: identification from the point tracker's confirmed 3D points (body_identification.h) or,
// for 7-LED markers, from one camera's blobs (led_marker.h); then a 6-DoF EKF per body
// (body_ekf.h) updated one camera frame at a time with each marker's projection. A body seen by a
// single camera, or by cameras that each see a single marker, keeps being updated.
// BodySet is a value type: the tracker copies it into its rewind checkpoints.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/camera_model.h"
#include "panoptes/estimator/body_ekf.h"
#include "panoptes/estimator/body_identification.h"
#include "panoptes/estimator/body_smoother.h"
#include "panoptes/estimator/led_marker.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

struct BodyTrackerOptions {
  BodyMotionNoise noise;
  double measurement_noise_px = 0.3;  // σ of a marker's centroid in the body filter
  double gate_chi2 = 13.82;           // χ²₂ at p = 0.999 for a marker's blob
  IdentificationOptions identification;
  TimeNs identify_interval_ns = 20'000'000;  // how often untracked bodies are looked for
  TimeNs verify_interval_ns = 100'000'000;   // how often a tracked body is checked against the points
  double verify_position_m = 0.01;           // identification and EKF disagree by more: re-identify
  double verify_angle_rad = 0.0873;          // (5°)
  TimeNs lost_after_ns = 250'000'000;        // no marker update for this long: lost
  double max_nis = 6.0;                      // moving average of a marker's d²: above it, lost
  // Adaptive process noise (docs/bodies.md, "Speed"): each body scales `noise` by its own factor
  // in [1, process_noise_max_scale], multiplied by exp(process_noise_adapt_gain × (c − c₀)) at
  // every marker update, c the correlation of successive innovations of a marker in a camera
  // (moving averages with weight process_noise_adapt_weight per update) and c₀
  // process_noise_adapt_correlation: up while the filter lags, down while its innovations are
  // (nearly) white. max_scale 1: off (the fixed `noise`).
  double process_noise_max_scale = 100.0;
  double process_noise_adapt_gain = 0.1;
  double process_noise_adapt_weight = 0.05;
  double process_noise_adapt_correlation = 0.05;
  double init_position_sigma_m = 0.002;
  double init_velocity_sigma_mps = 0.2;
  double init_accel_sigma_mps2 = 5.0;
  double init_angle_sigma_rad = 0.02;
  double init_angular_velocity_sigma = 1.0;  // rad/s
  double init_angular_accel_sigma = 10.0;    // rad/s² (used only when noise.angular_jerk > 0)
  TimeNs quality_window_ns = 100'000'000;    // BodyPose quality: markers seen in this window
  // > 0: poses are reported this far behind the newest frame, smoothed with the frames that came
  // after them (fixed-lag RTS, body_smoother.h); 0: the filter's pose at the newest frame.
  TimeNs smoothing_ns = 0;
  // 7-LED marker detection; centroid_sigma and max_rms are derived from measurement_noise_px and
  // each camera's focal length, so their values here are not used.
  LedMarkerOptions led_marker;
};

struct BodyStats {
  std::uint64_t identified = 0;          // acquisitions from 3D points
  std::uint64_t acquired_monocular = 0;  // acquisitions from a single camera (7-LED markers)
  std::uint64_t reidentified = 0;        // tracked pose contradicted by identification: restarted
  std::uint64_t lost = 0;
  std::uint64_t marker_updates = 0;  // marker projections applied
  std::uint64_t markers_gated_out = 0;
};

// A 3D point the point tracker is confident of (input to identification).
struct TrackedPoint {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  double sigma_m = 0.0;
};

class BodySet {
 public:
  BodySet();
  // Validated definitions (validate_body); states of bodies whose name and markers are unchanged
  // are kept, others start untracked.
  void set_definitions(std::vector<BodyDefinition> definitions, const BodyTrackerOptions& options);
  std::size_t size() const;
  bool empty() const { return size() == 0; }
  // In the order given to set_definitions (the bodies file's).
  const std::vector<BodyDefinition>& definitions() const;

  // One camera frame: every tracked body's markers are projected, gated and assigned to blobs
  // (Hungarian over all bodies' markers), and each assigned marker updates its body. `excluded`
  // marks blobs that may not be used (non-finite); blobs a body took are marked in `taken`.
  // Untracked 7-LED bodies are looked for among this frame's blobs.
  void process_frame(int camera_index, const CameraModel& camera, TimeNs stamp_ns,
                     const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& excluded,
                     std::vector<char>& taken);

  // Identification of untracked bodies (and verification of tracked ones) from 3D points, rate-
  // limited by identify_interval_ns / verify_interval_ns.
  void identify(TimeNs stamp_ns, const std::vector<TrackedPoint>& points);
  bool wants_points(TimeNs stamp_ns) const;

  // Poses of the tracked bodies at `stamp_ns` (at `stamp_ns` − smoothing_ns when smoothing, the
  // record's stamp says which), extrapolated `horizon_ns` further (seed 000 Ch. 5). `smoothed`
  // false: the filter's poses at `stamp_ns` whatever smoothing_ns (e.g. to label markers).
  std::vector<PoseRecord> poses_at(TimeNs stamp_ns, TimeNs horizon_ns = 0, bool smoothed = true) const;
  std::size_t tracked_count() const;
  const BodyStats& stats() const;

 private:
  struct Shared;  // definitions and options (immutable; shared by copies)
  struct Body;
  void acquire_monocular(int camera_index, const CameraModel& camera, TimeNs stamp_ns,
                         const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& excluded,
                         std::vector<char>& taken);
  // identify()'s steps. Points near a tracked body's predicted pose go to `near_body[b]`; those on
  // one of its markers are marked in `claimed`.
  void claim_points_of_tracked(TimeNs stamp_ns, const std::vector<TrackedPoint>& points,
                               std::vector<char>& claimed, std::vector<std::vector<int>>& near_body) const;
  void verify_tracked(TimeNs stamp_ns, const std::vector<TrackedPoint>& points,
                      const std::vector<MeasuredPoint>& measured,
                      const std::vector<std::vector<int>>& near_body);
  void acquire_untracked(TimeNs stamp_ns, const std::vector<TrackedPoint>& points,
                         const std::vector<MeasuredPoint>& measured, std::vector<char>& claimed);
  // Restarts body `b` at an identification of it; `point_index` maps the match's points to `points`.
  void start_from_match(std::size_t b, const BodyMatch& match, const std::vector<int>& point_index,
                        const std::vector<TrackedPoint>& points, TimeNs stamp_ns);
  std::shared_ptr<const Shared> shared_;
  std::vector<Body> bodies_;
  BodyStats stats_;
  TimeNs last_identify_ns_ = 0;
  TimeNs last_verify_ns_ = 0;
  bool identified_once_ = false;

 public:
  BodySet(const BodySet&);
  BodySet& operator=(const BodySet&);
  BodySet(BodySet&&) noexcept;
  BodySet& operator=(BodySet&&) noexcept;
  ~BodySet();
};

}  // namespace panoptes::estimator
