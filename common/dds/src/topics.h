// SPDX-License-Identifier: Apache-2.0
// Private to panoptes_dds: every topic's name and QoS (the table docs/protocol.md documents), the
// QoS of its readers and writers, the guarded type support that decodes received samples, and the
// table of topics panoptes_record and panoptes_replay see as raw CDR.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>

#include "panoptes/dds/bus.h"
#include "panoptes/dds/decode.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/chainsPubSubTypes.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/panoptesPubSubTypes.h"
#include "panoptes_msgs/ros2.h"
#include "panoptes_msgs/ros2PubSubTypes.h"
#include "panoptes_msgs/surface.h"
#include "panoptes_msgs/surfacePubSubTypes.h"

namespace panoptes::dds {

namespace fdds = eprosima::fastdds::dds;

enum class Durability { kVolatile, kTransientLocal };

// Per-topic name and QoS: the single source of truth documented in docs/protocol.md.
struct TopicSpec {
  const char* name;
  bool reliable;
  Durability durability;
  int depth;  // keep-last depth per instance
  // Writers offer reliability although readers ask for best effort by default: a reader that asks
  // for it (Qos::kReliable, e.g. calibration capture) gets repairs, the others are unaffected.
  bool offer_reliable;
  // The first member is a string naming the camera or client the sample is for or from
  // (Bus::make_reader's `only_id` filters on it).
  bool leading_id;
  // How long after sending a sample a reliable writer ignores requests to resend it (Fast DDS's
  // nackSupressionDuration, 0 by default). 0 re-arms a timer on the event thread for every sample
  // and every reliable reader, which then contends for the writer: at the frame rate of the ROS 2
  // topics that doubled their cost (docs/benchmarks.md, "Issue 15: ROS 2 publishers").
  int nack_suppression_ms = 0;
  // A camera-scoped topic: its writers and readers are in DDS partitions named by camera (or
  // time-sync client) id, which a camera's DDS Security permissions restrict to its own id.
  bool camera_scoped = false;
  // Samples larger than this (bytes, 0: no limit) are refused by a reader's payload pool at their
  // first fragment, before any of them is copied (apply_transport_cap, reader_qos_for).
  std::size_t transport_cap = 0;
};

// The size a topic's type declares to Fast DDS (m_typeSize), which its payload pools preallocate:
// the topic's transport cap if it has one, else the generated type's estimate. One rule for the
// typed (GuardedPubSubType) and raw (RawPubSubType) types, so that whichever registers the type
// first in a participant, its payloads have the same size.
inline std::uint32_t declared_type_size(std::size_t transport_cap, std::uint32_t generated) {
  return transport_cap != 0 ? static_cast<std::uint32_t>(transport_cap) : generated;
}

template <class T>
struct TopicTraits;

// The camera-scoped topics (TopicSpec::camera_scoped).
template <class T>
inline constexpr bool kCameraScoped = false;
template <>
inline constexpr bool kCameraScoped<msg::CameraInfo> = true;
template <>
inline constexpr bool kCameraScoped<msg::FeatureFrame> = true;
template <>
inline constexpr bool kCameraScoped<msg::CameraStatus> = true;
template <>
inline constexpr bool kCameraScoped<msg::CameraCommand> = true;
template <>
inline constexpr bool kCameraScoped<msg::CameraPreview> = true;
template <>
inline constexpr bool kCameraScoped<msg::Predictions> = true;
template <>
inline constexpr bool kCameraScoped<msg::TimeSync> = true;

// The largest serialised sample a reader of the type decodes (bytes; 0: no limit). A larger one is
// counted as "sample_too_large" and dropped before decoding: decoding runs on Fast DDS's receive
// thread, which every reader of the participant shares, and panoptes_rogue's FeatureFrame of 10^6
// blobs (40 MB) held the estimator's features from every camera for 0.5-0.9 s (test_hostile: the
// live estimator then deleted every track). 2 MiB is about 52 000 blobs, 12 times the
// estimator's own per-frame limit (FrameScreenOptions::max_blobs, 4096).
template <class T>
inline constexpr std::size_t kMaxSampleBytes = 0;
template <>
inline constexpr std::size_t kMaxSampleBytes<msg::FeatureFrame> = std::size_t{2} << 20;
// Larger than twice that, a sample is not even received: the reader's payloads are preallocated at
// this size (PREALLOCATED_MEMORY_MODE), and Fast DDS drops a fragmented sample that does not fit
// one at its first fragment. Before, the 40 MB frames were reassembled first: a payload grown to
// 40 MB and cleared on the receive thread every camera's frames wait behind (docs/hostile_input.md,
// "Where the 40 MB frames cost time"). Between the two limits a sample is counted, above the
// second it is not (it never arrives whole).
template <class T>
inline constexpr std::size_t kTransportCap = 2 * kMaxSampleBytes<T>;

#define PANOPTES_TOPIC(Type, topic_name, reliable, durability, depth, offer_reliable, leading_id) \
  template <>                                                                                     \
  struct TopicTraits<msg::Type> {                                                                 \
    using PubSubType = msg::Type##PubSubType;                                                     \
    static TopicSpec spec() {                                                                     \
      return {topic_name,                                                                         \
              reliable,                                                                           \
              durability,                                                                         \
              depth,                                                                              \
              offer_reliable,                                                                     \
              leading_id,                                                                         \
              0,                                                                                  \
              kCameraScoped<msg::Type>,                                                           \
              kTransportCap<msg::Type>};                                                          \
    }                                                                                             \
  };

PANOPTES_TOPIC(CameraInfo, "rt/panoptes/camera_info", true, Durability::kTransientLocal, 1, false, true)
PANOPTES_TOPIC(FeatureFrame, "rt/panoptes/features", false, Durability::kVolatile, 8, true, true)
PANOPTES_TOPIC(CameraStatus, "rt/panoptes/camera_status", false, Durability::kVolatile, 1, false, true)
PANOPTES_TOPIC(CameraCommand, "rt/panoptes/camera_command", true, Durability::kVolatile, 32, false, false)
PANOPTES_TOPIC(CameraPreview, "rt/panoptes/camera_preview", false, Durability::kVolatile, 1, false, true)
PANOPTES_TOPIC(Predictions, "rt/panoptes/predictions", false, Durability::kVolatile, 1, false, true)
PANOPTES_TOPIC(TimeSync, "rt/panoptes/time_sync", true, Durability::kVolatile, 64, false, true)
PANOPTES_TOPIC(EstimatorStatus, "rt/panoptes/estimator_status", false, Durability::kVolatile, 1, false, false)
PANOPTES_TOPIC(TrackFrame, "rt/panoptes/tracks", false, Durability::kVolatile, 1, true, false)
PANOPTES_TOPIC(BodyPose, "rt/panoptes/bodies", false, Durability::kVolatile, 1, true, true)
PANOPTES_TOPIC(SystemCalibration, "rt/panoptes/calibration", true, Durability::kTransientLocal, 1, false,
               false)
PANOPTES_TOPIC(MocapFrame, "rt/panoptes/frames", false, Durability::kVolatile, 8, true, false)
PANOPTES_TOPIC(BodyDescriptions, "rt/panoptes/body_descriptions", true, Durability::kTransientLocal, 1, false,
               false)
PANOPTES_TOPIC(MarkerLabels, "rt/panoptes/labels", true, Durability::kTransientLocal, 1, false, false)
PANOPTES_TOPIC(RecorderCommand, "rt/panoptes/recorder_command", true, Durability::kVolatile, 32, false, false)
PANOPTES_TOPIC(RecorderStatus, "rt/panoptes/recorder_status", false, Durability::kVolatile, 1, false, true)
// Off by default: camera_node and estimator_node --latency-probe (docs/protocol.md, "Latency probes").
PANOPTES_TOPIC(LatencyTraces, "rt/panoptes/latency_probe/trace", false, Durability::kVolatile, 8, false,
               false)
// Surface mode (docs/surface.md): every begin and end matters to a drawing application.
PANOPTES_TOPIC(StrokeEvents, "rt/panoptes/strokes", true, Durability::kVolatile, 64, false, false)
// Articulated chains (docs/articulated.md): grab and release events ride in these samples.
PANOPTES_TOPIC(ChainFrame, "rt/panoptes/chains", true, Durability::kVolatile, 64, false, false)
#undef PANOPTES_TOPIC

// A probe measures one hop of the pipeline, so it takes the QoS of the topic it stands in for: the
// QoS decides how Fast DDS carries a sample (seen with Fast DDS 2.9 and deploy/dds/loopback.xml: a
// best-effort writer sends over UDP loopback, one that offers reliability over shared memory).
#define PANOPTES_PROBE_TOPIC(Type, topic_name, Measured)   \
  template <>                                              \
  struct TopicTraits<msg::Type> {                          \
    using PubSubType = msg::Type##PubSubType;              \
    static TopicSpec spec() {                              \
      TopicSpec spec = TopicTraits<msg::Measured>::spec(); \
      spec.name = topic_name;                              \
      spec.camera_scoped = false;                          \
      return spec;                                         \
    }                                                      \
  };
PANOPTES_PROBE_TOPIC(LatencyProbe, "rt/panoptes/latency_probe/request", FeatureFrame)
PANOPTES_PROBE_TOPIC(LatencyProbeEcho, "rt/panoptes/latency_probe/echo", BodyPose)
#undef PANOPTES_PROBE_TOPIC

// ROS 2 types (idl/ros2.idl, docs/ros2.md): reliable, volatile, keep-last, which a ROS 2
// SensorDataQoS (best-effort) subscriber and a default (reliable) one both match. An empty name:
// the caller names the topic (per body).
#define PANOPTES_ROS2_TOPIC(Package, Type, topic_name, depth)                                              \
  template <>                                                                                              \
  struct TopicTraits<Package::msg::dds_::Type##_> {                                                        \
    using PubSubType = Package::msg::dds_::Type##_PubSubType;                                              \
    static TopicSpec spec() { return {topic_name, true, Durability::kVolatile, depth, false, false, 50}; } \
  };
