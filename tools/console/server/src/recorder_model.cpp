// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/recorder_model.h"

#include <nlohmann/json.hpp>

#include "json_helpers.h"

namespace panoptes::console {

using detail::round_to;
using nlohmann::json;

void RecorderModel::on_status(const std::string& recorder, RecorderRecord status, TimeNs now) {
  Recorder& entry = recorders_[recorder];
  const RecorderRecord& before = entry.status;
  if (before.recording && (!status.recording || status.path != before.path)) {
    const bool same_file = status.path == before.path;
    recordings_.push_back({recorder, before.path, same_file ? status.messages : before.messages,
                           same_file ? status.bytes : before.bytes, entry.started_ns, now});
    if (recordings_.size() > options_.max_recordings) recordings_.erase(recordings_.begin());
  }
  if (status.recording && (!before.recording || status.path != before.path)) entry.started_ns = now;
  entry.status = std::move(status);
  entry.status_ns = now;
}

bool RecorderModel::knows(const std::string& recorder) const {
  return recorders_.count(recorder) > 0;
}

json RecorderModel::to_json(TimeNs now) const {
  json recorders = json::array();
  for (const auto& [id, recorder] : recorders_) {
    if (now - recorder.status_ns > options_.recorder_timeout_ns) continue;
    const RecorderRecord& s = recorder.status;
    recorders.push_back({{"id", id},
                         {"recording", s.recording},
                         {"path", s.path},
                         {"topics", s.topics},
                         {"messages", s.messages},
                         {"bytes", s.bytes},
                         {"messages_per_s", round_to(s.messages_per_s, 1)},
                         {"error", s.error},
                         {"rejections", s.rejections},
                         {"seconds", s.recording ? detail::seconds(now - recorder.started_ns, 1) : 0.0}});
  }
  json recordings = json::array();
  for (const RecordingEntry& r : recordings_) {
    recordings.push_back({{"recorder", r.recorder},
                          {"path", r.path},
                          {"messages", r.messages},
                          {"bytes", r.bytes},
                          {"started_ms", r.started_ns / 1'000'000},
                          {"seconds", detail::seconds(r.stopped_ns - r.started_ns, 1)}});
  }
  return {{"recorders", std::move(recorders)}, {"recordings", std::move(recordings)}};
}

}  // namespace panoptes::console
