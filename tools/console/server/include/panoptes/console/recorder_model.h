// SPDX-License-Identifier: Apache-2.0
// The recorders on the bus (rt/panoptes/recorder_status) and the recordings the console saw from
// start to stop. Not thread-safe: ConsoleState guards it.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/console_records.h"

namespace panoptes::console {

class RecorderModel {
 public:
  explicit RecorderModel(const StateOptions& options) : options_(options) {}

  // A recording ends when its recorder stops or starts another file; it is listed with the
  // figures of the last status that described it (at most max_recordings, the newest).
  void on_status(const std::string& recorder, RecorderRecord status, TimeNs now);
  bool knows(const std::string& recorder) const;
  const std::vector<RecordingEntry>& recordings() const { return recordings_; }

  // The full snapshot's "recorders" (those heard from within recorder_timeout_ns) and "recordings".
  nlohmann::json to_json(TimeNs now) const;

 private:
  struct Recorder {
    RecorderRecord status;
    TimeNs status_ns = 0;
    TimeNs started_ns = 0;
  };

  StateOptions options_;
  std::map<std::string, Recorder> recorders_;
  std::vector<RecordingEntry> recordings_;
};

}  // namespace panoptes::console
