// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/bus.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string_view>
#include <thread>
#include <vector>

#include <fastdds/rtps/attributes/PropertyPolicy.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>
#include <fastdds/dds/topic/IContentFilter.hpp>
#include <fastdds/dds/topic/IContentFilterFactory.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "panoptes/dds/decode.h"
#include "panoptes/dds/security.h"
#include "panoptes/dds/shm_ports.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/chainsPubSubTypes.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/panoptesPubSubTypes.h"
#include "panoptes_msgs/ros2.h"
#include "panoptes_msgs/ros2PubSubTypes.h"
#include "panoptes_msgs/surface.h"
#include "panoptes_msgs/surfacePubSubTypes.h"

namespace fdds = eprosima::fastdds::dds;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

namespace panoptes::dds {
namespace {

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
};

template <class T>
struct TopicTraits;

// The camera-scoped topics (TopicSpec::camera_scoped).
template <class T>
constexpr bool kCameraScoped = false;
template <>
constexpr bool kCameraScoped<msg::CameraInfo> = true;
template <>
constexpr bool kCameraScoped<msg::FeatureFrame> = true;
template <>
constexpr bool kCameraScoped<msg::CameraStatus> = true;
template <>
constexpr bool kCameraScoped<msg::CameraCommand> = true;
template <>
constexpr bool kCameraScoped<msg::CameraPreview> = true;
template <>
constexpr bool kCameraScoped<msg::Predictions> = true;
template <>
constexpr bool kCameraScoped<msg::TimeSync> = true;

#define PANOPTES_TOPIC(Type, topic_name, reliable, durability, depth, offer_reliable, leading_id) \
  template <>                                                                                     \
  struct TopicTraits<msg::Type> {                                                                 \
    using PubSubType = msg::Type##PubSubType;                                                     \
    static TopicSpec spec() {                                                                     \
      return {topic_name,     reliable,   durability, depth,                                      \
              offer_reliable, leading_id, 0,          kCameraScoped<msg::Type>};                  \
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
// Camera-scoped topics (docs/security.md, "Camera-scoped permissions"). Each writer and reader is
// in DDS partitions (Fast DDS's per-endpoint "partitions" property): a camera's writers and its own
// readers in the partition named by its id; the writers of everyone else in "*" (every camera);
// the readers of every camera in "*" and the default partition "". DDS Security checks the
// partitions of every endpoint against the signed permissions, which grant a camera its own id
// only; each reader then drops a sample whose id is not its writer's partition, so a camera can
// neither publish nor read as another.

constexpr const char* kEveryCamera = "*";
constexpr const char* kPartitionsProperty = "partitions";

// The partitions of an endpoint on a camera-scoped topic, as the "partitions" property spells
// them (';'-separated). `scope`: the camera or client id the endpoint is for, or empty.
std::string scoped_partitions(const std::string& scope, bool reader) {
  if (scope.find(';') != std::string::npos)
    throw DdsError("camera or client id '" + scope + "': ';' cannot name a DDS partition");
  if (!scope.empty()) return scope;
  return reader ? std::string(";") + kEveryCamera : std::string(kEveryCamera);
}

// Whether a sample addressed to `id` may come from a writer in `partitions`: a writer in the
// default partition or in a wildcard one speaks for every camera (only operators and the estimator
// may do that when secured); a writer in named partitions only for those.
bool scope_allows(const std::vector<std::string>& partitions, std::string_view id) {
  if (partitions.empty()) return true;
  for (const std::string& partition : partitions) {
    if (partition.empty() || partition.find_first_of("*?[") != std::string::npos || partition == id)
      return true;
  }
  return false;
}

// The id a sample is addressed to or comes from: its leading camera or client id, or a command's target.
template <class T>
std::optional<std::string_view> addressed_id(const T& sample) {
  if constexpr (requires { sample.camera_id(); }) {
    return sample.camera_id();
  } else if constexpr (requires { sample.client_id(); }) {
    return sample.client_id();
  } else if constexpr (requires { sample.target(); }) {
    return sample.target();
  } else {
    return std::nullopt;
  }
}

using WriterKey = std::array<eprosima::fastrtps::rtps::octet, 16>;
WriterKey writer_key(const eprosima::fastrtps::rtps::InstanceHandle_t& handle) {
  WriterKey key{};
  std::memcpy(key.data(), handle.value, key.size());
  return key;
}
WriterKey writer_key(const eprosima::fastrtps::rtps::GUID_t& guid) {
  eprosima::fastrtps::rtps::InstanceHandle_t handle;
  handle = guid;
  return writer_key(handle);
}

// The partitions of every writer this participant discovered (remote ones through discovery, its
// own when created), so that a reader can check a sample against its writer's partitions.
class WriterPartitions : public fdds::DomainParticipantListener {
 public:
  void on_publisher_discovery(fdds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::WriterDiscoveryInfo::DISCOVERY_STATUS;
    const WriterKey key = writer_key(info.info.guid());
    if (info.status == Status::REMOVED_WRITER) {
      forget(key);
      return;
    }
    std::vector<std::string> partitions;
    for (const auto& name : info.info.m_qos.m_partition.names()) partitions.push_back(name);
    remember(key, std::move(partitions));
  }
  void remember(const WriterKey& key, std::vector<std::string> partitions) {
    std::lock_guard<std::mutex> lock(mutex_);
    partitions_[key] = std::move(partitions);
  }
  void forget(const WriterKey& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    partitions_.erase(key);
  }
  // Whether `writer` may write a sample addressed to `id` (none: any); what it may not is counted.
  bool admits(const eprosima::fastrtps::rtps::InstanceHandle_t& writer, std::optional<std::string_view> id,
              ReceiveCounters& counters) const {
    if (!id) return true;
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = partitions_.find(writer_key(writer));
    if (it == partitions_.end()) {
      counters.note("unknown_writer");  // discovery reports every writer before it matches
      return false;
    }
    if (scope_allows(it->second, *id)) return true;
    counters.note("id_outside_partition");
    return false;
  }

 private:
  mutable std::mutex mutex_;
  std::map<WriterKey, std::vector<std::string>> partitions_;
};

// ---------------------------------------------------------------------------------------------
// The `only_id` content filter. A custom filter class (not the SQL one, which needs the type's
// TypeObject) that reads the first member, a CDR string, straight from the serialised payload.
// Every participant registers it, so writers evaluate it for each matched reader and skip the
// readers a sample is not for (Fast DDS writer-side filtering, up to reader_filters_allocation
// readers per writer).

constexpr const char* kIdFilterClass = "PANOPTES_LEADING_ID";
constexpr const char* kIdFilterExpression = "leading_id = %0";

// The first string of a sample: 4 bytes of encapsulation (its second byte's low bit: little
// endian), a 4-byte length counting the terminating NUL, the characters.
std::optional<std::string_view> leading_string(const unsigned char* d, std::size_t length) {
  if (d == nullptr || length < 8) return std::nullopt;
  const bool little_endian = (d[1] & 1) != 0;
  std::uint32_t n = 0;
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t byte = d[4 + (little_endian ? i : 3 - i)];
    n |= byte << (8 * i);
  }
  if (n == 0 || n > length - 8) return std::nullopt;
  return std::string_view(reinterpret_cast<const char*>(d + 8), n - 1);
}
std::optional<std::string_view> leading_string(const eprosima::fastrtps::rtps::SerializedPayload_t& payload) {
  return leading_string(payload.data, payload.length);
}

class LeadingIdFilter final : public fdds::IContentFilter {
 public:
  explicit LeadingIdFilter(std::string id) : id_(std::move(id)) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&, const GUID_t&) const override {
    const auto id = leading_string(payload);
    return id.has_value() && *id == id_;
  }

