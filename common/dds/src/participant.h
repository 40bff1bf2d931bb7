// SPDX-License-Identifier: Apache-2.0
// Private to panoptes_dds: the participant every Bus owns (profile, DDS Security, domain and
// shared-memory ports resolved when it is made), with its publisher, subscriber and topics.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
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
  WriterPartitions& writer_partitions() { return writer_partitions_; }
  bool secured() const { return security_files_.has_value(); }
  // Appended to a refused writer, reader or topic: with DDS Security, the likely reason.
  std::string refusal_hint() const {
    return secured() ? " (DDS Security: not granted by " + security_files_->permissions.string() + ")" : "";
  }

 private:
  // The participant in `domain`, its content filter, publisher and subscriber; `qos` from the profile.
  void create_entities(int domain, fdds::DomainParticipantQos& qos);
  void teardown();

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

}  // namespace panoptes::dds
