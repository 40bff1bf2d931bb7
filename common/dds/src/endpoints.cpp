// SPDX-License-Identifier: Apache-2.0
// Typed endpoints: Writer<T>, Reader<T> and the Bus calls that make them, for every topic type.
#include <chrono>
#include <thread>

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>

#include "endpoints.h"
#include "participant.h"

namespace panoptes::dds {

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

template <class T>
class ReaderListener : public GatedReaderListener<typename Reader<T>::SourcedCallback> {
 public:
  using GatedReaderListener<typename Reader<T>::SourcedCallback>::GatedReaderListener;

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
        this->callback_(std::move(sample), SampleSource{writer_key(info.publication_handle)});
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
  return make_sourced_reader<T>(
      [callback = std::move(on_sample)](T&& sample, const SampleSource&) { callback(std::move(sample)); },
      qos, only_id, topic_name);
}

template <class T>
std::unique_ptr<Reader<T>> Bus::make_sourced_reader(typename Reader<T>::SourcedCallback on_sample, Qos qos,
                                                    const std::string& only_id,
                                                    const std::string& topic_name) {
  const TopicSpec spec = TopicTraits<T>::spec();
  const std::string name = topic_name_for<T>(topic_name);
  auto impl = std::make_unique<typename Reader<T>::Impl>();
  impl->core = core_;
  impl->listener =
      std::make_unique<ReaderListener<T>>(std::move(on_sample), core_->receive_counters(),
                                          spec.camera_scoped ? &core_->writer_partitions() : nullptr);
  fdds::TopicDescription* topic = core_->topic<T>(name);
  fdds::DataReaderQos reader_qos = reader_qos_for(spec, qos);
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
#define PANOPTES_INSTANTIATE_TYPE(Type)                                                                  \
  template class Writer<Type>;                                                                           \
  template class Reader<Type>;                                                                           \
  template std::unique_ptr<Writer<Type>> Bus::make_writer<Type>(Qos, const std::string&,                 \
                                                                const std::string&);                     \
  template std::unique_ptr<Reader<Type>> Bus::make_reader<Type>(Reader<Type>::Callback, Qos,             \
                                                                const std::string&, const std::string&); \
  template std::unique_ptr<Reader<Type>> Bus::make_sourced_reader<Type>(                                 \
      Reader<Type>::SourcedCallback, Qos, const std::string&, const std::string&);
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
PANOPTES_INSTANTIATE(MarkerLabels)
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

}  // namespace panoptes::dds
