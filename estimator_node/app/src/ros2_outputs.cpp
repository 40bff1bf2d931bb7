// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/ros2_outputs.h"

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "panoptes/geometry.h"
#include "panoptes/session/log.h"

namespace panoptes::estimator_app {

namespace ros2 = geometry_msgs::msg::dds_;
namespace mocap = mocap4r2_msgs::msg::dds_;

builtin_interfaces::msg::dds_::Time_ to_ros2_time(TimeNs stamp_ns) {
  TimeNs seconds = stamp_ns / kNsPerSecond;
  TimeNs nanoseconds = stamp_ns % kNsPerSecond;
  if (nanoseconds < 0) {  // C++ division truncates towards zero; ROS 2 wants nanosec >= 0
    nanoseconds += kNsPerSecond;
    --seconds;
  }
  builtin_interfaces::msg::dds_::Time_ time;
  if (seconds > std::numeric_limits<std::int32_t>::max()) {
    time.sec(std::numeric_limits<std::int32_t>::max());
    time.nanosec(static_cast<std::uint32_t>(kNsPerSecond - 1));
  } else if (seconds < std::numeric_limits<std::int32_t>::min()) {
    time.sec(std::numeric_limits<std::int32_t>::min());
    time.nanosec(0);
  } else {
    time.sec(static_cast<std::int32_t>(seconds));
    time.nanosec(static_cast<std::uint32_t>(nanoseconds));
  }
  return time;
}

std::string ros2_name_token(const std::string& body_name) {
  std::string token;
  token.reserve(body_name.size());
  for (const char c : body_name) {
    const bool allowed =
        std::isalnum(static_cast<unsigned char>(c)) != 0 && static_cast<unsigned char>(c) < 128;
    if (allowed) {
      token += c;
    } else if (!token.empty() && token.back() != '_') {
      token += '_';  // also drops leading '_'
    }
  }
  while (!token.empty() && token.back() == '_') token.pop_back();
  if (token.empty()) return "body";
  if (std::isdigit(static_cast<unsigned char>(token.front())) != 0) token.insert(0, "body_");
  return token;
}

// ---------------------------------------------------------------------------------------------
// Ros2Messages

namespace {

// A pose is for its stamp plus the prediction horizon it was extrapolated over.
TimeNs pose_time(const session::BodyOutput& body) {
  return body.pose.stamp_ns + body.pose.horizon_ns;
}

// geometry_msgs Point_ or Vector3_ (the same three members).
template <class Xyz>
Xyz xyz(const Eigen::Vector3d& v) {
  Xyz out;
  out.x(v.x());
  out.y(v.y());
  out.z(v.z());
  return out;
}

ros2::Quaternion_ quaternion(const Eigen::Vector4d& q_xyzw) {
  ros2::Quaternion_ out;
  out.x(q_xyzw[0]);
  out.y(q_xyzw[1]);
  out.z(q_xyzw[2]);
  out.w(q_xyzw[3]);
  return out;
}

// int32 marker_index from a 64-bit track id (ids count up from 1; they would wrap after 2^31).
std::int32_t index_of_track(std::int64_t id) {
  return static_cast<std::int32_t>(id & 0x7fffffff);
}

void labelled_marker(const session::MarkerOutput& marker, mocap::Marker_& out) {
  out.id_type(kMarkerUseBoth);
  out.marker_index(marker.body_marker);
  out.marker_name(marker.body + "/" + std::to_string(marker.body_marker));
  out.translation(xyz<ros2::Point_>(marker.track.p));
}

// A pose record as the transform world <- body.
RigidTransform world_from(const PoseRecord& pose) {
  return {Eigen::Quaterniond(pose.q[3], pose.q[0], pose.q[1], pose.q[2]), pose.p};
}

}  // namespace

void Ros2Messages::header(TimeNs stamp_ns, std_msgs::msg::dds_::Header_& out) const {
  out.stamp(to_ros2_time(stamp_ns));
  if (out.frame_id() != settings_.frame_id) out.frame_id(settings_.frame_id);
}

void Ros2Messages::pose(const session::BodyOutput& body, ros2::PoseStamped_& out) const {
  header(pose_time(body), out.header());
  out.pose().position(xyz<ros2::Point_>(body.pose.p));
  out.pose().orientation(quaternion(body.pose.q));
}

void Ros2Messages::twist(const session::BodyOutput& body, ros2::TwistStamped_& out) const {
  header(pose_time(body), out.header());
  out.twist().linear(xyz<ros2::Vector3_>(body.pose.v));
  out.twist().angular(xyz<ros2::Vector3_>(body.pose.w));
}

void Ros2Messages::transforms(const session::FrameOutput& frame, const std::vector<std::string>& tokens,
                              tf2_msgs::msg::dds_::TFMessage_& out) const {
  std::size_t n = 0;
  for (std::size_t b = 0; b < frame.bodies.size(); ++b) {
    const session::BodyOutput& body = frame.bodies[b];
    if (!body.tracking_valid) continue;
    // A subject's segment hangs from its parent segment (one tree per subject, docs/ros2.md); one
    // whose parent has no pose in this frame is left out of it rather than moved to the world.
    const session::BodyOutput* parent = nullptr;
    std::size_t parent_index = 0;
    if (!body.parent.empty()) {
      for (std::size_t p = 0; p < frame.bodies.size() && !parent; ++p) {
        if (frame.bodies[p].name == body.parent) {
          parent = &frame.bodies[p];
          parent_index = p;
        }
      }
      if (!parent || !parent->tracking_valid) continue;
    }
    if (out.transforms().size() <= n) out.transforms().emplace_back();
    ros2::TransformStamped_& transform = out.transforms()[n++];
    header(pose_time(body), transform.header());
    transform.child_frame_id(settings_.child_frame_prefix + tokens[b]);
    RigidTransform T_frame_body = world_from(body.pose);
    if (parent) {
      transform.header().frame_id(settings_.child_frame_prefix + tokens[parent_index]);
      T_frame_body = world_from(parent->pose).inverse() * T_frame_body;  // T_parent_body
    }
    const Eigen::Quaterniond& q = T_frame_body.q;
    transform.transform().translation(xyz<ros2::Vector3_>(T_frame_body.t));
    transform.transform().rotation(quaternion(Eigen::Vector4d(q.x(), q.y(), q.z(), q.w())));
  }
  out.transforms().resize(n);
}

void Ros2Messages::rigid_bodies(const session::FrameOutput& frame, mocap::RigidBodies_& out) const {
  // The poses share one stamp (one frame, one horizon); the first tracked body's gives it.
  TimeNs stamp_ns = frame.stamp_ns;
  for (const auto& body : frame.bodies) {
    if (body.tracking_valid) {
      stamp_ns = pose_time(body);
      break;
    }
  }
  header(stamp_ns, out.header());
  out.frame_number(static_cast<std::uint32_t>(frame.frame_number));
  std::size_t n = 0;
  for (const auto& body : frame.bodies) {
    if (!body.tracking_valid) continue;
    if (out.rigidbodies().size() <= n) out.rigidbodies().emplace_back();
    mocap::RigidBody_& rigid_body = out.rigidbodies()[n++];
    rigid_body.rigid_body_name(body.name);
    std::size_t m = 0;
    for (const auto& marker : frame.markers) {
      if (marker.body != body.name) continue;
      if (rigid_body.markers().size() <= m) rigid_body.markers().emplace_back();
      labelled_marker(marker, rigid_body.markers()[m++]);
    }
    rigid_body.markers().resize(m);
    rigid_body.pose().position(xyz<ros2::Point_>(body.pose.p));
    rigid_body.pose().orientation(quaternion(body.pose.q));
  }
  out.rigidbodies().resize(n);
}

void Ros2Messages::markers(const session::FrameOutput& frame, mocap::Markers_& out) const {
  header(frame.stamp_ns, out.header());
  out.frame_number(static_cast<std::uint32_t>(frame.frame_number));
  out.markers().resize(frame.markers.size());
  for (std::size_t i = 0; i < frame.markers.size(); ++i) {
    const session::MarkerOutput& marker = frame.markers[i];
    mocap::Marker_& m = out.markers()[i];
    if (marker.body.empty()) {
      // A subject's marker (--subjects) carries "subject/name" beside its track's index.
      m.id_type(marker.name.empty() ? kMarkerUseIndex : kMarkerUseBoth);
      m.marker_index(index_of_track(marker.track.id));
      if (marker.name.empty()) {
        m.marker_name().clear();
      } else {
        m.marker_name(marker.subject + "/" + marker.name);
      }
      m.translation(xyz<ros2::Point_>(marker.track.p));
    } else {
      labelled_marker(marker, m);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// RateLimiter, Ros2TopicNames

RateLimiter::RateLimiter(int rate_hz) {
  if (rate_hz > 0) grid_.emplace(rate_hz);
}

bool RateLimiter::admit(TimeNs stamp_ns) {
  if (!grid_) return true;
  const std::int64_t period = grid_->index_at(stamp_ns);
  if (last_period_ && period <= *last_period_ && period >= *last_period_ - grid_->rate_hz()) return false;
  last_period_ = period;
  return true;
}

Ros2TopicNames::Ros2TopicNames(const std::string& ros2_namespace)
    : rigid_bodies("rt" + session::ros2_namespace_prefix(ros2_namespace) + "/rigid_bodies"),
      markers("rt" + session::ros2_namespace_prefix(ros2_namespace) + "/markers"),
      prefix("rt" + session::ros2_namespace_prefix(ros2_namespace)) {}

std::string Ros2TopicNames::body(const std::string& token, const char* what) const {
  return prefix + "/panoptes/" + token + "/" + what;
}

// ---------------------------------------------------------------------------------------------
// Ros2Outputs

Ros2Outputs::Ros2Outputs(dds::Bus& bus, const session::Ros2Settings& settings)
    : bus_(bus),
      settings_(settings),
      names_(settings.topic_namespace),
      tf_limit_(settings.tf_rate_hz),
      messages_(settings_),
      tf_writer_(bus.make_writer<tf2_msgs::msg::dds_::TFMessage_>(dds::Qos::kDefault, names_.tf)),
      rigid_bodies_writer_(bus.make_writer<mocap::RigidBodies_>(dds::Qos::kDefault, names_.rigid_bodies)),
      markers_writer_(bus.make_writer<mocap::Markers_>(dds::Qos::kDefault, names_.markers)) {}

Ros2Outputs::~Ros2Outputs() = default;

const std::string& Ros2Outputs::token_of(const session::BodyOutput& body) {
  if (const auto it = tokens_.find(body.name); it != tokens_.end()) return it->second;
  std::string token = ros2_name_token(body.name);
  bool taken = false;
  for (const auto& [name, other] : tokens_) taken = taken || other == token;
  if (taken) token.append("_").append(std::to_string(body.id));
  if (token != body.name) {
    session::log("ROS 2: body '" + body.name + "' is published as '" + token +
                 "' (not a ROS 2 name token, or taken; docs/ros2.md \"Names\")");
  }
  return tokens_.emplace(body.name, std::move(token)).first->second;
}

Ros2Outputs::BodyWriters& Ros2Outputs::writers_of(const session::BodyOutput& body) {
  if (const auto it = body_writers_.find(body.name); it != body_writers_.end()) return it->second;
  const std::string& token = token_of(body);
  BodyWriters writers;
  try {
    writers.pose = bus_.make_writer<ros2::PoseStamped_>(dds::Qos::kDefault, names_.body(token, "pose"));
    writers.twist = bus_.make_writer<ros2::TwistStamped_>(dds::Qos::kDefault, names_.body(token, "twist"));
  } catch (const dds::DdsError& error) {  // a topic DDS refuses costs this body its topics only
    session::log("ROS 2: body '" + body.name + "' has no pose and twist topics: " + error.what());
    writers = {};
  }
  return body_writers_.emplace(body.name, std::move(writers)).first->second;
}

void Ros2Outputs::assign_new_tokens(const session::FrameOutput& frame) {
  // Names that are tokens already claim theirs first, so that they keep them.
  for (const bool valid_names : {true, false}) {
    for (const auto& body : frame.bodies) {
      if (tokens_.count(body.name) == 0 && (ros2_name_token(body.name) == body.name) == valid_names)
        token_of(body);
    }
  }
}

void Ros2Outputs::publish(const session::FrameOutput& frame) {
  if (std::any_of(frame.bodies.begin(), frame.bodies.end(),
                  [this](const session::BodyOutput& body) { return tokens_.count(body.name) == 0; }))
    assign_new_tokens(frame);
  frame_tokens_.resize(frame.bodies.size());
  for (std::size_t b = 0; b < frame.bodies.size(); ++b) {
    const session::BodyOutput& body = frame.bodies[b];
    frame_tokens_[b] = token_of(body);
    if (body.segment) continue;               // segments: /tf and /rigid_bodies only
    BodyWriters& writers = writers_of(body);  // every defined body's topics exist, tracked or not
    if (!body.tracking_valid || !writers.twist) continue;
    if (writers.pose->matched_readers() > 0) {
      messages_.pose(body, pose_message_);
      writers.pose->write(pose_message_);
    }
    if (writers.twist->matched_readers() > 0) {
      messages_.twist(body, twist_message_);
      writers.twist->write(twist_message_);
    }
  }
  // The limit counts only frames that carry a transform (a tracked body), so a frame without one
  // does not use up its period; a frame held back costs no message.
  const bool any_tracked = std::any_of(frame.bodies.begin(), frame.bodies.end(),
                                       [](const session::BodyOutput& body) { return body.tracking_valid; });
  if (any_tracked && tf_writer_->matched_readers() > 0 && tf_limit_.admit(frame.stamp_ns)) {
    messages_.transforms(frame, frame_tokens_, tf_message_);
    tf_writer_->write(tf_message_);
  }
  if (rigid_bodies_writer_->matched_readers() > 0) {
    messages_.rigid_bodies(frame, rigid_bodies_message_);
    rigid_bodies_writer_->write(rigid_bodies_message_);
  }
  if (markers_writer_->matched_readers() > 0) {
    messages_.markers(frame, markers_message_);
    markers_writer_->write(markers_message_);
  }
}

}  // namespace panoptes::estimator_app
