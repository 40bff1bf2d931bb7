// SPDX-License-Identifier: Apache-2.0
// File outputs of a session: Track JSONL (--out-tracks) and Pose JSONL (--out-poses), each
// optional (architecture.md, Contracts). Counts what was written for the closing log line.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/jsonl.h"

namespace panoptes::session {

class JsonlOutputs {
 public:
  // An empty path: that output is not written. Throws if a file cannot be opened.
  JsonlOutputs(const std::string& tracks_path, const std::string& poses_path);

  bool writes_tracks() const { return tracks_.has_value(); }
  bool writes_poses() const { return poses_.has_value(); }

  void write_tracks(const std::vector<TrackRecord>& tracks);
  void write_poses(const std::vector<PoseRecord>& poses);

  // Writes out what is buffered (the end of a run).
  void flush();

  // "wrote N track records[, M pose records]"
  std::string summary() const;

 private:
  std::optional<JsonlWriter> tracks_;
  std::optional<JsonlWriter> poses_;
  std::size_t track_records_ = 0;
  std::size_t pose_records_ = 0;
};

}  // namespace panoptes::session
