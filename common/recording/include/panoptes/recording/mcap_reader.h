// SPDX-License-Identifier: Apache-2.0
// An MCAP reader (https://mcap.dev/spec) that reads the data section in file order and so needs
// no summary: it recovers a file whose writer was killed (no summary, no footer, a cut chunk).
// Every chunk's CRC is checked; a truncated, corrupted or undecodable record is counted and
// skipped with the file and byte offset in ReadReport::problems, and the reader resynchronises on
// the next intact chunk. An empty or non-MCAP file throws RecordingError.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "panoptes/recording/mcap_types.h"

namespace panoptes::recording {

struct MessageView {
  const Channel* channel = nullptr;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;
  std::uint64_t publish_time = 0;
  std::span<const std::uint8_t> data;  // valid during the callback only
};

struct ReadReport {
  std::uint64_t messages = 0;            // delivered
  std::uint64_t chunks = 0;              // read intact
  std::uint64_t chunks_skipped = 0;      // truncated, corrupted (CRC) or undecodable
  std::uint64_t records_skipped = 0;     // other malformed records, messages of unknown channels
  bool data_end = false;                 // the data section ended with its Data End record
  bool summary = false;                  // a footer and summary were found and their CRC matched
  std::optional<Statistics> statistics;  // from the summary
  std::vector<std::string> problems;     // "<file>: byte <offset>: <what>" (the first 100)
  std::uint64_t problem_count = 0;
};

class McapReader {
 public:
  // Opens and maps the file and checks the magic and header; throws RecordingError naming the file.
  explicit McapReader(const std::filesystem::path& path);
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  using MessageCallback = std::function<void(const MessageView&)>;
  // Reads the whole data section in file order, delivering every recoverable message.
  ReadReport read(const MessageCallback& on_message);

  const std::string& profile() const { return profile_; }
  const std::string& library() const { return library_; }
  // Filled by read() as the records are met.
  const std::map<std::uint16_t, Schema>& schemas() const { return schemas_; }
  const std::map<std::uint16_t, Channel>& channels() const { return channels_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  class Scan;
  std::filesystem::path path_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  std::string profile_;
  std::string library_;
  std::map<std::uint16_t, Schema> schemas_;
  std::map<std::uint16_t, Channel> channels_;
};

}  // namespace panoptes::recording