 private:
  std::string id_;
};

class LeadingIdFilterFactory : public fdds::IContentFilterFactory {
 public:
  ReturnCode_t create_content_filter(const char*, const char*, const fdds::TopicDataType*, const char*,
                                     const ParameterSeq& parameters, fdds::IContentFilter*& filter) override {
    if (parameters.length() != 1 || parameters[0] == nullptr) return ReturnCode_t::RETCODE_BAD_PARAMETER;
    std::string_view id = parameters[0];
    if (id.size() >= 2 && id.front() == '\'' && id.back() == '\'') id = id.substr(1, id.size() - 2);
    delete static_cast<LeadingIdFilter*>(filter);
    filter = new LeadingIdFilter(std::string(id));
    return ReturnCode_t::RETCODE_OK;
  }
  ReturnCode_t delete_content_filter(const char*, fdds::IContentFilter* filter) override {
    delete static_cast<LeadingIdFilter*>(filter);
    return ReturnCode_t::RETCODE_OK;
  }
};

LeadingIdFilterFactory& leading_id_filter_factory() {
  static LeadingIdFilterFactory factory;  // outlives every participant
  return factory;
}

// ---------------------------------------------------------------------------------------------
// Received samples are decoded by decode_sample (decode.h), never by the generated code directly:
// that lets a bad encapsulation header or std::bad_alloc escape into Fast DDS's threads, and
// accepts strings without a terminator. A sample that fails is counted under its reason in the
// Bus's ReceiveCounters and dropped (docs/hostile_input.md).

// Set by GuardedPubSubType::deserialize on the thread that takes the sample: the reader's listener
// skips it. (Fast DDS 2.9 ignores deserialize's result when a reader takes a sample.)
thread_local bool t_last_decode_failed = false;

template <class PubSubType, class T>
class GuardedPubSubType final : public fdds::TopicDataType {
 public:
  explicit GuardedPubSubType(ReceiveCounters& counters) : counters_(counters) {
    setName(real_.getName());
    m_typeSize = real_.m_typeSize;
    m_isGetKeyDefined = real_.m_isGetKeyDefined;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    return real_.serialize(data, payload);
  }
  // Also decodes the samples whose key Fast DDS must compute on receipt.
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    T& message = *static_cast<T*>(data);
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
}

// The writer QoS of a topic (docs/protocol.md), for typed and raw writers alike.
fdds::DataWriterQos writer_qos_for(const TopicSpec& spec, Qos qos) {
  fdds::DataWriterQos writer_qos = fdds::DATAWRITER_QOS_DEFAULT;
  apply_spec(writer_qos, spec, qos);
  if (spec.offer_reliable && !spec.reliable && qos == Qos::kDefault) {
    writer_qos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    writer_qos.history().depth = kOfferedReliableDepth;
    writer_qos.resource_limits().max_samples_per_instance = kOfferedReliableDepth;
    writer_qos.resource_limits().max_samples = kMaxInstances * kOfferedReliableDepth;
    writer_qos.reliable_writer_qos().times.heartbeatPeriod =
        eprosima::fastrtps::Duration_t(0, kOfferedHeartbeatNs);
  }
  writer_qos.reliable_writer_qos().times.nackSupressionDuration =
      eprosima::fastrtps::Duration_t(0, static_cast<std::uint32_t>(spec.nack_suppression_ms) * 1'000'000U);
  // Evaluate the content filter of every matched reader (default: at most 32 readers per writer).
  writer_qos.writer_resource_limits().reader_filters_allocation =
      eprosima::fastrtps::ResourceLimitedContainerConfig(0, kMaxInstances, 1);
  return writer_qos;
}

std::filesystem::path executable_dir() {
  std::vector<char> buffer(4096);
  const ssize_t n = readlink("/proc/self/exe", buffer.data(), buffer.size() - 1);
  if (n <= 0) return {};
  return std::filesystem::path(std::string(buffer.data(), static_cast<std::size_t>(n))).parent_path();
}

// The directory of the binary holding this code: the executable, or a shared library that links
// panoptes_dds (libpanoptes_client.so in <prefix>/lib, used by programs installed anywhere).
std::filesystem::path module_dir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&module_dir), &info) == 0 || info.dli_fname == nullptr) return {};
  return std::filesystem::path(info.dli_fname).parent_path();
}

}  // namespace

