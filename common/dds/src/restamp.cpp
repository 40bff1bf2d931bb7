// SPDX-License-Identifier: Apache-2.0
// Moving every absolute time of a recorded sample by one offset (panoptes_replay's restamp).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/dds/bus.h"
#include "panoptes/dds/cdr.h"
#include "panoptes/dds/decode.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/ros2.h"
#include "topics.h"

namespace panoptes::dds {

namespace {

// A time moved by the offset; 0 means "unknown" and stays 0.
class Shift {
 public:
  explicit Shift(std::int64_t offset_ns) : offset_ns_(offset_ns) {}
  std::int64_t operator()(std::int64_t t) const { return t == 0 ? 0 : t + offset_ns_; }

 private:
  std::int64_t offset_ns_;
};

template <class T>
bool is_topic(const std::string& topic) {
  return topic == TopicTraits<T>::spec().name;
}

// Decodes `cdr` as T, applies `move` and encodes it again. False if it does not decode.
template <class T, class Move>
bool shift_as(std::vector<std::uint8_t>& cdr, const Move& move) {
  T message;
  if (decode_sample(cdr.data(), cdr.size(), message) != DecodeError::kNone) return false;
  move(message);
  cdr = encode_sample(message);
  return !cdr.empty();
}

// Samples whose only time is their stamp_ns.
template <class T>
bool shift_stamp(std::vector<std::uint8_t>& cdr, const Shift& at) {
  return shift_as<T>(cdr, [&](T& m) { m.stamp_ns(at(m.stamp_ns())); });
}

void shift_mocap_frame(msg::MocapFrame& m, const Shift& at) {
  m.stamp_ns(at(m.stamp_ns()));
  m.publish_ns(at(m.publish_ns()));
  msg::FrameStages& s = m.stages();  // camera_processing_ns is a duration
  s.camera_arrival_ns(at(s.camera_arrival_ns()));
  s.feature_publish_ns(at(s.feature_publish_ns()));
  s.received_ns(at(s.received_ns()));
  s.dequeued_ns(at(s.dequeued_ns()));
  s.updated_ns(at(s.updated_ns()));
}

// A ROS 2 header's stamp (sec, nanosec) moved as one time in ns; an all-zero stamp stays.
void shift_header(std_msgs::msg::dds_::Header_& header, const Shift& at) {
  auto& stamp = header.stamp();
  const std::int64_t ns = std::int64_t{stamp.sec()} * 1'000'000'000 + std::int64_t{stamp.nanosec()};
  const std::int64_t moved = at(ns);
  std::int64_t sec = moved / 1'000'000'000;
  std::int64_t nanosec = moved % 1'000'000'000;
  if (nanosec < 0) {
    nanosec += 1'000'000'000;
    --sec;
  }
  stamp.sec(static_cast<std::int32_t>(sec));
  stamp.nanosec(static_cast<std::uint32_t>(nanosec));
}

// The ROS 2 topics (docs/ros2.md), by the type their name resolves to: every header stamp moved.
std::optional<bool> shift_ros2(const std::string& topic, std::vector<std::uint8_t>& cdr, const Shift& at) {
  const auto raw = recordable_topic(topic);
  if (!raw) return std::nullopt;
  const std::string& type = raw->type_name;
  const auto header_of = [&](auto& m) { shift_header(m.header(), at); };
  if (type == "tf2_msgs::msg::dds_::TFMessage_")
    return shift_as<tf2_msgs::msg::dds_::TFMessage_>(cdr, [&](auto& m) {
      for (auto& transform : m.transforms()) shift_header(transform.header(), at);
    });
  if (type == "mocap4r2_msgs::msg::dds_::RigidBodies_")
    return shift_as<mocap4r2_msgs::msg::dds_::RigidBodies_>(cdr, header_of);
  if (type == "mocap4r2_msgs::msg::dds_::Markers_")
    return shift_as<mocap4r2_msgs::msg::dds_::Markers_>(cdr, header_of);
  if (type == "geometry_msgs::msg::dds_::PoseStamped_")
    return shift_as<geometry_msgs::msg::dds_::PoseStamped_>(cdr, header_of);
  if (type == "geometry_msgs::msg::dds_::TwistStamped_")
    return shift_as<geometry_msgs::msg::dds_::TwistStamped_>(cdr, header_of);
  return std::nullopt;
}

}  // namespace

bool shift_sample_times(const std::string& topic, std::vector<std::uint8_t>& cdr, std::int64_t offset_ns) {
  const Shift at(offset_ns);
  if (is_topic<msg::FeatureFrame>(topic)) return shift_feature_frame_times(cdr, offset_ns);
  if (is_topic<msg::MocapFrame>(topic))
    return shift_as<msg::MocapFrame>(cdr, [&](msg::MocapFrame& m) { shift_mocap_frame(m, at); });
  if (is_topic<msg::TrackFrame>(topic)) {
    return shift_as<msg::TrackFrame>(cdr, [&](msg::TrackFrame& m) {
      m.stamp_ns(at(m.stamp_ns()));
      m.publish_ns(at(m.publish_ns()));
    });
  }
  if (is_topic<msg::EstimatorStatus>(topic)) {
    return shift_as<msg::EstimatorStatus>(cdr, [&](msg::EstimatorStatus& m) {
      m.stamp_ns(at(m.stamp_ns()));
      for (auto& camera : m.cameras()) camera.last_stamp_ns(at(camera.last_stamp_ns()));
    });
  }
  if (is_topic<msg::TimeSync>(topic)) {
    return shift_as<msg::TimeSync>(cdr, [&](msg::TimeSync& m) {
      m.t1_ns(at(m.t1_ns()));
      m.t2_ns(at(m.t2_ns()));
      m.t3_ns(at(m.t3_ns()));
    });
  }
  if (is_topic<msg::BodyPose>(topic)) return shift_stamp<msg::BodyPose>(cdr, at);
  if (is_topic<msg::BodyDescriptions>(topic)) return shift_stamp<msg::BodyDescriptions>(cdr, at);
  if (is_topic<msg::MarkerLabels>(topic)) return shift_stamp<msg::MarkerLabels>(cdr, at);
  if (is_topic<msg::CameraInfo>(topic)) return shift_stamp<msg::CameraInfo>(cdr, at);
  if (is_topic<msg::CameraStatus>(topic)) return shift_stamp<msg::CameraStatus>(cdr, at);
  if (is_topic<msg::CameraPreview>(topic)) return shift_stamp<msg::CameraPreview>(cdr, at);
  if (is_topic<msg::Predictions>(topic)) return shift_stamp<msg::Predictions>(cdr, at);
  if (is_topic<msg::SystemCalibration>(topic)) return shift_stamp<msg::SystemCalibration>(cdr, at);
  if (const auto ros2 = shift_ros2(topic, cdr, at)) return *ros2;
  return true;  // no times (camera commands) or not a recorded topic: unchanged
}

}  // namespace panoptes::dds