PANOPTES_ROS2_TOPIC(geometry_msgs, PoseStamped, "", 10)
PANOPTES_ROS2_TOPIC(geometry_msgs, TwistStamped, "", 10)
PANOPTES_ROS2_TOPIC(tf2_msgs, TFMessage, "rt/tf", 100)
PANOPTES_ROS2_TOPIC(mocap4r2_msgs, RigidBodies, "rt/rigid_bodies", 10)
PANOPTES_ROS2_TOPIC(mocap4r2_msgs, Markers, "rt/markers", 10)
#undef PANOPTES_ROS2_TOPIC

constexpr int kReliableDepth = 2000;
constexpr int kMaxInstances = 1024;  // cameras (or bodies) per keyed topic, as the estimator's own limit
// A writer that offers reliability keeps this many samples per instance for repairs and announces
// them this often: 64 frames are 270 ms at 240 Hz, several heartbeat periods.
constexpr int kOfferedReliableDepth = 64;
constexpr std::int32_t kOfferedHeartbeatNs = 50'000'000;

// ---------------------------------------------------------------------------------------------
// Received samples are decoded by decode_sample (decode.h), never by the generated code directly:
// that lets a bad encapsulation header or std::bad_alloc escape into Fast DDS's threads, and
// accepts strings without a terminator. A sample that fails is counted under its reason in the
// Bus's ReceiveCounters and dropped (docs/hostile_input.md).