std::filesystem::path resolve_profile_file(const std::filesystem::path& requested) {
  if (!requested.empty()) {
    if (!std::filesystem::is_regular_file(requested)) {
      throw DdsError("DDS profile " + requested.string() + ": no such file");
    }
    return requested;
  }
  if (const char* env = std::getenv("PANOPTES_DDS_PROFILE"); env != nullptr && *env != '\0') {
    if (!std::filesystem::is_regular_file(env)) {
      throw DdsError(std::string("PANOPTES_DDS_PROFILE=") + env + ": no such file");
    }
    return env;
  }
  const std::filesystem::path exe = executable_dir();
  const std::vector<std::filesystem::path> candidates = {
      exe / "../../deploy/dds/loopback.xml",                // build/bin in a source checkout
      exe / "../share/panoptes/dds/loopback.xml",           // installed prefix
      module_dir() / "../share/panoptes/dds/loopback.xml",  // <prefix>/lib/libpanoptes_client.so
      std::filesystem::path(PANOPTES_INSTALL_DATADIR) / "panoptes/dds/loopback.xml",  // configured prefix
      std::filesystem::path(PANOPTES_SOURCE_DIR) / "deploy/dds/loopback.xml",  // a build tree elsewhere
  };
  for (const auto& candidate : candidates) {
    if (std::filesystem::is_regular_file(candidate)) return std::filesystem::weakly_canonical(candidate);
  }
  std::string tried;
  for (const auto& candidate : candidates) tried += " " + candidate.lexically_normal().string();
  throw DdsError("no DDS profile given (--dds-profile or PANOPTES_DDS_PROFILE) and none found at:" + tried);
}

ReturnCode return_code_ok() {
  return ReturnCode::RETCODE_OK;
}

// The profile asks for DDS Security with the participant property panoptes.security=required.
bool profile_requires_security(const fdds::DomainParticipantQos& qos) {
  const std::string* value =
      eprosima::fastrtps::rtps::PropertyPolicyHelper::find_property(qos.properties(), "panoptes.security");
  return value != nullptr && *value == "required";
}

// Adds the DDS Security properties to `qos` when `options` (or the environment) name security
// files, after checking them; nullopt for an unsecured participant. SecurityError for bad files and
// for a profile that requires security without them.
std::optional<SecurityFiles> apply_security(const BusOptions& options, const std::filesystem::path& profile,
                                            fdds::DomainParticipantQos& qos) {
  std::optional<SecurityFiles> files = resolve_security_files(options.security);
  if (!files) {
    if (profile_requires_security(qos))
      throw SecurityError(profile.string(), "panoptes.security",
                          "the profile requires DDS Security: give --security-dir and --security-identity "
                          "(or PANOPTES_SECURITY_DIR and PANOPTES_SECURITY_IDENTITY)");
    return std::nullopt;
  }
  check_security_files(*files);
  for (const auto& [name, value] : security_properties(*files))
    qos.properties().properties().emplace_back(name, value);
  return files;
}

// Where Fast DDS 2.9 keeps its shared-memory segments and their lock files on Linux.
constexpr const char* kShmDir = "/dev/shm";
constexpr const char* kProcDir = "/proc";
// Participant ids tried for one without an initial-peer range (discovery by multicast or server).
constexpr int kParticipantIdLimit = 120;

bool uses_shared_memory(const fdds::DomainParticipantQos& qos) {
  if (qos.transport().use_builtin_transports) return true;
  for (const auto& transport : qos.transport().user_transports) {
    if (std::dynamic_pointer_cast<eprosima::fastdds::rtps::SharedMemTransportDescriptor>(transport))
      return true;
  }
  return false;
}

