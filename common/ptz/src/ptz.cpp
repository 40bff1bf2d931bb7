// SPDX-License-Identifier: Apache-2.0
#include "panoptes/ptz/ptz.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace panoptes::ptz {

namespace {

double wrap_angle(double a) {
  return std::remainder(a, 2.0 * std::numbers::pi);
}

std::string axis_problem(const char* axis, const AxisLimits& limits) {
  const std::string name = axis;
  if (!std::isfinite(limits.min_rad) || !std::isfinite(limits.max_rad) || limits.min_rad >= limits.max_rad)
    return name + ": min must be below max";
  if (limits.min_rad < -std::numbers::pi || limits.max_rad > std::numbers::pi)
    return name + ": limits must lie within ±180°";
  if (!(limits.max_speed_radps > 0.0) || !std::isfinite(limits.max_speed_radps))
    return name + ": max_speed must be positive";
  if (!(limits.max_accel_radps2 > 0.0) || !std::isfinite(limits.max_accel_radps2))
    return name + ": max_accel must be positive";
  return "";
}

// The axes of a head at `pose`: optical axis (forward), image x (right) and image y (down).
struct Axes {
  Eigen::Vector3d forward, right, down;
};

Axes axes_of(const PtzModel& model, const PtzPose& pose) {
  const double heading = model.base_yaw_rad + pose.pan;
  Axes axes;
  axes.forward = {std::cos(pose.tilt) * std::cos(heading), std::cos(pose.tilt) * std::sin(heading),
                  std::sin(pose.tilt)};
  axes.right = {std::sin(heading), -std::cos(heading), 0.0};
  axes.down = axes.forward.cross(axes.right);
  return axes;
}

// One axis following a set-point that moves at `setpoint_rate`: the speed wanted is the set-point's
// plus what closes the error while still able to brake onto it (√(2 a |e|)), limited in speed and
// reached within the acceleration limit.
void servo(double& angle, double& rate, double setpoint, double setpoint_rate, const AxisLimits& limits,
           double dt) {
  const double error = setpoint - angle;
  const double closing =
      std::min(std::sqrt(2.0 * limits.max_accel_radps2 * std::abs(error)), std::abs(error) / dt);
  const double wanted = std::clamp(setpoint_rate + std::copysign(closing, error), -limits.max_speed_radps,
                                   limits.max_speed_radps);
  rate += std::clamp(wanted - rate, -limits.max_accel_radps2 * dt, limits.max_accel_radps2 * dt);
  angle += rate * dt;
  if (angle < limits.min_rad) {
    angle = limits.min_rad;
    rate = std::max(rate, 0.0);
  } else if (angle > limits.max_rad) {
    angle = limits.max_rad;
    rate = std::min(rate, 0.0);
  }
}

}  // namespace

std::string model_problem(const PtzModel& model) {
  if (!model.position.allFinite()) return "position: not finite";
  if (!std::isfinite(model.base_yaw_rad)) return "base_yaw: not finite";
  if (auto problem = axis_problem("pan", model.pan); !problem.empty()) return problem;
  if (auto problem = axis_problem("tilt", model.tilt); !problem.empty()) return problem;
  if (!(model.fov_min_rad > 0.0) || !(model.fov_max_rad < std::numbers::pi) ||
      !(model.fov_min_rad <= model.fov_max_rad))
    return "zoom: need 0 < fov_min <= fov_max < 180°";
  if (!(model.zoom_speed_radps > 0.0) || !std::isfinite(model.zoom_speed_radps))
    return "zoom: speed must be positive";
  if (!(model.command_latency_s >= 0.0) || !(model.command_latency_s < 10.0))
    return "command_latency: must be in [0, 10) s";
  if (model.width < 16 || model.height < 16) return "image: width and height must be at least 16 pixels";
  return "";
}

PtzPose aim_at(const PtzModel& model, const Eigen::Vector3d& world) {
  const Eigen::Vector3d d = world - model.position;
  PtzPose pose;
  pose.pan = wrap_angle(std::atan2(d.y(), d.x()) - model.base_yaw_rad);
  pose.tilt = std::atan2(d.z(), std::hypot(d.x(), d.y()));
  return pose;
}

