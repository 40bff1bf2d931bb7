// SPDX-License-Identifier: Apache-2.0
// Pan/tilt/zoom guidance (seed 003 §2.3.3): a PTZ camera model with mechanical limits and command
// latency, the guidance that turns a tracked point (position, velocity, stamp) into commands aimed
// at where the point will be when the command takes effect, and a simulated PTZ head that obeys
// the limits, so that framing can be measured (docs/ptz.md). No DDS, no files (ptz_file.h reads
// the model).
//
// Geometry: the head sits at `position` with a level base; pan turns about world +z from the base
// direction `base_yaw` (0: looking along world +x), tilt raises the optical axis above the
// horizontal. The image is a pinhole of `width` x `height` pixels whose horizontal field of view
// is the zoom; x to the right, y down.
#pragma once

#include <deque>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "panoptes/time.h"

namespace panoptes::ptz {

struct AxisLimits {
  double min_rad = 0.0;
  double max_rad = 0.0;
  double max_speed_radps = 0.0;
  double max_accel_radps2 = 0.0;
};

struct PtzModel {
  std::string name = "ptz";
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, m: the centre of rotation
  double base_yaw_rad = 0.0;                           // pan 0 looks along this world heading
  AxisLimits pan{-3.0, 3.0, 1.0472, 2.0944};           // ±172°, 60°/s, 120°/s²
  AxisLimits tilt{-1.0, 1.0, 1.0472, 2.0944};
  double fov_min_rad = 0.035;      // horizontal field of view at full zoom (2°)
  double fov_max_rad = 1.05;       // wide (60°)
  double zoom_speed_radps = 0.5;   // rate of change of the field of view
  double command_latency_s = 0.1;  // from a command's issue to the head acting on it
  int width = 1920;
  int height = 1080;
};

// Why a model is unusable ("" when usable): limits inverted, speeds not positive, a zoom range
// outside (0, π), a negative latency, an empty image.
std::string model_problem(const PtzModel& model);

// Where the head points and how wide it sees.
struct PtzPose {
  double pan = 0.0;
  double tilt = 0.0;
  double fov = 0.5;
};

// Pan and tilt that put `world` on the optical axis (not clamped to the limits).
PtzPose aim_at(const PtzModel& model, const Eigen::Vector3d& world);

// `world` in the image of a head at `pose`; nullopt behind the camera.
std::optional<Eigen::Vector2d> image_point(const PtzModel& model, const PtzPose& pose,
                                           const Eigen::Vector3d& world);

// A command: aim at (pan, tilt) at the moment it takes effect, moving on at (pan_rate, tilt_rate)
// (the target's angular velocity, so that the head follows a moving target without lag), and
// zoom to `fov`.
struct PtzCommand {
  TimeNs issued_ns = 0;
  double pan = 0.0;
  double tilt = 0.0;
  double pan_rate = 0.0;
  double tilt_rate = 0.0;
  double fov = 0.5;
};

struct GuideOptions {
  bool predict = true;        // false: aim at the last measured position, no rates
  double lookahead_s = -1.0;  // predicted this far past `now` (< 0: the command latency)
  double framing_m = 0.5;     // width of the scene the image should span at the target
  Eigen::Vector3d aim_offset = Eigen::Vector3d::Zero();  // added to the tracked point (e.g. marker -> head)
};

// The command to issue at `now_ns` for a point measured at `stamp_ns` with position `p` and
// velocity `v` (world, m and m/s). With prediction the point is extrapolated to now + lookahead:
// the time the measurement already has plus the time the command will take.
PtzCommand guide_command(const PtzModel& model, const GuideOptions& options, TimeNs now_ns, TimeNs stamp_ns,
                         const Eigen::Vector3d& p, const Eigen::Vector3d& v);

// A simulated head: commands act `command_latency_s` after their issue; each axis follows the
// commanded (moving) set-point with its speed and acceleration limits (brakes in time to stop on
// it), the zoom at its speed; angles stay inside the limits.
class PtzSimulator {
 public:
  PtzSimulator(const PtzModel& model, const PtzPose& initial, TimeNs start_ns);
  void send(const PtzCommand& command);
  // Integrates to `t_ns` (steps of at most 1 ms).
  void advance_to(TimeNs t_ns);
  const PtzPose& pose() const { return pose_; }
  double pan_rate() const { return pan_rate_; }
  double tilt_rate() const { return tilt_rate_; }

 private:
  void step(double dt);

  PtzModel model_;
  PtzPose pose_;
  double pan_rate_ = 0.0;
  double tilt_rate_ = 0.0;
  TimeNs now_ns_ = 0;
  std::deque<PtzCommand> pending_;
  std::optional<PtzCommand> active_;
  TimeNs active_since_ns_ = 0;
};

}  // namespace panoptes::ptz
