// SPDX-License-Identifier: Apache-2.0
// The one place that knows Fast DDS: a participant loaded from an XML profile, topics with their
// canonical names and QoS (docs/protocol.md), typed writers and readers. Entities are created and
// checked in constructors and torn down with delete_contained_entities().
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "panoptes/dds/security.h"
#include "panoptes/errors.h"

namespace panoptes::dds {

// DDS failed at run time: a participant, topic, reader or writer it would not create (exit 1,
// panoptes/errors.h).
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the bus was given cannot be used: the DDS profile file (missing, not a profile Fast DDS can
// load, without the participant profile asked for), a topic name that is not a Panoptes topic, a
// camera or client id that cannot name a partition. An InputError (exit 2); what() names the file
// or the name. DDS Security files and the domain have their own (SecurityError, DomainError).
class DdsInputError : public InputError {
 public:
  using InputError::InputError;
};

struct BusOptions {
  // XML profile file. Empty: $PANOPTES_DDS_PROFILE, else deploy/dds/loopback.xml found next to the
  // executable or to libpanoptes_client.so (build tree or install prefix). Without a profile the bus refuses
  // to start, so Fast DDS's default multicast discovery never runs by accident.
  std::filesystem::path profile_file;
  std::string participant_profile = "panoptes_participant";
  // 0..232; -1: $PANOPTES_DOMAIN, else 0. Checked by resolve_domain (domain.h): the Bus throws its
  // DomainError (a ConfigError naming the variable or "domain") for anything else.
  int domain_id = -1;
  std::string participant_name = "panoptes";
  // DDS Security (docs/security.md). Empty: $PANOPTES_SECURITY_DIR and $PANOPTES_SECURITY_IDENTITY;
  // neither set: an unsecured participant, unless the profile requires security (deploy/dds/secure.xml
  // sets the participant property panoptes.security=required), which is then a SecurityError.
  SecurityOptions security;
  // false: the profile's shared-memory transport is left out (its UDP transports kept; a profile on
  // Fast DDS's builtin transports gets plain UDPv4), so this participant exchanges nothing with
  // others through shared memory; a profile with shared memory only (shm.xml) is kept as it is.
  // estimator_node's default: a Fast DDS 2.9 process that dies while it holds the lock of its
  // shared-memory port stalls every participant sending to it for the lock's 1 s timeout, all of that
  // participant's sends included (docs/protocol.md, "A peer that dies").
  bool shared_memory = true;
};

// Resolves the profile file as BusOptions describes; throws DdsInputError naming what was tried.
std::filesystem::path resolve_profile_file(const std::filesystem::path& requested);

enum class Qos {
  kDefault,   // the topic's own QoS (docs/protocol.md)
  kReliable,  // reliable with a deep history, e.g. recording features for calibration
  // Best effort on a reliable topic: what is lost is not repaired, and the writer sends this reader
  // no heartbeats and no gaps (e.g. a time-sync reply, useless once late).
  kBestEffort,
};

class BusCore;

// A Panoptes topic seen as serialized CDR, without decoding: what panoptes_record records and
// panoptes_replay publishes.
struct RawTopic {
  std::string topic;      // DDS name, "rt/panoptes/features"
  std::string type_name;  // DDS type name, "panoptes::msg::FeatureFrame"
  std::string ros_type;   // "panoptes/msg/FeatureFrame" (ROS 2 naming: rosbag2 schemas)
  bool transient_local = false;
};
// Every topic panoptes_record records by default, in a fixed order: the Panoptes topics of
// docs/protocol.md (the latency probes and the recorder's own left out), then the ROS 2 topics of
// docs/ros2.md with fixed names (rt/tf, rt/rigid_bodies, rt/markers).
std::vector<RawTopic> panoptes_raw_topics();
// `topic` if it can be recorded: one of the above, or a ROS 2 topic named after a namespace or a
// body (rt/lab1/rigid_bodies, rt/lab1/markers, rt/[lab1/]panoptes/<body>/pose|twist).
std::optional<RawTopic> recordable_topic(const std::string& topic);

// One serialized sample: the CDR payload as on the wire, its 4-byte encapsulation header included.
struct RawSample {
  std::vector<std::uint8_t> cdr;
  std::int64_t source_timestamp_ns = 0;  // the writer's
};

class RawReader {
 public:
  using Callback = std::function<void(RawSample&&)>;
  ~RawReader();
  RawReader(const RawReader&) = delete;
  RawReader& operator=(const RawReader&) = delete;
  int matched_writers() const;
  std::uint64_t received() const;
  struct Impl;
  explicit RawReader(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

class RawWriter {
 public:
  ~RawWriter();
  RawWriter(const RawWriter&) = delete;
  RawWriter& operator=(const RawWriter&) = delete;
  bool write(const std::vector<std::uint8_t>& cdr);
  int matched_readers() const;
  struct Impl;
  explicit RawWriter(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

template <class T>
class Writer {
 public:
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  bool write(const T& sample);
  int matched_readers() const;
  // Waits until at least `count` readers matched; false on timeout.
  bool wait_for_readers(int count, std::chrono::milliseconds timeout) const;
  // Waits until every reliable reader acknowledged every sample written (e.g. before a camera
  // node exits, so that a calibration capture gets the last frames repaired); false on timeout.
  bool wait_for_acknowledgments(std::chrono::milliseconds timeout) const;

  struct Impl;
  explicit Writer(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

// Who wrote a sample: its DDS writer's GUID (12-byte participant prefix, 4-byte entity id). Two
// processes writing one camera's topic have different writers (docs/estimator.md, "Two writers for
// one camera").
struct SampleSource {
  std::array<std::uint8_t, 16> writer_guid{};
  // The GUID as 32 hex digits, "<prefix>.<entity>" (24 + 8 digits): the form logs name it by.
  std::string writer() const;
};

template <class T>
class Reader {
 public:
  using Callback = std::function<void(T&&)>;
  using SourcedCallback = std::function<void(T&&, const SampleSource&)>;
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  int matched_writers() const;
  std::uint64_t received() const;

  struct Impl;
  explicit Reader(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

// Whether `id` can be the `scope` of a writer for that one camera (or client): a DDS partition name
// without ';' (the separator), wildcards ("*?[") and at most 256 characters. Ids from the bus
// (a time-sync request's client id, a script's target) are checked before a writer is made.
bool names_one_partition(std::string_view id);

class Bus {
 public:
  // Throws DdsInputError (the profile), SecurityError, DomainError, or DdsError when DDS refuses
  // the participant.
  explicit Bus(const BusOptions& options = {});
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  // T is one of the generated panoptes::msg types that has a topic (docs/protocol.md), or one of the
  // ROS 2 types of idl/ros2.idl (docs/ros2.md). `topic_name`, if not empty, replaces the type's
  // topic name (same QoS): the ROS 2 per-body topics rt/panoptes/<body>/pose. Types without a
  // topic of their own (geometry_msgs PoseStamped, TwistStamped) need one; DdsError otherwise.
  // `scope`, on a camera-scoped topic (camera_info, features, camera_status, camera_preview,
  // camera_command, predictions, time_sync): the camera (or time-sync client) id the writer speaks
  // for or writes to, the DDS partition it joins, which DDS Security permissions restrict
  // (docs/security.md, "Camera-scoped permissions"); the readers drop its samples that name another
  // id ("id_outside_partition"). Empty or "*": every camera (the estimator, operators, tools). An id
  // that cannot name a partition (with ';') is a DdsInputError; DDS refusing the writer a DdsError.
  template <class T>
  std::unique_ptr<Writer<T>> make_writer(Qos qos = Qos::kDefault, const std::string& topic_name = {},
                                         const std::string& scope = {});
  // `on_sample` runs on a DDS listener thread: keep it short (enqueue and return).
  // `only_id`, if not empty, subscribes to the samples addressed to one camera or client only: those
  // whose first member (camera_id of Predictions, client_id of TimeSync) equals it. It is a DDS
  // content filter that the writers apply (every Bus registers it), so the samples of the other
  // cameras are not even sent: traffic per camera stays constant as cameras are added. On a
  // camera-scoped topic (see make_writer) the reader also joins that camera's partition, so only
  // the writers for that camera or for every camera match it; camera_command has no leading id and
  // is selected by the partition alone. Throws DdsError for another type without such a member.
  template <class T>
  std::unique_ptr<Reader<T>> make_reader(typename Reader<T>::Callback on_sample, Qos qos = Qos::kDefault,
                                         const std::string& only_id = {}, const std::string& topic_name = {});
  // As make_reader, and `on_sample` also gets the sample's writer.
  template <class T>
  std::unique_ptr<Reader<T>> make_sourced_reader(typename Reader<T>::SourcedCallback on_sample,
                                                 Qos qos = Qos::kDefault, const std::string& only_id = {},
                                                 const std::string& topic_name = {});

  // Serialized samples of one of panoptes_raw_topics(). The reader asks for reliability where the
  // topic's writers offer it (so a recorder gets repairs) and for the history of transient-local
  // topics; the writer has the QoS of make_writer. DdsInputError for a topic that is not a Panoptes
  // topic.
  std::unique_ptr<RawReader> make_raw_reader(const std::string& topic, RawReader::Callback on_sample);
  std::unique_ptr<RawWriter> make_raw_writer(const std::string& topic);

  const std::filesystem::path& profile_file() const;
  // True when the participant joined with DDS Security.
  bool secured() const;

  // Received samples this Bus's readers dropped, by reason: the decode failures of decode.h
  // ("cdr_truncated", ...), "handler_error" (a reader's callback threw), and on camera-scoped topics
  // "id_outside_partition" (a sample naming another camera than its writer's partition) and
  // "unknown_writer". Reported in the nodes' status counters (docs/hostile_input.md).
  std::map<std::string, std::uint64_t> receive_rejections() const;

 private:
  std::shared_ptr<BusCore> core_;
};

}  // namespace panoptes::dds
