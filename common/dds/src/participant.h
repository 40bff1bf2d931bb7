// SPDX-License-Identifier: Apache-2.0
// Private to panoptes_dds: the participant every Bus owns (profile, DDS Security, domain and
// shared-memory ports resolved when it is made), with its publisher, subscriber and topics.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "panoptes/dds/bus.h"
#include "panoptes/dds/decode.h"
#include "panoptes/dds/security.h"
#include "scoping.h"
#include "topics.h"

namespace panoptes::dds {

using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

ReturnCode return_code_ok();

// The participant's listener: the writers' partitions (WriterPartitions), and the processes of the
// participants it discovered (its shared memory reaches those of this host: BusCore::teardown).
class ParticipantListener final : public WriterPartitions {
 public:
  void on_participant_discovery(fdds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override;
  // Whether a participant of another process on the host of `own` was discovered. Fast DDS 2.9's
  // GUID prefixes start with the vendor (2 octets), the host (2) and the process (4).
  bool discovered_another_process_on_host_of(const eprosima::fastrtps::rtps::GuidPrefix_t& own) const;

 private:
  using ProcessKey = std::array<eprosima::fastrtps::rtps::octet, 8>;
  mutable std::mutex mutex_;
  std::set<ProcessKey> processes_;
};

class BusCore {
 public:
  // Throws DdsInputError (the profile), SecurityError, DomainError or DdsError naming what is wrong.
  explicit BusCore(const BusOptions& options);
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
  fdds::Topic* topic_of_type(const std::string& name, const std::function<fdds::TypeSupport()>& make_type);

  // A content-filtered view of T's topic holding the samples whose leading id is `id`.
  template <class T>
  fdds::ContentFilteredTopic* filtered_topic(const std::string& topic_name, const std::string& id) {
    fdds::Topic* related = topic<T>(topic_name);
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string name = topic_name + "|" + id + "|" + std::to_string(filtered_count_++);
    return participant_->create_contentfilteredtopic(name, related, kIdFilterExpression, {"'" + id + "'"},
                                                     kIdFilterClass);
  }
  void delete_filtered_topic(fdds::ContentFilteredTopic* topic);

  fdds::Publisher* publisher() const { return publisher_; }
  fdds::Subscriber* subscriber() const { return subscriber_; }
  const std::filesystem::path& profile_file() const { return profile_file_; }
  ReceiveCounters& receive_counters() { return receive_counters_; }
  WriterPartitions& writer_partitions() { return listener_; }
  bool secured() const { return security_files_.has_value(); }
  // Appended to a refused writer, reader or topic: with DDS Security, the likely reason.
  std::string refusal_hint() const {
    return secured() ? " (DDS Security: not granted by " + security_files_->permissions.string() + ")" : "";
  }

 private:
  // The participant in `domain`, its content filter, publisher and subscriber; `qos` from the profile,
  // its shared-memory transport left out unless `shared_memory` (BusOptions).
  void create_entities(int domain, fdds::DomainParticipantQos& qos, bool shared_memory);
  void teardown();

  std::filesystem::path profile_file_;
  ReceiveCounters receive_counters_;  // outlives the participant: its types refer to it
  ParticipantListener listener_;
  std::optional<SecurityFiles> security_files_;
  fdds::DomainParticipant* participant_ = nullptr;
  // The participant's shared-memory data segment ("fastrtps_<id>"), kept reachable after it closes
  // (shm_ports.h, keep_shm_segment_name); empty when it has none or it was not found.
  std::string shm_segment_;
  fdds::Publisher* publisher_ = nullptr;
  fdds::Subscriber* subscriber_ = nullptr;
  std::mutex mutex_;
  std::map<std::string, fdds::Topic*> topics_;
  std::uint64_t filtered_count_ = 0;
};

}  // namespace panoptes::dds
