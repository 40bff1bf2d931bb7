// SPDX-License-Identifier: Apache-2.0
// Inside-out tracking (seed 000 §6.2): a camera that moves with the user (head-mounted) sees
// landmarks fixed in the room, and its own 6-DoF pose is tracked from its frames alone. The
// filter is the rigid-body EKF (body_ekf.h) with the measurement turned round: the "body" is the
// rig the camera is mounted on, and each update is one known world landmark's projection through
// the moving camera (landmark_pixel). Landmarks come in constellations (a few markers in a known
// arrangement); a cold start needs no prior: every blob triple is matched to each
// constellation's widest triangle by P3P (panoptes/p3p.h), and the hypothesis that reprojects the
// most landmarks onto blobs wins. docs/inside_out.md.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"
#include "panoptes/estimator/body_ekf.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

// A known arrangement of landmarks, world frame (surveyed, or from an outside-in calibration).
struct Constellation {
  std::string name;
  std::vector<Eigen::Vector3d> landmarks;  // at least 3, not all collinear (when `identifies`)
  // false: single fixed markers and the like, used once tracking but never to identify from a
  // cold start (a constellation's widest triangle is the P3P anchor).
  bool identifies = true;
};

// A landmark's pixel in a camera mounted on a rig at `T_world_rig`, with the 2×6 Jacobian with
// respect to the rig's position (columns 0-2) and its rig-frame rotation error δθ (3-5), the
// body filter's convention. `camera_in_rig`'s T_world_cam() is read as T_rig_cam. Nullopt when
// the landmark is closer than `min_depth_m` or behind the camera.
std::optional<MarkerPixel> landmark_pixel(const RigidTransform& T_world_rig,
                                          const Eigen::Vector3d& landmark_world,
                                          const CameraModel& camera_in_rig, double min_depth_m = 0.05);

struct InsideOutOptions {
  double pixel_sigma = 0.1;                  // blob centroid noise, px
  BodyMotionNoise motion{50.0, 0.1, 100.0};  // a walking, turning head
  double gate_chi2 = 13.82;                  // association gate, 2 degrees of freedom (99.9%)
  double acquire_inlier_px = 2.0;            // a hypothesis's landmark counts when a blob is this close
  int acquire_min_landmarks = 4;             // landmarks a cold-start hypothesis must explain
  int track_min_landmarks = 3;               // fewer matched in a frame: the frame does not update
  TimeNs lost_after_ns = 200'000'000;        // no update this long: lost, acquire again
};

struct InsideOutPose {
  TimeNs stamp_ns = 0;
  RigidTransform T_world_rig;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          // world frame, m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // rig frame, rad/s
  int landmarks = 0;                                           // matched in this frame
  bool acquired = false;                                       // this frame was a cold start
};

struct InsideOutCounters {
  std::uint64_t frames = 0;
  std::uint64_t acquisitions = 0;  // cold starts that succeeded
  std::uint64_t failed_acquisitions = 0;
  std::uint64_t updates = 0;  // landmark updates
  std::uint64_t frames_without_update = 0;
  std::uint64_t lost = 0;
  std::uint64_t late_frames = 0;         // older than the filter: dropped
  std::uint64_t outside_in_updates = 0;  // rig-marker updates from fixed cameras
};

class InsideOutTracker {
 public:
  // Throws std::invalid_argument naming the constellation when one that identifies has fewer than
  // three landmarks or they are collinear, or when none identifies.
  InsideOutTracker(std::vector<Constellation> constellations, CameraModel camera_in_rig,
                   InsideOutOptions options = {});

  // One frame's blob centroids (pixels, distorted as the camera delivers them). Returns the pose
  // at the frame's stamp when tracking (after this frame's update), nullopt while not acquired.
  std::optional<InsideOutPose> add_frame(TimeNs stamp_ns, std::span<const Eigen::Vector2d> pixels);

  // Fusion with outside-in (issue 21): a fixed camera's frame showing markers carried by the rig
  // (`rig_markers`, rig frame; `fixed_camera` with its world pose). Each marker's projection is the
  // rigid-body measurement (body_ekf.h's marker_pixel) and updates the same filter, gated and
  // assigned as the landmarks are. Only while tracking: a cold start needs the moving camera.
  // Returns the markers that updated (0 also for a late frame, counted).
  int add_outside_in_frame(TimeNs stamp_ns, const CameraModel& fixed_camera,
                           std::span<const Eigen::Vector3d> rig_markers,
                           std::span<const Eigen::Vector2d> pixels);

  bool tracking() const { return state_.has_value(); }
  // The filter's state (pose, rates, covariance) while tracking.
  const std::optional<BodyState>& state() const { return state_; }
  const InsideOutCounters& counters() const { return counters_; }
  // The constellation the last cold start identified (empty before).
  const std::string& acquired_from() const { return acquired_from_; }
  // Stamp of the last frame that updated the filter (0 before).
  TimeNs last_update_ns() const { return last_update_ns_; }
  const InsideOutOptions& options() const { return options_; }

 private:
  struct Landmark {
    Eigen::Vector3d world;
    int constellation = 0;
  };
  std::optional<RigidTransform> acquire(std::span<const Eigen::Vector2d> pixels);
  int update(BodyState& state, std::span<const Eigen::Vector2d> pixels) const;
  int count_inliers(const RigidTransform& T_world_rig, std::span<const Eigen::Vector2d> pixels) const;

  std::vector<Constellation> constellations_;
  std::vector<Landmark> landmarks_;
  std::vector<std::optional<std::array<int, 3>>> widest_triangles_;  // per constellation that identifies
  CameraModel camera_in_rig_;
  RigidTransform T_rig_cam_;
  InsideOutOptions options_;
  std::optional<BodyState> state_;
  TimeNs last_update_ns_ = 0;
  InsideOutCounters counters_;
  std::string acquired_from_;
};

}  // namespace panoptes::estimator
