// SPDX-License-Identifier: Apache-2.0
#include "panoptes/recorder/recorder.h"

#include <algorithm>
#include <chrono>
#include <utility>

#include "panoptes/recorder/ros2_naming.h"

namespace panoptes::recorder {

namespace {

std::uint64_t wall_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

}  // namespace

Recorder::Recorder(dds::Bus& bus, RecorderOptions options) : bus_(bus), options_(std::move(options)) {
  if (options_.topics.empty()) {
    for (const auto& raw : dds::panoptes_raw_topics()) topics_.push_back({raw});
    return;
  }
  for (const auto& name : options_.topics) {
    const auto raw = dds::recordable_topic(name);
    if (!raw)
      throw dds::DdsInputError(
          "'" + name +
          "' is not a Panoptes topic (docs/protocol.md) nor one of its ROS 2 topics (docs/ros2.md)");
    if (std::none_of(topics_.begin(), topics_.end(), [&](const Topic& t) { return t.raw.topic == name; }))
      topics_.push_back({*raw});
  }
}

Recorder::~Recorder() {
  unsubscribe();
}

void Recorder::start(const std::filesystem::path& path) {
  if (writer_) stop();
  writer_ = std::make_unique<recording::McapWriter>(path, options_.mcap);
  schemas_.clear();
  for (auto& topic : topics_) topic = Topic{topic.raw};
  for (std::size_t i = 0; i < topics_.size(); ++i) {
    readers_.push_back(bus_.make_raw_reader(topics_[i].raw.topic, [this, i](dds::RawSample&& sample) {
      Pending p{i, wall_ns(), static_cast<std::uint64_t>(sample.source_timestamp_ns), std::move(sample.cdr)};
      const std::lock_guard<std::mutex> lock(mutex_);
      pending_.push_back(std::move(p));
      ++received_;
    }));
  }
}

void Recorder::unsubscribe() {
  readers_.clear();  // after this no callback runs
}

void Recorder::stop() {
  if (!writer_) return;
  unsubscribe();
  pump();
  auto writer = std::move(writer_);
  last_path_ = writer->path();
  last_stats_ = writer->stats();
  writer->close();
  last_stats_ = writer->stats();
}

void Recorder::pump() {
  if (!writer_) return;
  batch_.clear();
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    batch_.swap(pending_);
  }
  try {
    write_pending(batch_);
  } catch (const recording::RecordingError&) {
    unsubscribe();
    last_path_ = writer_->path();
    last_stats_ = writer_->stats();
    writer_.reset();
    throw;
  }
}

void Recorder::write_pending(std::vector<Pending>& batch) {
  for (auto& p : batch) {
    Topic& topic = topics_[p.topic];
    if (topic.channel == 0) {
      auto [it, added] = schemas_.try_emplace(topic.raw.ros_type, 0);
      if (added)
        it->second =
            writer_->add_schema(topic.raw.ros_type, kSchemaEncoding, ros2idl_schema(topic.raw.ros_type));
      topic.channel = writer_->add_channel(it->second, ros_topic_name(topic.raw.topic), kMessageEncoding,
                                           {{"dds_type", topic.raw.type_name}});
    }
    writer_->write(topic.channel, topic.sequence++, p.log_time, p.publish_time, p.cdr);
    ++topic.written;
  }
}

RecorderProgress Recorder::progress() const {
  RecorderProgress progress;
  progress.recording = writer_ != nullptr;
  progress.path = writer_ ? writer_->path() : last_path_;
  const recording::WriterStats& stats = writer_ ? writer_->stats() : last_stats_;
  progress.messages = stats.messages;
  progress.bytes = stats.file_bytes;
  for (const auto& topic : topics_) {
    if (topic.written == 0) continue;
    ++progress.topics;
    progress.per_topic[topic.raw.topic] = topic.written;
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  progress.received = received_;
  return progress;
}

}  // namespace panoptes::recorder
