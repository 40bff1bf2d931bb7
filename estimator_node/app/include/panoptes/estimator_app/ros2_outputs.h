// SPDX-License-Identifier: Apache-2.0
// The ROS 2 topics (docs/ros2.md): a FrameOutput as geometry_msgs/PoseStamped and TwistStamped per
// tracked body (rt/panoptes/<body>/pose, .../twist), tf2_msgs/TFMessage (rt/tf) and the mocap4r2
// driver's mocap4r2_msgs/RigidBodies (rt/rigid_bodies) and Markers (rt/markers). No ROS installation
// is involved: the types of idl/ros2.idl carry ROS 2's DDS type names and wire format.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/dds/bus.h"
#include "panoptes/session/estimator_config.h"
#include "panoptes/session/frame_clock.h"
#include "panoptes/session/frame_output.h"
#include "panoptes_msgs/ros2.h"

namespace panoptes::estimator_app {

// mocap4r2_msgs/Marker's id_type constants (Marker.msg; constants are not on the wire).
inline constexpr std::int8_t kMarkerUseName = 0;
inline constexpr std::int8_t kMarkerUseIndex = 1;
inline constexpr std::int8_t kMarkerUseBoth = 2;

// builtin_interfaces/Time of a stamp in ns: sec = floor(ns / 1 s), nanosec in [0, 1e9), so
// -1.7 s is {-2, 300000000}. Stamps beyond int32 seconds saturate.
builtin_interfaces::msg::dds_::Time_ to_ros2_time(TimeNs stamp_ns);

// A body name as one ROS 2 name token: characters outside [A-Za-z0-9_] become '_', runs of '_'
// become one, leading and trailing '_' are dropped, and a token that would be empty or start with a
// digit gets the prefix "body_" (an empty one is "body"). Names that are already tokens are returned
// unchanged.
std::string ros2_name_token(const std::string& body_name);

// The /tf rate limit (ros2.tf_rate_hz): lets through at most one frame per period of a grid of
// `rate_hz` periods on the capture clock, the fixed-rate frames' grid (session::FrameClock, aligned
// to whole seconds). A frame is let through when its stamp lies in a later period than the last one
// let through, so frames that come at least once per period give exactly `rate_hz` a second,
// whatever their spacing; a frame older than the last one let through (cameras' frames may come out
// of stamp order) is held back unless it is more than a second older (the clock was set back, a
// replay started again), which starts the grid anew. 0: every frame.
class RateLimiter {
 public:
  explicit RateLimiter(int rate_hz);
  bool admit(TimeNs stamp_ns);

 private:
  std::optional<session::FrameClock> grid_;
  std::optional<std::int64_t> last_period_;
};

// The DDS names of the ROS 2 topics for a namespace (ros2.namespace; "" for none): /tf stays
// global, as tf2_ros's listeners subscribe to the absolute /tf (docs/ros2.md, "Namespace").
struct Ros2TopicNames {
  explicit Ros2TopicNames(const std::string& ros2_namespace);
  std::string body(const std::string& token, const char* what) const;  // what: "pose", "twist"

  std::string tf = "rt/tf";
  std::string rigid_bodies;
  std::string markers;
  std::string prefix;  // "rt" + the namespace
};

// The message builders, apart from the writers so that tests and benchmarks can check them.
// Only tracked bodies (tracking_valid) give poses, twists, transforms and rigid bodies.
class Ros2Messages {
 public:
  explicit Ros2Messages(const session::Ros2Settings& settings) : settings_(settings) {}

  // `token` is the body's name token (ros2_name_token, made unique among the bodies).
  void pose(const session::BodyOutput& body, geometry_msgs::msg::dds_::PoseStamped_& out) const;
  void twist(const session::BodyOutput& body, geometry_msgs::msg::dds_::TwistStamped_& out) const;
  void transforms(const session::FrameOutput& frame, const std::vector<std::string>& tokens,
                  tf2_msgs::msg::dds_::TFMessage_& out) const;
  void rigid_bodies(const session::FrameOutput& frame, mocap4r2_msgs::msg::dds_::RigidBodies_& out) const;
  void markers(const session::FrameOutput& frame, mocap4r2_msgs::msg::dds_::Markers_& out) const;

 private:
  void header(TimeNs stamp_ns, std_msgs::msg::dds_::Header_& out) const;

  const session::Ros2Settings& settings_;
};

// Writes the ROS 2 topics of each processed frame. A topic nobody subscribes to costs a check of its
// matched readers: its message is neither built nor written.
class Ros2Outputs {
 public:
  Ros2Outputs(dds::Bus& bus, const session::Ros2Settings& settings);
  ~Ros2Outputs();
  Ros2Outputs(const Ros2Outputs&) = delete;
  Ros2Outputs& operator=(const Ros2Outputs&) = delete;

  void publish(const session::FrameOutput& frame);

  // The name token of each body seen so far (body name -> token; tests, docs).
  const std::map<std::string, std::string>& body_tokens() const { return tokens_; }

 private:
  struct BodyWriters {
    std::unique_ptr<dds::Writer<geometry_msgs::msg::dds_::PoseStamped_>> pose;
    std::unique_ptr<dds::Writer<geometry_msgs::msg::dds_::TwistStamped_>> twist;
  };

  // The token of `body`, unique among the bodies: the first body to claim a token keeps it, a later
  // one whose name maps to the same token gets "_<id>" appended (id: its place in the bodies file).
  // Within a frame, names that are tokens already claim first (assign_new_tokens).
  const std::string& token_of(const session::BodyOutput& body);
  void assign_new_tokens(const session::FrameOutput& frame);
  BodyWriters& writers_of(const session::BodyOutput& body);

  dds::Bus& bus_;
  session::Ros2Settings settings_;
  Ros2TopicNames names_;
  RateLimiter tf_limit_;
  Ros2Messages messages_;
  std::map<std::string, std::string> tokens_;  // body name -> token
  std::map<std::string, BodyWriters> body_writers_;
  std::unique_ptr<dds::Writer<tf2_msgs::msg::dds_::TFMessage_>> tf_writer_;
  std::unique_ptr<dds::Writer<mocap4r2_msgs::msg::dds_::RigidBodies_>> rigid_bodies_writer_;
  std::unique_ptr<dds::Writer<mocap4r2_msgs::msg::dds_::Markers_>> markers_writer_;
  // Reused from frame to frame: their sequences and strings keep their capacity.
  geometry_msgs::msg::dds_::PoseStamped_ pose_message_;
  geometry_msgs::msg::dds_::TwistStamped_ twist_message_;
  tf2_msgs::msg::dds_::TFMessage_ tf_message_;
  mocap4r2_msgs::msg::dds_::RigidBodies_ rigid_bodies_message_;
  mocap4r2_msgs::msg::dds_::Markers_ markers_message_;
  std::vector<std::string> frame_tokens_;  // per frame.bodies entry
};

}  // namespace panoptes::estimator_app
