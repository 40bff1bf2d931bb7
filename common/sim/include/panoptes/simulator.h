// SPDX-License-Identifier: Apache-2.0
// Deterministic simulator of IR cameras observing moving markers and rigid bodies.
// Scene files: see docs/simulator.md and deploy/scenes/. Scene time is nanoseconds since the
// scene start on the true clock; callers add an epoch to get absolute stamps.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/formats/trc.h"
#include "panoptes/image.h"
#include "panoptes/landmarks.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes {

struct SimCameraConfig {
  CameraCalibration calibration;  // always has T_world_cam
  double rate_hz = 100.0;
  TimeNs phase_ns = 0;         // scene time of frame 0's mid-exposure
  TimeNs clock_offset_ns = 0;  // camera clock minus true clock
  TimeNs exposure_ns = 1'000'000;
  double pixel_noise_dn = 1.0;     // Gaussian sensor noise, DN (of `bits`)
  double centroid_noise_px = 0.0;  // jitter of each rendered spot centre, px
  double background_dn = 8.0;
  double blob_peak_dn = 220.0;       // peak of a spot of minimum size
  double blob_min_sigma_px = 1.0;    // spots never render smaller than this
  double dropout_probability = 0.0;  // each marker missing from a frame at random
  int bits = 8;                      // 8, 10, 12 or 16
  double false_blobs = 0.0;          // mean number of spurious blobs per frame (Poisson)
  double merge_distance_px = 0.0;    // spots with centres closer than this form one blob; 0: off
  // Delivery to the estimator: end of exposure + latency + a jitter drawn per frame from an
  // exponential distribution of mean latency_jitter_ns (network and scheduling; reorders frames
  // of different cameras), plus a late delay for late_fraction of the frames
  // (FeatureFrame::received_ns).
  TimeNs latency_ns = 2'000'000;
  TimeNs latency_jitter_ns = 0;
  double late_fraction = 0.0;
  TimeNs late_delay_min_ns = 5'000'000;
  TimeNs late_delay_max_ns = 30'000'000;
  // A bump (camera key `bump`, issue 36): from scene time bump_at_ns on, the camera's true pose is
  // T_world_cam · bump (a turn and shift in the camera's own frame). The calibration keeps the
  // pose from before: what a knocked tripod does to a calibrated system.
  bool bumped = false;
  TimeNs bump_at_ns = 0;
  RigidTransform bump;
  // A slow drift (camera key `drift`, issue 36 item 6): from scene time drift_from_ns on the
  // camera turns about drift_axis (its own frame, unit) at drift_rate_rad_s and moves at
  // drift_velocity_m_s (its own frame): T_world_cam · drift(t) (· bump). A truss warming up.
  bool drifting = false;
  TimeNs drift_from_ns = 0;
  Eigen::Vector3d drift_axis = Eigen::Vector3d::UnitX();
  double drift_rate_rad_s = 0.0;
  Eigen::Vector3d drift_velocity_m_s = Eigen::Vector3d::Zero();
};

struct MarkerTruth {
  std::string name;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  bool valid = true;  // false where the source (e.g. a TRC gap) has no data
  // Self-occlusion (trc.occlusion): the marker is hidden from a camera whose direction, seen from
  // the marker, is more than facing_angle_rad away from `normal`. A zero normal: seen from anywhere.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double facing_angle_rad = 0.0;
};

struct BodyTruth {
  std::string name;
  RigidTransform T_world_body;
};

// An articulated chain of the scene (`chains:`, docs/articulated.md) at one instant.
struct ChainTruth {
  std::string name;
  RigidTransform T_world_base;
  std::vector<double> angles;            // joint angles, rad
  std::vector<Eigen::Vector3d> markers;  // world, base first
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
};

// TRC playback reads marker files through the formats library (C3D too: docs/simulator.md).
using TrcData = MarkerTrajectories;

class Scene {
 public:
  // Throws ConfigError naming the file and key.
  static Scene load(const std::filesystem::path& path);
  static Scene from_yaml_string(const std::string& yaml, const std::filesystem::path& base_dir = ".",
                                const std::string& name_for_errors = "<string>");
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  ~Scene();

  std::uint64_t seed() const;
  TimeNs duration_ns() const;
  const std::vector<SimCameraConfig>& cameras() const;
  const SimCameraConfig* find_camera(std::string_view id) const;
  SystemCalibration calibration() const;