std::optional<Eigen::Vector2d> image_point(const PtzModel& model, const PtzPose& pose,
                                           const Eigen::Vector3d& world) {
  const Axes axes = axes_of(model, pose);
  const Eigen::Vector3d q = world - model.position;
  const double depth = q.dot(axes.forward);
  if (depth <= 1e-6) return std::nullopt;
  const double focal = 0.5 * model.width / std::tan(0.5 * pose.fov);
  return Eigen::Vector2d(0.5 * model.width + focal * q.dot(axes.right) / depth,
                         0.5 * model.height + focal * q.dot(axes.down) / depth);
}

PtzCommand guide_command(const PtzModel& model, const GuideOptions& options, TimeNs now_ns, TimeNs stamp_ns,
                         const Eigen::Vector3d& p, const Eigen::Vector3d& v) {
  const double lookahead = options.lookahead_s < 0.0 ? model.command_latency_s : options.lookahead_s;
  const double ahead = options.predict ? ns_to_seconds(now_ns - stamp_ns) + lookahead : 0.0;
  const Eigen::Vector3d target = p + ahead * v + options.aim_offset;
  const PtzPose aim = aim_at(model, target);
  PtzCommand command;
  command.issued_ns = now_ns;
  command.pan = aim.pan;
  command.tilt = aim.tilt;
  const Eigen::Vector3d d = target - model.position;
  const double horizontal2 = d.x() * d.x() + d.y() * d.y();
  if (options.predict && horizontal2 > 1e-12) {
    const double horizontal = std::sqrt(horizontal2);
    command.pan_rate = (d.x() * v.y() - d.y() * v.x()) / horizontal2;
    command.tilt_rate = (horizontal * v.z() - d.z() * (d.x() * v.x() + d.y() * v.y()) / horizontal) /
                        (horizontal2 + d.z() * d.z());
  }
  const double distance = std::max(d.norm(), 1e-3);
  command.fov =
      std::clamp(2.0 * std::atan(0.5 * options.framing_m / distance), model.fov_min_rad, model.fov_max_rad);
  return command;
}

PtzSimulator::PtzSimulator(const PtzModel& model, const PtzPose& initial, TimeNs start_ns)
    : model_(model), pose_(initial), now_ns_(start_ns) {
  pose_.pan = std::clamp(pose_.pan, model_.pan.min_rad, model_.pan.max_rad);
  pose_.tilt = std::clamp(pose_.tilt, model_.tilt.min_rad, model_.tilt.max_rad);
  pose_.fov = std::clamp(pose_.fov, model_.fov_min_rad, model_.fov_max_rad);
}

void PtzSimulator::send(const PtzCommand& command) {
  pending_.push_back(command);
}

void PtzSimulator::advance_to(TimeNs t_ns) {
  constexpr TimeNs kStepNs = 1'000'000;
  const TimeNs latency_ns = seconds_to_ns(model_.command_latency_s);
  while (now_ns_ < t_ns) {
    const TimeNs next = std::min(t_ns, now_ns_ + kStepNs);
    // Commands take effect in issue order once their latency has passed.
    while (!pending_.empty() && pending_.front().issued_ns + latency_ns <= next) {
      active_ = pending_.front();
      active_since_ns_ = pending_.front().issued_ns + latency_ns;
      pending_.pop_front();
    }
    step(ns_to_seconds(next - now_ns_));
    now_ns_ = next;
  }
}

void PtzSimulator::step(double dt) {
  if (!active_ || dt <= 0.0) return;
  const double since = ns_to_seconds(now_ns_ - active_since_ns_);
  const auto follow = [&](double& angle, double& rate, double target, double target_rate,
                          const AxisLimits& limits) {
    double setpoint = target + target_rate * since;
    double setpoint_rate = target_rate;
    if (setpoint <= limits.min_rad || setpoint >= limits.max_rad) {
      setpoint = std::clamp(setpoint, limits.min_rad, limits.max_rad);
      setpoint_rate = 0.0;
    }
    servo(angle, rate, setpoint, setpoint_rate, limits, dt);
  };
  follow(pose_.pan, pan_rate_, active_->pan, active_->pan_rate, model_.pan);
  follow(pose_.tilt, tilt_rate_, active_->tilt, active_->tilt_rate, model_.tilt);
  const double zoom_step = model_.zoom_speed_radps * dt;
  const double fov_target = std::clamp(active_->fov, model_.fov_min_rad, model_.fov_max_rad);
  pose_.fov += std::clamp(fov_target - pose_.fov, -zoom_step, zoom_step);
}

}  // namespace panoptes::ptz
