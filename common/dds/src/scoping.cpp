// SPDX-License-Identifier: Apache-2.0
// Scoping: camera-scoped partitions and the `only_id` content filter.
#include "scoping.h"

#include <cstring>

#include <fastdds/dds/topic/IContentFilter.hpp>

#include "panoptes/dds/bus.h"

namespace panoptes::dds {

std::string scoped_partitions(const std::string& scope, bool reader) {
  if (scope.find(';') != std::string::npos)
    throw DdsInputError("camera or client id '" + scope + "': ';' cannot name a DDS partition");
  if (!scope.empty()) return scope;
  return reader ? std::string(";") + kEveryCamera : std::string(kEveryCamera);
}

bool scope_allows(const std::vector<std::string>& partitions, std::string_view id) {
  if (partitions.empty()) return true;
  for (const std::string& partition : partitions) {
    if (partition.empty() || partition.find_first_of("*?[") != std::string::npos || partition == id)
      return true;
  }
  return false;
}

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
void WriterPartitions::on_publisher_discovery(fdds::DomainParticipant*,
                                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) {
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

void WriterPartitions::remember(const WriterKey& key, std::vector<std::string> partitions) {
  std::lock_guard<std::mutex> lock(mutex_);
  partitions_[key] = std::move(partitions);
}

void WriterPartitions::forget(const WriterKey& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  partitions_.erase(key);
}

bool WriterPartitions::admits(const eprosima::fastrtps::rtps::InstanceHandle_t& writer,
                              std::optional<std::string_view> id, ReceiveCounters& counters) const {
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

std::string SampleSource::writer() const {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string text;
  text.reserve(33);
  for (std::size_t i = 0; i < writer_guid.size(); ++i) {
    if (i == 12) text += '.';
    text += kHex[writer_guid[i] >> 4];
    text += kHex[writer_guid[i] & 0xf];
  }
  return text;
}

bool names_one_partition(std::string_view id) {
  constexpr std::size_t kMaxPartitionName = 256;
  return !id.empty() && id.size() <= kMaxPartitionName && id.find_first_of(";*?[") == std::string_view::npos;
}

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

namespace {

class LeadingIdFilter final : public fdds::IContentFilter {
 public:
  explicit LeadingIdFilter(std::string id) : id_(std::move(id)) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&, const GUID_t&) const override {
    const auto id = leading_string(payload.data, payload.length);
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

}  // namespace

fdds::IContentFilterFactory& leading_id_filter_factory() {
  static LeadingIdFilterFactory factory;  // outlives every participant
  return factory;
}

}  // namespace panoptes::dds