// Set by GuardedPubSubType::deserialize on the thread that takes the sample: the reader's listener
// skips it. (Fast DDS 2.9 ignores deserialize's result when a reader takes a sample.)
inline thread_local bool t_last_decode_failed = false;

template <class PubSubType, class T>
class GuardedPubSubType final : public fdds::TopicDataType {
 public:
  explicit GuardedPubSubType(ReceiveCounters& counters) : counters_(counters) {
    setName(real_.getName());
    m_typeSize = declared_type_size(kTransportCap<T>, real_.m_typeSize);
    m_isGetKeyDefined = real_.m_isGetKeyDefined;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    return real_.serialize(data, payload);
  }
  // Also decodes the samples whose key Fast DDS must compute on receipt.
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    T& message = *static_cast<T*>(data);
    if (kMaxSampleBytes<T> != 0 && payload->length > kMaxSampleBytes<T>) {
      t_last_decode_failed = true;
      counters_.note("sample_too_large");
      message = T();
      return false;
    }
    const DecodeError error = decode_sample(payload->data, payload->length, message);
    t_last_decode_failed = error != DecodeError::kNone;
    if (t_last_decode_failed) {
      counters_.note(decode_error_name(error));
      message = T();
      return false;
    }
    payload->encapsulation = (payload->data[1] & 1) != 0 ? CDR_LE : CDR_BE;
    return true;
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return real_.getSerializedSizeProvider(data);
  }
  void* createData() override { return real_.createData(); }
  void deleteData(void* data) override { real_.deleteData(data); }
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool force_md5) override {
    return real_.getKey(data, handle, force_md5);
  }

 private:
  PubSubType real_;
  ReceiveCounters& counters_;
};