// The ids a participant can take and still be found: with initial peers, those whose ports the
// UDP transports probe (maxInitialPeersRange).
int participant_id_limit(const fdds::DomainParticipantQos& qos) {
  int limit = kParticipantIdLimit;
  if (qos.wire_protocol().builtin.initialPeersList.empty()) return limit;
  if (qos.transport().use_builtin_transports)
    limit = std::min(
        limit, static_cast<int>(eprosima::fastdds::rtps::UDPv4TransportDescriptor().maxInitialPeersRange));
  for (const auto& transport : qos.transport().user_transports) {
    if (std::dynamic_pointer_cast<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(transport))
      limit = std::min(limit, static_cast<int>(transport->maxInitialPeersRange));
  }
  return limit;
}

// Keeps a participant off the shared-memory ports of participants killed on this host, and off
// those a process still maps after they were removed (shm_ports.h):
// taking one would cut it off from every writer that still maps the killed one's segment (a console
// restarted after SIGKILL received no FeatureFrame from some or all cameras). An id the profile sets
// is kept; when every id is taken, Fast DDS chooses as before.
void keep_off_killed_participants_ports(fdds::DomainParticipantQos& qos, std::uint32_t domain) {
  auto& wire = qos.wire_protocol();
  if (wire.participant_id >= 0 || !uses_shared_memory(qos)) return;
  const ParticipantPortRule rule{wire.port.portBase, wire.port.domainIDGain, wire.port.participantIDGain,
                                 wire.port.offsetd1, wire.port.offsetd3};
  if (const auto id = participant_id_clear_of_owned_shm_ports(
          rule, domain, participant_id_limit(qos), kShmDir, shm_ports_mapped_after_removal(kProcDir)))
    wire.participant_id = *id;
}

// Held from choosing a participant id until its ports exist: two buses of one process never take
// the same id.
std::mutex& participant_creation_mutex() {
  static std::mutex mutex;
  return mutex;
}

class BusCore {
 public:
  explicit BusCore(const BusOptions& options) : profile_file_(resolve_profile_file(options.profile_file)) {
    auto* factory = fdds::DomainParticipantFactory::get_instance();
    if (factory->load_XML_profiles_file(profile_file_.string()) != return_code_ok()) {
      throw DdsError("DDS profile " + profile_file_.string() + ": cannot be parsed");
    }
    fdds::DomainParticipantQos qos;
    if (factory->get_participant_qos_from_profile(options.participant_profile, qos) != return_code_ok()) {
      throw DdsError("DDS profile " + profile_file_.string() + ": no participant profile named '" +
                     options.participant_profile + "'");
    }
    qos.name(options.participant_name);
    security_files_ = apply_security(options, profile_file_, qos);
    int domain = options.domain_id;
    if (domain < 0) {
      const char* env = std::getenv("PANOPTES_DOMAIN");
      domain = env != nullptr ? std::atoi(env) : 0;
    }
    {
      std::lock_guard<std::mutex> lock(participant_creation_mutex());
      keep_off_killed_participants_ports(qos, static_cast<std::uint32_t>(domain));
      participant_ = factory->create_participant(static_cast<fdds::DomainId_t>(domain), qos,
                                                 &writer_partitions_, fdds::StatusMask::none());
    }
    if (participant_ == nullptr && security_files_) {
      fdds::Log::Flush();  // Fast DDS's own reason, logged asynchronously, goes out before ours
      throw SecurityError(
          security_files_->certificate.string(), "",
          "DDS Security refused to create the participant (domain " + std::to_string(domain) +
              "): a certificate not signed by the identity CA, expired or revoked, a key that "
              "does not match it, or a governance or permissions document not signed by the "
              "permissions CA or not granting this domain and subject (Fast DDS's reason is "
              "logged above). Files: " +
              describe_security_files(*security_files_));
    }
    if (participant_ == nullptr)
      throw DdsError("cannot create DDS participant (domain " + std::to_string(domain) + ")");
    if (participant_->register_content_filter_factory(kIdFilterClass, &leading_id_filter_factory()) !=
        return_code_ok()) {
      teardown();
      throw DdsError("cannot register the DDS content filter " + std::string(kIdFilterClass));
    }
    publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    if (publisher_ == nullptr || subscriber_ == nullptr) {
      teardown();
      throw DdsError("cannot create DDS publisher/subscriber");
    }
  }
  ~BusCore() { teardown(); }
  BusCore(const BusCore&) = delete;
  BusCore& operator=(const BusCore&) = delete;

  template <class T>
  fdds::Topic* topic(const std::string& name) {
    return topic_of_type(name, [this] {
      return fdds::TypeSupport(
          new GuardedPubSubType<typename TopicTraits<T>::PubSubType, T>(receive_counters_));
    });
  }

