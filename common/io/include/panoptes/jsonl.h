// SPDX-License-Identifier: Apache-2.0
// JSON Lines files of FeatureFrame, Track and Pose records (docs/contracts.md).
#pragma once

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "panoptes/records.h"

namespace panoptes {

// One JSON object per line. Parsing errors come back as a message, never an exception.
std::string to_json_line(const FeatureFrame& frame);
std::string to_json_line(const TrackRecord& track);
std::string to_json_line(const PoseRecord& pose);

struct ParseError {
  std::string message;
};
template <class T>
struct Parsed {
  std::optional<T> value;
  std::string error;  // empty when value is set
};
Parsed<FeatureFrame> parse_feature_frame(std::string_view line);
Parsed<TrackRecord> parse_track(std::string_view line);
Parsed<PoseRecord> parse_pose(std::string_view line);

// Reads a whole JSONL file. Malformed lines are skipped and counted; `errors` (if given) receives
// "<file>:<line>: <reason>" for each. Throws std::runtime_error if the file cannot be opened.
std::vector<FeatureFrame> read_feature_frames(const std::filesystem::path& path,
                                              std::vector<std::string>* errors = nullptr);
std::vector<TrackRecord> read_tracks(const std::filesystem::path& path,
                                     std::vector<std::string>* errors = nullptr);
std::vector<PoseRecord> read_poses(const std::filesystem::path& path,
                                   std::vector<std::string>* errors = nullptr);

// Appends lines to a file; throws std::runtime_error naming the file if it cannot be opened.
class JsonlWriter {
 public:
  explicit JsonlWriter(const std::filesystem::path& path);
  void write_line(const std::string& line);
  template <class Record>
  void write(const Record& record) {
    write_line(to_json_line(record));
  }
  void flush();

 private:
  std::filesystem::path path_;
  std::ofstream out_;
};

}  // namespace panoptes