template <class Qos>
void apply_spec(Qos& qos, const TopicSpec& spec, panoptes::dds::Qos override_qos) {
  const bool reliable = override_qos == panoptes::dds::Qos::kReliable ||
                        (spec.reliable && override_qos != panoptes::dds::Qos::kBestEffort);
  qos.reliability().kind = reliable ? fdds::RELIABLE_RELIABILITY_QOS : fdds::BEST_EFFORT_RELIABILITY_QOS;
  qos.durability().kind = spec.durability == Durability::kTransientLocal
                              ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS
                              : fdds::VOLATILE_DURABILITY_QOS;
  qos.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  qos.history().depth = override_qos == panoptes::dds::Qos::kReliable ? kReliableDepth : spec.depth;
  // Keyed topics hold one instance per camera or body. Fast DDS's default limit of 10 instances
  // made a reader silently discard every camera after the tenth (found with 32 cameras, issue 7).
  qos.resource_limits().max_instances = kMaxInstances;
  qos.resource_limits().max_samples_per_instance = qos.history().depth;
  qos.resource_limits().max_samples = kMaxInstances * qos.history().depth;
  // Payloads sized by the samples that come, not preallocated at the type's maximum: the topics a
  // late joiner needs are written seldom and their types are large at their maximum (MarkerLabels
  // 10.5 MB, BodyDescriptions 293 KB with Fast DDS's default bounds), and Fast DDS reserves 100 of
  // them per endpoint. A Python client that created its MarkerLabels reader took 4-7 s in
  // python.bindings, clearing about a gigabyte of pages (perf: 79 % in clear_page under the
  // payload pool's reserve).
  if (spec.durability == Durability::kTransientLocal)
    qos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
}

// The reader and writer policies of a topic with a transport cap (TopicSpec::transport_cap, whose
// type's m_typeSize is that cap in every participant: GuardedPubSubType, RawPubSubType).
void apply_transport_cap(fdds::DataReaderQos& qos, const TopicSpec& spec);
void apply_transport_cap(fdds::DataWriterQos& qos, const TopicSpec& spec);

// The writer QoS of a topic (docs/protocol.md), for typed and raw writers alike.
fdds::DataWriterQos writer_qos_for(const TopicSpec& spec, Qos qos);
// The reader QoS of a topic, for typed and raw readers alike.
fdds::DataReaderQos reader_qos_for(const TopicSpec& spec, Qos qos);

// A topic panoptes_record and panoptes_replay (and panoptes_rogue) read and write as raw CDR: its
// public description, its QoS, and a factory of the generated type support it is decoded with.
struct RawTopicEntry {
  RawTopic topic;
  TopicSpec spec;
  std::function<fdds::TopicDataType*()> make_real;
};

// The entry of `topic`: a recorded one (a Panoptes topic or a ROS 2 one, whose name may carry a
// namespace or a body: rt/lab1/markers, rt/panoptes/head/pose) or one only panoptes_rogue writes;
// DdsInputError for another name.
RawTopicEntry raw_entry_named(const std::string& topic);

}  // namespace panoptes::dds