  // The topic `name`, created with the type `make_type` returns the first time.
  fdds::Topic* topic_of_type(const std::string& name, const std::function<fdds::TypeSupport()>& make_type) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (auto it = topics_.find(name); it != topics_.end()) return it->second;
    fdds::TypeSupport type = make_type();
    if (type.register_type(participant_) != return_code_ok()) {
      throw DdsError("cannot register DDS type for " + name);
    }
    fdds::Topic* topic = participant_->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    if (topic == nullptr) throw DdsError("cannot create DDS topic " + name + refusal_hint());
    topics_.emplace(name, topic);
    return topic;
  }

  // A content-filtered view of T's topic holding the samples whose leading id is `id`.
  template <class T>
  fdds::ContentFilteredTopic* filtered_topic(const std::string& topic_name, const std::string& id) {
    fdds::Topic* related = topic<T>(topic_name);
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string name = topic_name + "|" + id + "|" + std::to_string(filtered_count_++);
    return participant_->create_contentfilteredtopic(name, related, kIdFilterExpression, {"'" + id + "'"},
                                                     kIdFilterClass);
  }
  void delete_filtered_topic(fdds::ContentFilteredTopic* topic) {
    std::lock_guard<std::mutex> lock(mutex_);
    participant_->delete_contentfilteredtopic(topic);
  }

  fdds::Publisher* publisher() const { return publisher_; }
  fdds::Subscriber* subscriber() const { return subscriber_; }
  const std::filesystem::path& profile_file() const { return profile_file_; }
  ReceiveCounters& receive_counters() { return receive_counters_; }
  WriterPartitions& writer_partitions() { return writer_partitions_; }
  bool secured() const { return security_files_.has_value(); }
  // Appended to a refused writer, reader or topic: with DDS Security, the likely reason.
  std::string refusal_hint() const {
    return secured() ? " (DDS Security: not granted by " + security_files_->permissions.string() + ")" : "";
  }

 private:
  void teardown() {
    if (participant_ == nullptr) return;
    participant_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
    participant_ = nullptr;
  }

  std::filesystem::path profile_file_;
  ReceiveCounters receive_counters_;    // outlives the participant: its types refer to it
  WriterPartitions writer_partitions_;  // the participant's listener
  std::optional<SecurityFiles> security_files_;
  fdds::DomainParticipant* participant_ = nullptr;
  fdds::Publisher* publisher_ = nullptr;
  fdds::Subscriber* subscriber_ = nullptr;
  std::mutex mutex_;
  std::map<std::string, fdds::Topic*> topics_;
  std::uint64_t filtered_count_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Writer

class WriterListener : public fdds::DataWriterListener {
 public:
  void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus& status) override {
    matched.store(status.current_count);
  }
  std::atomic<int> matched{0};
};

template <class T>
struct Writer<T>::Impl {
  std::shared_ptr<BusCore> core;
  fdds::DataWriter* writer = nullptr;
  WriterListener listener;
};

template <class T>
Writer<T>::Writer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

template <class T>
Writer<T>::~Writer() {
  if (impl_ && impl_->writer != nullptr) {
    impl_->core->writer_partitions().forget(writer_key(impl_->writer->guid()));
    impl_->writer->set_listener(nullptr);
    impl_->core->publisher()->delete_datawriter(impl_->writer);
  }
}

template <class T>
bool Writer<T>::write(const T& sample) {
  return impl_->writer->write(const_cast<T*>(&sample));
}

template <class T>
int Writer<T>::matched_readers() const {
  return impl_->listener.matched.load();
}

template <class T>
bool Writer<T>::wait_for_acknowledgments(std::chrono::milliseconds timeout) const {
  const auto ms = timeout.count();
  return impl_->writer->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
             static_cast<std::int32_t>(ms / 1000), static_cast<std::uint32_t>((ms % 1000) * 1'000'000))) ==
         return_code_ok();
}

template <class T>
bool Writer<T>::wait_for_readers(int count, std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (matched_readers() < count) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Reader

// What the typed and the raw readers' listeners share: the callback, the check of a sample's id
// against its writer's partition on a camera-scoped topic, the counts, and deactivation.
template <class Callback>
class GatedReaderListener : public fdds::DataReaderListener {
 public:
  // `partitions`, on a camera-scoped topic: the writers' partitions each sample is checked against.
  GatedReaderListener(Callback callback, ReceiveCounters& counters, const WriterPartitions* partitions)
      : callback_(std::move(callback)), counters_(counters), partitions_(partitions) {}

  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& status) override {
    matched.store(status.current_count);
  }
  // After this returns no callback is running or will run.
  void deactivate() {
    std::lock_guard<std::mutex> lock(mutex_);
    active_ = false;
  }

  std::atomic<int> matched{0};
  std::atomic<std::uint64_t> received{0};

 protected:
  // False (counted) when the sample's id, from `id_of()` (asked only on a camera-scoped topic),
  // names another camera than its writer's partition.
  template <class IdOf>
  bool admits(const fdds::SampleInfo& info, const IdOf& id_of) {
    return partitions_ == nullptr || partitions_->admits(info.publication_handle, id_of(), counters_);
  }

  Callback callback_;
  ReceiveCounters& counters_;
  std::mutex mutex_;  // held while a callback runs
  bool active_ = true;

 private:
  const WriterPartitions* partitions_;
};

template <class T>
class ReaderListener : public GatedReaderListener<typename Reader<T>::Callback> {
 public:
  using GatedReaderListener<typename Reader<T>::Callback>::GatedReaderListener;

  void on_data_available(fdds::DataReader* reader) override {
    std::lock_guard<std::mutex> lock(this->mutex_);
    if (!this->active_) return;
    T sample;
    fdds::SampleInfo info;
    t_last_decode_failed = false;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      const bool decoded = !t_last_decode_failed;
      t_last_decode_failed = false;
      if (!info.valid_data || !decoded) continue;  // a failed decode is counted by its type
      if (!this->admits(info, [&] { return addressed_id(sample); })) continue;
      this->received.fetch_add(1);
      // Runs on a Fast DDS thread: whatever a sample makes the handler throw is counted, not fatal.
      try {
        this->callback_(std::move(sample));
      } catch (const std::exception&) {
        this->counters_.note("handler_error");
      }
      sample = T();
    }
  }
};

