// SPDX-License-Identifier: Apache-2.0
// An MCAP writer (https://mcap.dev/spec): messages go into compressed chunks, each followed by its
// message indexes; close() writes the data end, a summary (schemas, channels, statistics, chunk
// indexes) with its summary offsets, and the footer.
//
// Crash safety: the header, every schema and channel, and every chunk with its indexes reach the
// file (write(2), not a user-space buffer) as soon as they are complete, so a process killed with
// SIGKILL loses at most the open chunk, and McapReader recovers the rest without the summary.
// A write error (full disk, file size limit) throws RecordingError; the writer then cuts the file
// back to its last complete record and tries to close it with a summary, so it stays valid.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "panoptes/recording/mcap_types.h"

namespace panoptes::recording {

struct McapWriterOptions {
  std::string profile = "ros2";
  std::string library = "panoptes";
  Compression compression = Compression::kZstd;
  int compression_level = 1;            // zstd 1 (fast); lz4 0 (default)
  std::size_t chunk_size = 1 << 20;     // uncompressed bytes that close a chunk
  std::uint64_t chunk_duration_ns = 0;  // also close a chunk this long after its first message (0: never)
  bool fsync_chunks = false;            // fsync after every chunk (power-loss safety; slower)
};

struct WriterStats {
  std::uint64_t messages = 0;
  std::uint64_t message_bytes = 0;  // payload bytes
  std::uint64_t chunks = 0;
  std::uint64_t file_bytes = 0;  // written to the file so far
  std::map<std::uint16_t, std::uint64_t> per_channel;
};

class McapWriter {
 public:
  // Creates (truncates) `path` and writes the magic and header; throws RecordingError.
  McapWriter(const std::filesystem::path& path, const McapWriterOptions& options = {});
  // Closes the file if close() was not called (errors are swallowed here; call close() to see them).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // Returns the new schema's or channel's id (ids start at 1). Written to the file at once.
  std::uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  std::uint16_t add_channel(std::uint16_t schema_id, const std::string& topic,
                            const std::string& message_encoding,
                            const std::map<std::string, std::string>& metadata = {});

  // Appends a message to the open chunk (flushed when it reaches chunk_size). Throws RecordingError
  // on a write error or an unknown channel.
  void write(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time,
             std::uint64_t publish_time, std::span<const std::uint8_t> data);
  // Writes the open chunk now.
  void flush();
  // Flushes, writes data end, summary and footer, closes the file. Idempotent; throws RecordingError
  // on a write error (the file is then closed as valid as the writer could make it).
  void close();

  const WriterStats& stats() const { return stats_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  struct State;
  void commit(std::span<const std::uint8_t> bytes, const char* what);
  bool close_after_error();
  bool drop_last_chunk();  // forgets the newest complete chunk (false: none left)
  void append_data_end_and_summary(std::vector<std::uint8_t>& out) const;
  std::filesystem::path path_;
  McapWriterOptions options_;
  WriterStats stats_;
  std::unique_ptr<State> state_;
};

}  // namespace panoptes::recording
