// SPDX-License-Identifier: Apache-2.0
// Private to panoptes_dds: who may read and write what. Camera-scoped topics put each endpoint in
// DDS partitions and check every received sample against its writer's partitions; the `only_id`
// content filter lets writers skip the readers a sample is not for.
#pragma once

#include <array>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <fastdds/rtps/common/InstanceHandle.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/topic/IContentFilterFactory.hpp>

#include "panoptes/dds/decode.h"

namespace panoptes::dds {

namespace fdds = eprosima::fastdds::dds;

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
std::string scoped_partitions(const std::string& scope, bool reader);

// Whether a sample addressed to `id` may come from a writer in `partitions`: a writer in the
// default partition or in a wildcard one speaks for every camera (only operators and the estimator
// may do that when secured); a writer in named partitions only for those.
bool scope_allows(const std::vector<std::string>& partitions, std::string_view id);

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
WriterKey writer_key(const eprosima::fastrtps::rtps::InstanceHandle_t& handle);
WriterKey writer_key(const eprosima::fastrtps::rtps::GUID_t& guid);

// The partitions of every writer this participant discovered (remote ones through discovery, its
// own when created), so that a reader can check a sample against its writer's partitions.
class WriterPartitions : public fdds::DomainParticipantListener {
 public:
  void on_publisher_discovery(fdds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;
  void remember(const WriterKey& key, std::vector<std::string> partitions);
  void forget(const WriterKey& key);
  // Whether `writer` may write a sample addressed to `id` (none: any); what it may not is counted.
  bool admits(const eprosima::fastrtps::rtps::InstanceHandle_t& writer, std::optional<std::string_view> id,
              ReceiveCounters& counters) const;

 private:
  mutable std::mutex mutex_;
  std::map<WriterKey, std::vector<std::string>> partitions_;
};

// ---------------------------------------------------------------------------------------------
// The `only_id` content filter. A custom filter class (not the SQL one, which needs the type's
// TypeObject) that reads the first member, a CDR string, straight from the serialised payload.
// Every participant registers it. The readers evaluate it (writer-side filtering is off:
// writer_qos_for).

constexpr const char* kIdFilterClass = "PANOPTES_LEADING_ID";
constexpr const char* kIdFilterExpression = "leading_id = %0";

// The first string of a sample: 4 bytes of encapsulation (its second byte's low bit: little
// endian), a 4-byte length counting the terminating NUL, the characters.
std::optional<std::string_view> leading_string(const unsigned char* d, std::size_t length);

// The factory of the `only_id` filter class kIdFilterClass, registered with every participant.
fdds::IContentFilterFactory& leading_id_filter_factory();

}  // namespace panoptes::dds