template <class T>
struct Reader<T>::Impl {
  std::shared_ptr<BusCore> core;
  fdds::ContentFilteredTopic* filtered_topic = nullptr;  // with `only_id`
  fdds::DataReader* reader = nullptr;
  std::unique_ptr<ReaderListener<T>> listener;
};

template <class T>
Reader<T>::Reader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

template <class T>
Reader<T>::~Reader() {
  if (!impl_) return;
  impl_->listener->deactivate();
  if (impl_->reader != nullptr) {
    impl_->reader->set_listener(nullptr);
    impl_->core->subscriber()->delete_datareader(impl_->reader);
  }
  if (impl_->filtered_topic != nullptr) impl_->core->delete_filtered_topic(impl_->filtered_topic);
}

template <class T>
int Reader<T>::matched_writers() const {
  return impl_->listener->matched.load();
}

template <class T>
std::uint64_t Reader<T>::received() const {
  return impl_->listener->received.load();
}

// ---------------------------------------------------------------------------------------------
// Bus

Bus::Bus(const BusOptions& options) : core_(std::make_shared<BusCore>(options)) {}
Bus::~Bus() = default;

const std::filesystem::path& Bus::profile_file() const {
  return core_->profile_file();
}

std::map<std::string, std::uint64_t> Bus::receive_rejections() const {
  return core_->receive_counters().snapshot();
}

bool Bus::secured() const {
  return core_->secured();
}

bool names_one_partition(std::string_view id) {
  constexpr std::size_t kMaxPartitionName = 256;
  return !id.empty() && id.size() <= kMaxPartitionName && id.find_first_of(";*?[") == std::string_view::npos;
}

namespace {

// The topic's name: `requested` if given, else the type's own; DdsError if neither.
template <class T>
std::string topic_name_for(const std::string& requested) {
  if (!requested.empty()) return requested;
  std::string name = TopicTraits<T>::spec().name;
  if (name.empty()) throw DdsError("a DDS topic of this type needs a name (e.g. rt/panoptes/<body>/pose)");
  return name;
}

}  // namespace

template <class T>
std::unique_ptr<Writer<T>> Bus::make_writer(Qos qos, const std::string& topic_name,
                                            const std::string& scope) {
  auto impl = std::make_unique<typename Writer<T>::Impl>();
  impl->core = core_;
  const TopicSpec spec = TopicTraits<T>::spec();
  const std::string name = topic_name_for<T>(topic_name);
  fdds::Topic* topic = core_->topic<T>(name);
  fdds::DataWriterQos writer_qos = writer_qos_for(spec, qos);
  std::vector<std::string> partitions;
  if (spec.camera_scoped) {
    const std::string property = scoped_partitions(scope, false);
    writer_qos.properties().properties().emplace_back(kPartitionsProperty, property);
    partitions.push_back(property);
  }
  impl->writer = core_->publisher()->create_datawriter(topic, writer_qos, &impl->listener);
  if (impl->writer == nullptr) {
    throw DdsError("cannot create DDS writer on " + name + (scope.empty() ? "" : " for '" + scope + "'") +
                   core_->refusal_hint());
  }
  core_->writer_partitions().remember(writer_key(impl->writer->guid()), std::move(partitions));
  return std::make_unique<Writer<T>>(std::move(impl));
}

template <class T>
std::unique_ptr<Reader<T>> Bus::make_reader(typename Reader<T>::Callback on_sample, Qos qos,
                                            const std::string& only_id, const std::string& topic_name) {
  const TopicSpec spec = TopicTraits<T>::spec();
  const std::string name = topic_name_for<T>(topic_name);
  auto impl = std::make_unique<typename Reader<T>::Impl>();
  impl->core = core_;
  impl->listener =
      std::make_unique<ReaderListener<T>>(std::move(on_sample), core_->receive_counters(),
                                          spec.camera_scoped ? &core_->writer_partitions() : nullptr);
  fdds::TopicDescription* topic = core_->topic<T>(name);
  fdds::DataReaderQos reader_qos = fdds::DATAREADER_QOS_DEFAULT;
  apply_spec(reader_qos, spec, qos);
  if (spec.camera_scoped)
    reader_qos.properties().properties().emplace_back(kPartitionsProperty, scoped_partitions(only_id, true));
  // A camera-scoped topic without a leading id (commands): the partition alone selects the samples.
  if (!only_id.empty() && !(spec.camera_scoped && !spec.leading_id)) {
    if (!spec.leading_id) throw DdsError("cannot filter " + name + " by id: it has no leading id");
    impl->filtered_topic = core_->filtered_topic<T>(name, only_id);
    if (impl->filtered_topic == nullptr)
      throw DdsError("cannot create the content filter on " + name + " for '" + only_id + "'");
    topic = impl->filtered_topic;
  }
  impl->reader = core_->subscriber()->create_datareader(topic, reader_qos, impl->listener.get());
  if (impl->reader == nullptr) {
    if (impl->filtered_topic != nullptr) core_->delete_filtered_topic(impl->filtered_topic);
    throw DdsError("cannot create DDS reader on " + name + (only_id.empty() ? "" : " for '" + only_id + "'") +
                   core_->refusal_hint());
  }
  return std::make_unique<Reader<T>>(std::move(impl));
}

