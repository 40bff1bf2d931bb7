// SPDX-License-Identifier: Apache-2.0
// Records every Panoptes topic into an MCAP file (ros2 profile) as the serialized CDR received,
// without decoding (docs/recording.md). DDS listener threads only queue samples; pump(), called by
// the owner's loop, writes them, so the file is touched by one thread.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "panoptes/dds/bus.h"
#include "panoptes/recording/mcap_writer.h"

namespace panoptes::recorder {

struct RecorderOptions {
  recording::McapWriterOptions mcap;
  std::vector<std::string> topics;  // DDS names; empty: every Panoptes topic
};

struct RecorderProgress {
  bool recording = false;
  std::filesystem::path path;
  std::uint32_t topics = 0;  // with at least one message
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;                         // in the file
  std::uint64_t received = 0;                      // from DDS (messages + queued)
  std::map<std::string, std::uint64_t> per_topic;  // DDS topic -> messages written
};

class Recorder {
 public:
  // Throws DdsInputError for a topic that is not a Panoptes topic.
  Recorder(dds::Bus& bus, RecorderOptions options);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Opens `path` and subscribes (transient-local topics deliver their last samples at once).
  // Throws recording::RecordingError if the file cannot be created.
  void start(const std::filesystem::path& path);
  // Unsubscribes, writes what is queued and closes the file with its summary. Throws
  // RecordingError on a write error (the file is left as valid as the writer could make it).
  void stop();
  // Writes the queued samples. After a write error: recording stops, the readers are removed and
  // the error is rethrown as RecordingError (the writer already closed the file).
  void pump();

  bool recording() const { return writer_ != nullptr; }
  RecorderProgress progress() const;

 private:
  struct Pending {
    std::size_t topic = 0;  // index in topics_
    std::uint64_t log_time = 0;
    std::uint64_t publish_time = 0;
    std::vector<std::uint8_t> cdr;
  };
  struct Topic {
    dds::RawTopic raw;
    std::uint16_t channel = 0;  // 0: not in the file yet
    std::uint32_t sequence = 0;
    std::uint64_t written = 0;
  };
  void write_pending(std::vector<Pending>& batch);
  void unsubscribe();

  dds::Bus& bus_;
  RecorderOptions options_;
  std::vector<Topic> topics_;
  std::map<std::string, std::uint16_t> schemas_;  // ros type -> schema id
  std::vector<std::unique_ptr<dds::RawReader>> readers_;
  std::unique_ptr<recording::McapWriter> writer_;
  mutable std::mutex mutex_;
  std::vector<Pending> pending_;  // guarded by mutex_
  std::uint64_t received_ = 0;    // guarded by mutex_
  std::vector<Pending> batch_;
  std::filesystem::path last_path_;  // of the last file closed
  recording::WriterStats last_stats_;
};

}  // namespace panoptes::recorder
