// SPDX-License-Identifier: Apache-2.0
// Raw (serialized) endpoints: what panoptes_record records, panoptes_replay publishes and
// panoptes_rogue forges.
#include <cstring>

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>

#include "endpoints.h"
#include "participant.h"

namespace panoptes::dds {
namespace {

// Keeps the serialized payload as it is. It bears the real type's name, size bound and key flag,
// so it matches the typed writers and readers; the key of a sample to write is computed by the
// real type from the decoded sample.
class RawPubSubType final : public fdds::TopicDataType {
 public:
  // transport_cap: the topic's (TopicSpec::transport_cap; declared_type_size).
  RawPubSubType(std::unique_ptr<fdds::TopicDataType> real, std::size_t transport_cap)
      : real_(std::move(real)) {
    setName(real_->getName());
    m_typeSize = declared_type_size(transport_cap, real_->m_typeSize);
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
    return fdds::TypeSupport(
        new RawPubSubType(std::unique_ptr<fdds::TopicDataType>(entry.make_real()), entry.spec.transport_cap));
  });
}

}  // namespace

std::unique_ptr<RawReader> Bus::make_raw_reader(const std::string& topic, RawReader::Callback on_sample) {
  const RawTopicEntry entry = raw_entry_named(topic);
  auto impl = std::make_unique<RawReader::Impl>();
  impl->core = core_;
  impl->listener =
      std::make_unique<RawReaderListener>(std::move(on_sample), core_->receive_counters(),
                                          entry.spec.camera_scoped ? &core_->writer_partitions() : nullptr);
  const bool offered = entry.spec.reliable || entry.spec.offer_reliable;
  fdds::DataReaderQos reader_qos = reader_qos_for(entry.spec, offered ? Qos::kReliable : Qos::kDefault);
  if (entry.spec.camera_scoped)
    reader_qos.properties().properties().emplace_back(kPartitionsProperty, scoped_partitions({}, true));
  impl->reader =
      core_->subscriber()->create_datareader(raw_topic(*core_, entry), reader_qos, impl->listener.get());
  if (impl->reader == nullptr) throw DdsError("cannot create DDS reader on " + topic + core_->refusal_hint());
  return std::make_unique<RawReader>(std::move(impl));
}

std::unique_ptr<RawWriter> Bus::make_raw_writer(const std::string& topic) {
  const RawTopicEntry entry = raw_entry_named(topic);
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