// NOLINTBEGIN(bugprone-macro-parentheses): a type argument of a template cannot be parenthesised
#define PANOPTES_INSTANTIATE_TYPE(Type)                                                      \
  template class Writer<Type>;                                                               \
  template class Reader<Type>;                                                               \
  template std::unique_ptr<Writer<Type>> Bus::make_writer<Type>(Qos, const std::string&,     \
                                                                const std::string&);         \
  template std::unique_ptr<Reader<Type>> Bus::make_reader<Type>(Reader<Type>::Callback, Qos, \
                                                                const std::string&, const std::string&);
#define PANOPTES_INSTANTIATE(Type) PANOPTES_INSTANTIATE_TYPE(msg::Type)

PANOPTES_INSTANTIATE(CameraInfo)
PANOPTES_INSTANTIATE(FeatureFrame)
PANOPTES_INSTANTIATE(CameraStatus)
PANOPTES_INSTANTIATE(CameraCommand)
PANOPTES_INSTANTIATE(CameraPreview)
PANOPTES_INSTANTIATE(Predictions)
PANOPTES_INSTANTIATE(TimeSync)
PANOPTES_INSTANTIATE(EstimatorStatus)
PANOPTES_INSTANTIATE(TrackFrame)
PANOPTES_INSTANTIATE(BodyPose)
PANOPTES_INSTANTIATE(SystemCalibration)
PANOPTES_INSTANTIATE(LatencyProbe)
PANOPTES_INSTANTIATE(LatencyProbeEcho)
PANOPTES_INSTANTIATE(LatencyTraces)
PANOPTES_INSTANTIATE(MocapFrame)
PANOPTES_INSTANTIATE(BodyDescriptions)
PANOPTES_INSTANTIATE(RecorderCommand)
PANOPTES_INSTANTIATE(RecorderStatus)
PANOPTES_INSTANTIATE(StrokeEvents)
PANOPTES_INSTANTIATE(ChainFrame)
PANOPTES_INSTANTIATE_TYPE(geometry_msgs::msg::dds_::PoseStamped_)
PANOPTES_INSTANTIATE_TYPE(geometry_msgs::msg::dds_::TwistStamped_)
PANOPTES_INSTANTIATE_TYPE(tf2_msgs::msg::dds_::TFMessage_)
PANOPTES_INSTANTIATE_TYPE(mocap4r2_msgs::msg::dds_::RigidBodies_)
PANOPTES_INSTANTIATE_TYPE(mocap4r2_msgs::msg::dds_::Markers_)
#undef PANOPTES_INSTANTIATE
#undef PANOPTES_INSTANTIATE_TYPE
// NOLINTEND(bugprone-macro-parentheses)

// ---------------------------------------------------------------------------------------------
// Raw (serialized) samples: panoptes_record and panoptes_replay

namespace {

// Keeps the serialized payload as it is. It bears the real type's name, size bound and key flag,
// so it matches the typed writers and readers; the key of a sample to write is computed by the
// real type from the decoded sample.
class RawPubSubType final : public fdds::TopicDataType {
 public:
  explicit RawPubSubType(std::unique_ptr<fdds::TopicDataType> real) : real_(std::move(real)) {
    setName(real_->getName());
    m_typeSize = real_->m_typeSize;
    m_isGetKeyDefined = real_->m_isGetKeyDefined;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const auto& cdr = static_cast<RawSample*>(data)->cdr;
    if (cdr.size() < 4 || cdr.size() > payload->max_size) return false;
    std::memcpy(payload->data, cdr.data(), cdr.size());
    payload->length = static_cast<std::uint32_t>(cdr.size());
    payload->encapsulation = (cdr[1] & 1) != 0 ? CDR_LE : CDR_BE;
    return true;
  }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    auto& cdr = static_cast<RawSample*>(data)->cdr;
    cdr.assign(payload->data, payload->data + payload->length);
    return true;
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    const auto size = static_cast<std::uint32_t>(static_cast<RawSample*>(data)->cdr.size());
    return [size] { return size; };
  }
  void* createData() override { return new RawSample(); }
  void deleteData(void* data) override { delete static_cast<RawSample*>(data); }
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle, bool force_md5) override {
    if (!m_isGetKeyDefined) return false;
    const auto& cdr = static_cast<RawSample*>(data)->cdr;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(cdr.size()));
    std::memcpy(payload.data, cdr.data(), cdr.size());
    payload.length = static_cast<std::uint32_t>(cdr.size());
    void* typed = real_->createData();
    bool ok = false;
    try {
      ok = real_->deserialize(&payload, typed) && real_->getKey(typed, handle, force_md5);
    } catch (const std::exception&) {
      ok = false;
    }
    real_->deleteData(typed);
    if (!ok) {
      // A sample that does not decode (panoptes_rogue writes such on purpose) joins one instance of
      // its own, so the writer still sends it.
      *handle = eprosima::fastrtps::rtps::InstanceHandle_t();
      handle->value[15] = 1;
    }
    return true;
  }

 private:
  std::unique_ptr<fdds::TopicDataType> real_;
};

struct RawTopicEntry {
  RawTopic topic;
  TopicSpec spec;
  std::function<fdds::TopicDataType*()> make_real;
};

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
  };
  return entries;
}

