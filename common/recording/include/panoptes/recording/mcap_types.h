// SPDX-License-Identifier: Apache-2.0
// The MCAP records a recording is made of (https://mcap.dev/spec), as plain C++ values, and the
// error every reader and writer failure throws.
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace panoptes::recording {

// A file that cannot be opened, read or written, or that is not an MCAP file; the message names the
// file (and the byte offset where it applies).
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Compression { kNone, kZstd, kLz4 };
// "", "zstd", "lz4" as the specification spells them.
const char* compression_name(Compression compression);

struct Schema {
  std::uint16_t id = 0;
  std::string name;      // ros2: "panoptes/msg/FeatureFrame"
  std::string encoding;  // ros2: "ros2idl" or "ros2msg"
  std::string data;      // the schema text
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;             // ros2: "/panoptes/features"
  std::string message_encoding;  // ros2: "cdr"
  std::map<std::string, std::string> metadata;
};

struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t attachment_count = 0;
  std::uint32_t metadata_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

}  // namespace panoptes::recording