  // Every point marker, including those of bodies (named "<body>/<index>"), in a fixed order.
  const std::vector<std::string>& marker_names() const;
  std::vector<MarkerTruth> markers_at(TimeNs scene_time_ns) const;
  // The bodies' poses, then the rigs' of moving cameras (camera key `rig`, docs/inside_out.md).
  std::vector<BodyTruth> bodies_at(TimeNs scene_time_ns) const;
  std::vector<BodyDefinition> body_definitions() const;
  // A camera's pose in the world: its T_world_cam, or for a camera on a rig (calibration.moving,
  // whose T_world_cam is then its mount T_rig_cam) the rig's pose times the mount.
  // A bumped camera's pose is its bump applied from bump_at_ns on.
  RigidTransform camera_pose_at(std::size_t camera_index, TimeNs scene_time_ns) const;
  // Bumps camera `camera_index` at `at_ns` (as the camera key `bump` does): for tests.
  void set_camera_bump(std::size_t camera_index, TimeNs at_ns, const RigidTransform& bump);
  // Gives camera `camera_index` a slow drift (as the camera key `drift` does; `axis` in the
  // camera's frame, normalised here; a zero axis draws one from the scene seed and the camera).
  void set_camera_drift(std::size_t camera_index, TimeNs from_ns, double degrees_per_minute,
                        const Eigen::Vector3d& axis, const Eigen::Vector3d& millimetres_per_minute);
  // The markers a rig carries (camera key rig.markers, rig frame), by rig name; simulated as
  // markers "<rig>/<index>" after the bodies'.
  std::map<std::string, std::vector<Eigen::Vector3d>> rig_markers() const;
  // The names of the rigs that carry moving cameras, in camera order.
  std::vector<std::string> rig_names() const;
  // The scene's `landmarks` (fixed markers whose positions a moving camera's tracking knows).
  const std::vector<LandmarkGroup>& landmarks() const;
  std::vector<ChainTruth> chains_at(TimeNs scene_time_ns) const;
  double marker_radius(std::size_t marker_index) const;

 private:
  Scene();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class CameraSimulator {
 public:
  // Throws std::invalid_argument if the scene has no such camera. The scene must outlive this.
  CameraSimulator(const Scene& scene, std::string_view camera_id);

  const SimCameraConfig& config() const { return *config_; }
  // True scene time of frame k's mid-exposure.
  TimeNs frame_time_ns(std::int64_t k) const;
  // The frames whose mid-exposure lies in [from_ns, to_ns) of scene time: k in [first, end).
  // Every program that runs a scene takes its frames from here (docs/simulator.md: `duration`).
  struct FrameRange {
    std::int64_t first = 0;
    std::int64_t end = 0;
  };
  FrameRange frames_in(TimeNs from_ns, TimeNs to_ns) const;
  // Stamp frame k carries on the camera's own clock (scene time + clock offset).
  TimeNs frame_stamp_ns(std::int64_t k) const;
  // Renders frame k: Gaussian spots integrated over each pixel, background, sensor noise.
  // Deterministic for (scene seed, camera, k).
  Image render(std::int64_t k) const;
  // Frame k as ideal features (no rendering): projected centres plus centroid noise, markers
  // outside the image, hidden or dropped omitted, false blobs added, spots closer than
  // merge_distance merged. stamp_ns = frame_stamp_ns(k) and received_ns = frame_received_ns(k)
  // (both relative to the epoch).
  FeatureFrame features(std::int64_t k) const;
  // Indices into Scene::marker_names() of the markers whose spot frame k shows (before merging;
  // the same decision features() and render() make), ascending.
  std::vector<int> visible_markers(std::int64_t k) const;
  // Number of false blobs (false_blobs) frame k shows, before merging.
  int false_blob_count(std::int64_t k) const;
  // True scene time at which frame k reaches the estimator: end of exposure + latency, plus a
  // random late delay for a late_fraction of the frames. Deterministic for (seed, camera, k).
  TimeNs frame_received_ns(std::int64_t k) const;

 private:
  const Scene* scene_;
  const SimCameraConfig* config_;
  std::size_t camera_index_ = 0;
};

}  // namespace panoptes