// Topics a raw writer may write although panoptes_record does not record them (panoptes_rogue).
const std::vector<RawTopicEntry>& unrecorded_raw_entries() {
  static const std::vector<RawTopicEntry> entries = {
      raw_entry<msg::RecorderCommand>("panoptes/msg/RecorderCommand"),
      raw_entry<msg::RecorderStatus>("panoptes/msg/RecorderStatus"),
  };
  return entries;
}

const RawTopicEntry& raw_entry_named(const std::string& topic) {
  for (const auto* entries : {&raw_entries(), &unrecorded_raw_entries()}) {
    for (const auto& entry : *entries) {
      if (entry.topic.topic == topic) return entry;
    }
  }
  throw DdsError("'" + topic + "' is not a Panoptes topic (docs/protocol.md)");
}

class RawReaderListener : public GatedReaderListener<RawReader::Callback> {
 public:
  using GatedReaderListener<RawReader::Callback>::GatedReaderListener;

  void on_data_available(fdds::DataReader* reader) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!active_) return;
    RawSample sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (!info.valid_data) continue;
      // A sample that does not decode has no id: it is recorded as it came (docs/hostile_input.md).
      if (!admits(info, [&] { return leading_string(sample.cdr.data(), sample.cdr.size()); })) continue;
      received.fetch_add(1);
      sample.source_timestamp_ns = info.source_timestamp.to_ns();
      callback_(std::move(sample));
      sample = RawSample();
    }
  }
};

}  // namespace

std::vector<RawTopic> panoptes_raw_topics() {
  std::vector<RawTopic> topics;
  for (const auto& entry : raw_entries()) topics.push_back(entry.topic);
  return topics;
}

struct RawReader::Impl {
  std::shared_ptr<BusCore> core;
  fdds::DataReader* reader = nullptr;
  std::unique_ptr<RawReaderListener> listener;
};

RawReader::RawReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RawReader::~RawReader() {
  if (!impl_) return;
  impl_->listener->deactivate();
  if (impl_->reader != nullptr) {
    impl_->reader->set_listener(nullptr);
    impl_->core->subscriber()->delete_datareader(impl_->reader);
  }
}
int RawReader::matched_writers() const {
  return impl_->listener->matched.load();
}
std::uint64_t RawReader::received() const {
  return impl_->listener->received.load();
}

struct RawWriter::Impl {
  std::shared_ptr<BusCore> core;
  fdds::DataWriter* writer = nullptr;
  WriterListener listener;
};

RawWriter::RawWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RawWriter::~RawWriter() {
  if (impl_ && impl_->writer != nullptr) {
    impl_->writer->set_listener(nullptr);
    impl_->core->publisher()->delete_datawriter(impl_->writer);
  }
}
bool RawWriter::write(const std::vector<std::uint8_t>& cdr) {
  RawSample sample;
  sample.cdr = cdr;
  return impl_->writer->write(&sample);
}
int RawWriter::matched_readers() const {
  return impl_->listener.matched.load();
}

namespace {

fdds::Topic* raw_topic(BusCore& core, const RawTopicEntry& entry) {
  return core.topic_of_type(entry.topic.topic, [&entry] {
    return fdds::TypeSupport(new RawPubSubType(std::unique_ptr<fdds::TopicDataType>(entry.make_real())));
  });
}

}  // namespace

std::unique_ptr<RawReader> Bus::make_raw_reader(const std::string& topic, RawReader::Callback on_sample) {
  const RawTopicEntry& entry = raw_entry_named(topic);
  auto impl = std::make_unique<RawReader::Impl>();
  impl->core = core_;
  impl->listener =
      std::make_unique<RawReaderListener>(std::move(on_sample), core_->receive_counters(),
                                          entry.spec.camera_scoped ? &core_->writer_partitions() : nullptr);
  fdds::DataReaderQos reader_qos = fdds::DATAREADER_QOS_DEFAULT;
  const bool offered = entry.spec.reliable || entry.spec.offer_reliable;
  apply_spec(reader_qos, entry.spec, offered ? Qos::kReliable : Qos::kDefault);
  if (entry.spec.camera_scoped)
    reader_qos.properties().properties().emplace_back(kPartitionsProperty, scoped_partitions({}, true));
  impl->reader =
      core_->subscriber()->create_datareader(raw_topic(*core_, entry), reader_qos, impl->listener.get());
  if (impl->reader == nullptr) throw DdsError("cannot create DDS reader on " + topic + core_->refusal_hint());
  return std::make_unique<RawReader>(std::move(impl));
}

std::unique_ptr<RawWriter> Bus::make_raw_writer(const std::string& topic) {
  const RawTopicEntry& entry = raw_entry_named(topic);
  auto impl = std::make_unique<RawWriter::Impl>();
  impl->core = core_;
  fdds::DataWriterQos writer_qos = writer_qos_for(entry.spec, Qos::kDefault);
  if (entry.spec.camera_scoped)
    writer_qos.properties().properties().emplace_back(kPartitionsProperty, scoped_partitions({}, false));
  impl->writer = core_->publisher()->create_datawriter(raw_topic(*core_, entry), writer_qos, &impl->listener);
  if (impl->writer == nullptr) throw DdsError("cannot create DDS writer on " + topic + core_->refusal_hint());
  return std::make_unique<RawWriter>(std::move(impl));
}

}  // namespace panoptes::dds
