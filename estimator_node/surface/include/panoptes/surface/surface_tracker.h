// SPDX-License-Identifier: Apache-2.0
// Surface tracking (seed 003 §2.3.2, LumiPoint): laser spots on a wall, seen by several
// asynchronous cameras, become strokes. Each camera frame's spots are mapped onto the surface
// (image_to_surface.h); a spot is one constant-acceleration Kalman filter in surface coordinates
// (the measurement is linear after the mapping: H = [I 0 0], R = J Σ_pixel Jᵀ, as the seed notes),
// fused over every camera that sees it, so overlapping views give one stroke, not two. The
// association is the estimator's gated global-nearest-neighbour step (estimator/assignment.h).
// A new spot begins a stroke once it is confirmed; a stroke ends when no camera has seen it for
// `end_after_ns`. Core only: no DDS, no I/O. docs/surface.md.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "panoptes/surface/image_to_surface.h"
#include "panoptes/time.h"

namespace panoptes::surface {

struct SurfaceTrackerOptions {
  double pixel_sigma = 0.2;           // spot centroid noise, pixels
  double jerk_noise = 2000.0;         // white-jerk spectral density, m²/s⁵ (hand-held pointers)
  double initial_speed_sigma = 3.0;   // m/s, a new spot's velocity prior
  double initial_accel_sigma = 30.0;  // m/s²
  double gate_chi2 = 13.82;           // 2 degrees of freedom, 99.9%
  int confirm_updates = 2;            // a spot begins a stroke after this many updates
  TimeNs end_after_ns = 30'000'000;   // a stroke ends when unseen this long ...
  // ... by every camera that saw it: each must have delivered a frame that much newer than the
  // stroke's last update (a camera whose frames are delayed, and dropped as late, does not end it),
  // or this long must have passed (a camera that stopped sending).
  TimeNs camera_wait_ns = 250'000'000;
  double duplicate_distance_m = 0.005;  // an unexplained spot this close to a stroke is the same spot
};

enum class StrokePhase : std::uint8_t { kBegin, kContinue, kEnd };

// One stroke event. kBegin carries the stamp and position of the stroke's first spot; kEnd those
// of its last update; kContinue the filtered state at each update.
struct StrokeEvent {
  StrokePhase phase = StrokePhase::kContinue;
  std::uint32_t stroke_id = 0;
  TimeNs stamp_ns = 0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();      // m, surface frame
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();      // m/s
  Eigen::Vector2d acceleration = Eigen::Vector2d::Zero();  // m/s²
  int camera = -1;                                         // the camera whose frame caused it
  int cameras = 0;  // distinct cameras that updated the stroke within end_after_ns of its stamp
};

// Why spots and frames were not used, counted (docs/surface.md).
struct SurfaceCounters {
  std::uint64_t frames = 0;
  std::uint64_t spots = 0;
  std::uint64_t late_frames = 0;          // older than a frame already processed: dropped
  std::uint64_t unknown_camera = 0;       // a camera index without a mapping: dropped
  std::uint64_t off_surface = 0;          // mapped outside the surface's extent: ignored
  std::uint64_t unmappable = 0;           // beyond the plane's horizon, or not finite: ignored
  std::uint64_t duplicate_spots = 0;      // a second spot on one stroke in one frame
  std::uint64_t unconfirmed_dropped = 0;  // new spots that never became strokes
  std::uint64_t strokes_begun = 0;
  std::uint64_t strokes_ended = 0;
};

class SurfaceTracker {
 public:
  // `cameras[i]` maps camera i's pixels; `surface` gives the extent spots must fall in.
  SurfaceTracker(SurfacePlane surface, std::vector<ImageToSurface> cameras,
                 SurfaceTrackerOptions options = {});
  ~SurfaceTracker();
  SurfaceTracker(SurfaceTracker&&) noexcept;
  SurfaceTracker& operator=(SurfaceTracker&&) noexcept;
  SurfaceTracker(const SurfaceTracker&) = delete;
  SurfaceTracker& operator=(const SurfaceTracker&) = delete;

  // One frame of camera `camera` at `stamp_ns` (mid-exposure) with its spots' pixel centroids.
  // Frames must come in stamp order across cameras (the estimator's inbox orders them); an older
  // one is counted and dropped. Returns the events it causes, in order.
  std::vector<StrokeEvent> add_frame(int camera, TimeNs stamp_ns, std::span<const Eigen::Vector2d> pixels);
  // Ends the strokes unseen for end_after_ns at `now_ns` (call when no frames arrive).
  std::vector<StrokeEvent> end_silent(TimeNs now_ns);

  const SurfaceCounters& counters() const { return counters_; }
  const SurfaceTrackerOptions& options() const { return options_; }
  const SurfacePlane& surface() const { return surface_; }
  std::size_t active_strokes() const;

 private:
  struct Spot;
  // `by_cameras`: the camera-aware rule of add_frame; otherwise end_after_ns alone (end_silent).
  void end_stale(TimeNs now_ns, bool by_cameras, std::vector<StrokeEvent>& events);
  void begin_stroke(Spot& spot, std::vector<StrokeEvent>& events);

  SurfacePlane surface_;
  std::vector<ImageToSurface> cameras_;
  SurfaceTrackerOptions options_;
  std::vector<Spot> spots_;
  SurfaceCounters counters_;
  TimeNs last_stamp_ns_ = 0;
  bool started_ = false;
  std::vector<TimeNs> camera_stamp_ns_;  // per camera: its newest processed frame
  std::uint32_t next_id_ = 1;
};

}  // namespace panoptes::surface
