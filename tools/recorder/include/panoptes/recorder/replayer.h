// SPDX-License-Identifier: Apache-2.0
// Publishes a recording back onto the bus (panoptes_replay, docs/recording.md): every message of a
// Panoptes topic, as recorded (serialized CDR, no decoding), at the recorded pace scaled by `rate`,
// and says whether it kept up.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "panoptes/dds/bus.h"

namespace panoptes::recorder {

struct ReplayOptions {
  double rate = 1.0;  // 2: twice as fast; 0: as fast as possible
  bool loop = false;
  double start_s = 0;  // from the first message
  double end_s = -1;   // from the first message; < 0: to the end
  std::vector<std::string>
      topics;  // DDS ("rt/panoptes/features") or ROS ("/panoptes/features") names; empty: all
  // Shift every time of every message by one offset so that the replay happens now
  // (dds::shift_sample_times): a live estimator rejects frames whose stamps are far from its clock,
  // and clients measure latency against their clock. Each pass (--loop) is shifted anew.
  bool restamp = true;
  double late_ms = 20;  // a message published later than this behind its schedule counts as late
  bool quiet = false;
};

struct ReplayReport {
  std::uint64_t published = 0;
  std::uint64_t late = 0;
  double max_lag_ms = 0;
  double recorded_s = 0;  // span of the replayed messages (one pass)
  double wall_s = 0;
  int passes = 0;
  std::int64_t first_shift_ns = 0;  // time shift of the first pass (restamp)
  std::map<std::string, std::uint64_t> per_topic;
  bool kept_up() const { return late == 0; }
};

// One message of the recording, ready to publish.
struct ReplayMessage {
  std::size_t topic = 0;  // index in Replayer::topics()
  std::uint64_t log_time = 0;
  std::vector<std::uint8_t> cdr;
};

class Replayer {
 public:
  // Reads the recording (recording::RecordingError if it cannot; damaged chunks are skipped and
  // listed in problems()). Throws std::invalid_argument for a --topics name it does not hold.
  Replayer(const std::filesystem::path& path, ReplayOptions options);

  // Publishes until done (or `stop` returns true); writers are created on `bus` first and wait
  // until each has matched a reader, at most `discovery_s`.
  ReplayReport run(dds::Bus& bus, double discovery_s, const std::function<bool()>& stop);

  const std::vector<std::string>& topics() const { return topics_; }
  const std::vector<ReplayMessage>& messages() const { return messages_; }
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  ReplayOptions options_;
  std::vector<std::string> topics_;      // DDS names
  std::vector<ReplayMessage> messages_;  // by log time, within [start, end]
  std::vector<std::string> problems_;
};

}  // namespace panoptes::recorder
