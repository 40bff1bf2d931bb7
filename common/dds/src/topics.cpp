// SPDX-License-Identifier: Apache-2.0
// Topics and QoS: the writer and reader QoS of a topic and the table of raw (serialized) topics.
#include "topics.h"

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

namespace panoptes::dds {

// Transient-local topics (the samples a late joiner needs: body descriptions, calibration, camera
// info) are repaired at once rather than on Fast DDS's timers. A reader that matches a writer asks
// for the history after initialAcknackDelay (70 ms by default, then doubled until the writer's
// first heartbeat) and the writer answers after nackResponseDelay (5 ms): a client started late got
// the body descriptions 5-39 ms after its first frame, which has no such wait (docs/clients.md,
// "Late joiners"). Not 0 ms for the reader: the doubling would then resend without pause.
constexpr std::uint32_t kLateJoinerAcknackNs = 1'000'000;
// And a lost sample of theirs is repaired within this: they are written seldom (a label map when
// names change, descriptions when bodies do), so the next write may be seconds away, and a reader
// asks again only after the writer's heartbeat (3 s by default). Under CPU contention a client held
// an old label map for 2.6 s (test_live_labels); a heartbeat per 100 ms to each reader costs nothing
// at these topics' rates.
constexpr std::uint32_t kTransientLocalHeartbeatNs = 100'000'000;

fdds::DataWriterQos writer_qos_for(const TopicSpec& spec, Qos qos) {
  fdds::DataWriterQos writer_qos = fdds::DATAWRITER_QOS_DEFAULT;
  apply_spec(writer_qos, spec, qos);
  apply_transport_cap(writer_qos, spec);
  if (spec.durability == Durability::kTransientLocal) {
    writer_qos.reliable_writer_qos().times.nackResponseDelay = eprosima::fastrtps::Duration_t(0, 0);
    writer_qos.reliable_writer_qos().times.heartbeatPeriod =
        eprosima::fastrtps::Duration_t(0, kTransientLocalHeartbeatNs);
  }
  if (spec.offer_reliable && !spec.reliable && qos == Qos::kDefault) {
    writer_qos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    writer_qos.history().depth = kOfferedReliableDepth;
    writer_qos.resource_limits().max_samples_per_instance = kOfferedReliableDepth;
    writer_qos.resource_limits().max_samples = kMaxInstances * kOfferedReliableDepth;
    writer_qos.reliable_writer_qos().times.heartbeatPeriod =
        eprosima::fastrtps::Duration_t(0, kOfferedHeartbeatNs);
  }
  // A writer that offers reliability on a best-effort topic (frames, features, tracks, bodies)
  // offers transient-local durability too: Fast DDS 2.9.1 removes a volatile writer's sample once
  // every reader acknowledged it, and when that happens as a reader leaves (matched_reader_remove)
  // while its flow controller's thread sends a sample of the same writer, both wait for each
  // other's lock for good (eProsima/Fast-DDS#3468, fixed in 2.10): write() blocks and the
  // participant no longer receives discovery (a fake estimator's frames writer, as 20 clients came
  // and went; docs/protocol.md "Closing a participant"). A transient-local writer keeps its
  // samples (history depth as before) and matches volatile readers, which receive nothing written
  // before they matched. Not for reliable topics (commands, time sync, the ROS 2 types): there it
  // cost a best-effort reader of rt/tf (depth 100, beside a reliable one) 2.5-7.6 % of its samples
  // under load, none with a volatile writer (integration.test_ros2_topics; cause not analysed).
  if (spec.offer_reliable && writer_qos.reliability().kind == fdds::RELIABLE_RELIABILITY_QOS &&
      writer_qos.durability().kind == fdds::VOLATILE_DURABILITY_QOS)
    writer_qos.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  writer_qos.reliable_writer_qos().times.nackSupressionDuration =
      eprosima::fastrtps::Duration_t(0, static_cast<std::uint32_t>(spec.nack_suppression_ms) * 1'000'000U);
  // No writer-side filtering: a filtered reader (`only_id`) evaluates its filter itself. Fast DDS
  // 2.9.1 changes a writer's list of reader filters as readers come and go without the writer's
  // lock, while a write walks that list (ReaderFilterCollection): panoptes_rogue died there
  // (SIGSEGV in ContentFilterInfo::cdr_serialize under DataWriter::write, in 1 of 6 test_hostile
  // runs, as the demo's nodes ended; eProsima/Fast-DDS#4878 reports the same stack), and the
  // estimator writes predictions and time-sync replies while cameras come and go. Since those
  // go through a writer per camera in its partition (docs/protocol.md), the filter on the writer
  // saved little: only what the writers for every camera ("*") send reaches each camera.
  writer_qos.writer_resource_limits().reader_filters_allocation =
      eprosima::fastrtps::ResourceLimitedContainerConfig(0, 0, 0);
  return writer_qos;
}

void apply_transport_cap(fdds::DataReaderQos& qos, const TopicSpec& spec) {
  if (spec.transport_cap == 0) return;
  // Payloads of the cap's size, so that a larger fragmented sample finds no room and is dropped at
  // its first fragment; only a few reserved up front (each is the cap's size, and the pool clears
  // it), more taken as the history needs them.
  qos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_MEMORY_MODE;
  qos.resource_limits().allocated_samples = std::min(qos.history().depth, 8);
}

void apply_transport_cap(fdds::DataWriterQos& qos, const TopicSpec& spec) {
  // A writer's payloads sized by what it writes, not preallocated at the cap.
  if (spec.transport_cap != 0)
    qos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
}

fdds::DataReaderQos reader_qos_for(const TopicSpec& spec, Qos qos) {
  fdds::DataReaderQos reader_qos = fdds::DATAREADER_QOS_DEFAULT;
  apply_spec(reader_qos, spec, qos);
  apply_transport_cap(reader_qos, spec);
  if (spec.durability == Durability::kTransientLocal)
    reader_qos.reliable_reader_qos().times.initialAcknackDelay =
        eprosima::fastrtps::Duration_t(0, kLateJoinerAcknackNs);
  return reader_qos;
}

namespace {

template <class T>
RawTopicEntry raw_entry(const char* ros_type) {
  const TopicSpec spec = TopicTraits<T>::spec();
  typename TopicTraits<T>::PubSubType real;
  return {{spec.name, real.getName(), ros_type, spec.durability == Durability::kTransientLocal}, spec, [] {
            return new typename TopicTraits<T>::PubSubType();
          }};
}

const std::vector<RawTopicEntry>& raw_entries() {
  static const std::vector<RawTopicEntry> entries = {
      raw_entry<msg::CameraInfo>("panoptes/msg/CameraInfo"),
      raw_entry<msg::FeatureFrame>("panoptes/msg/FeatureFrame"),
      raw_entry<msg::CameraStatus>("panoptes/msg/CameraStatus"),
      raw_entry<msg::CameraCommand>("panoptes/msg/CameraCommand"),
      raw_entry<msg::CameraPreview>("panoptes/msg/CameraPreview"),
      raw_entry<msg::Predictions>("panoptes/msg/Predictions"),
      raw_entry<msg::TimeSync>("panoptes/msg/TimeSync"),
      raw_entry<msg::EstimatorStatus>("panoptes/msg/EstimatorStatus"),
      raw_entry<msg::TrackFrame>("panoptes/msg/TrackFrame"),
      raw_entry<msg::BodyPose>("panoptes/msg/BodyPose"),
      raw_entry<msg::SystemCalibration>("panoptes/msg/SystemCalibration"),
      raw_entry<msg::MocapFrame>("panoptes/msg/MocapFrame"),
      raw_entry<msg::BodyDescriptions>("panoptes/msg/BodyDescriptions"),
      raw_entry<msg::MarkerLabels>("panoptes/msg/MarkerLabels"),
  };
  return entries;
}

template <class T>
RawTopicEntry ros2_entry(std::string name, const char* ros_type) {
  typename TopicTraits<T>::PubSubType real;
  return {{std::move(name), real.getName(), ros_type, false}, TopicTraits<T>::spec(), [] {
            return new typename TopicTraits<T>::PubSubType();
          }};
}

// The ROS 2 topics of docs/ros2.md recorded by default (their names without a namespace).
const std::vector<RawTopicEntry>& ros2_entries() {
  static const std::vector<RawTopicEntry> entries = {
      ros2_entry<tf2_msgs::msg::dds_::TFMessage_>("rt/tf", "tf2_msgs/msg/TFMessage"),
      ros2_entry<mocap4r2_msgs::msg::dds_::RigidBodies_>("rt/rigid_bodies", "mocap4r2_msgs/msg/RigidBodies"),
      ros2_entry<mocap4r2_msgs::msg::dds_::Markers_>("rt/markers", "mocap4r2_msgs/msg/Markers"),
  };
  return entries;
}

bool ends_with(const std::string& text, const std::string& tail) {
  return text.size() > tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0;
}

// A ROS 2 topic whose name depends on the configuration: rt/<namespace>/rigid_bodies and
// rt/<namespace>/markers (ros2.namespace), rt/[<namespace>/]panoptes/<body>/pose and twist.
std::optional<RawTopicEntry> ros2_entry_by_pattern(const std::string& topic) {
  if (topic.rfind("rt/", 0) != 0) return std::nullopt;
  if (ends_with(topic, "/rigid_bodies"))
    return ros2_entry<mocap4r2_msgs::msg::dds_::RigidBodies_>(topic, "mocap4r2_msgs/msg/RigidBodies");
  if (ends_with(topic, "/markers"))
    return ros2_entry<mocap4r2_msgs::msg::dds_::Markers_>(topic, "mocap4r2_msgs/msg/Markers");
  const auto body = topic.find("/panoptes/");
  if (body == std::string::npos || topic.find('/', body + 10) == std::string::npos) return std::nullopt;
  if (ends_with(topic, "/pose"))
    return ros2_entry<geometry_msgs::msg::dds_::PoseStamped_>(topic, "geometry_msgs/msg/PoseStamped");
  if (ends_with(topic, "/twist"))
    return ros2_entry<geometry_msgs::msg::dds_::TwistStamped_>(topic, "geometry_msgs/msg/TwistStamped");
  return std::nullopt;
}

// Topics a raw writer may write although panoptes_record does not record them (panoptes_rogue).
const std::vector<RawTopicEntry>& unrecorded_raw_entries() {
  static const std::vector<RawTopicEntry> entries = {
      raw_entry<msg::RecorderCommand>("panoptes/msg/RecorderCommand"),
      raw_entry<msg::RecorderStatus>("panoptes/msg/RecorderStatus"),
  };
  return entries;
}

}  // namespace

std::optional<RawTopicEntry> find_raw_entry(const std::string& topic) {
  for (const auto* entries : {&raw_entries(), &ros2_entries(), &unrecorded_raw_entries()}) {
    for (const auto& entry : *entries) {
      if (entry.topic.topic == topic) return entry;
    }
  }
  return ros2_entry_by_pattern(topic);
}

RawTopicEntry raw_entry_named(const std::string& topic) {
  if (auto entry = find_raw_entry(topic)) return std::move(*entry);
  throw DdsInputError(
      "'" + topic +
      "' is not a Panoptes topic (docs/protocol.md) nor one of its ROS 2 topics (docs/ros2.md)");
}

std::optional<RawTopic> recordable_topic(const std::string& topic) {
  for (const auto& entry : unrecorded_raw_entries()) {
    if (entry.topic.topic == topic) return std::nullopt;
  }
  if (auto entry = find_raw_entry(topic)) return entry->topic;
  return std::nullopt;
}

std::vector<RawTopic> panoptes_raw_topics() {
  std::vector<RawTopic> topics;
  for (const auto& entry : raw_entries()) topics.push_back(entry.topic);
  for (const auto& entry : ros2_entries()) topics.push_back(entry.topic);
  return topics;
}

}  // namespace panoptes::dds
