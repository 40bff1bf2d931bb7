// SPDX-License-Identifier: Apache-2.0
// The byte level of MCAP (https://mcap.dev/spec): opcodes, magic, little-endian primitives, a
// bounds-checked cursor, chunk compression and the CRC. Private to panoptes_recording.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "panoptes/recording/mcap_types.h"

namespace panoptes::recording::format {

inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
inline constexpr std::size_t kRecordPrefix = 9;  // opcode (1) + content length (8)

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};
// Opcodes 0x10..0x7F are reserved and 0x00 is never valid: meeting one means the reader lost its place.
inline bool valid_opcode(std::uint8_t op) {
  return (op >= kHeader && op <= kDataEnd) || op >= 0x80;
}

// Appends little-endian fields to a byte buffer.
class Out {
 public:
  explicit Out(std::vector<std::uint8_t>& buffer) : b_(buffer) {}
  void u8(std::uint8_t v) { b_.push_back(v); }
  void u16(std::uint16_t v) { le(v, 2); }
  void u32(std::uint32_t v) { le(v, 4); }
  void u64(std::uint64_t v) { le(v, 8); }
  void bytes(const void* data, std::size_t n);
  void str(std::string_view s);  // uint32 length + bytes
  void map(const std::map<std::string, std::string>& m);
  // Starts a record; finish_record() writes its content length.
  std::size_t begin_record(std::uint8_t op);
  void finish_record(std::size_t start);
  std::size_t size() const { return b_.size(); }

 private:
  void le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  std::vector<std::uint8_t>& b_;
};

// Reads little-endian fields from a byte span; every read checks the bounds and sets `ok` false
// (returning zero/empty) instead of reading past the end.
class In {
 public:
  explicit In(std::span<const std::uint8_t> data) : d_(data) {}
  std::uint8_t u8() { return static_cast<std::uint8_t>(le(1)); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(le(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(le(4)); }
  std::uint64_t u64() { return le(8); }
  std::string str();
  std::span<const std::uint8_t> take(std::uint64_t n);
  std::map<std::string, std::string> string_map();
  std::map<std::uint16_t, std::uint64_t> u16_u64_map();
  std::span<const std::uint8_t> rest() { return take(remaining()); }
  std::size_t remaining() const { return d_.size() - pos_; }
  std::size_t pos() const { return pos_; }
  bool ok() const { return ok_; }

 private:
  std::uint64_t le(int n);
  std::span<const std::uint8_t> d_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t previous = 0);

// Compresses `data` into `out` (replacing its contents).
void compress(Compression compression, int level, std::span<const std::uint8_t> data,
              std::vector<std::uint8_t>& out);
// Decompresses a chunk's records; nullopt (with `why`) on an unknown compression, corrupt data or
// a size other than `uncompressed_size`.
std::optional<std::vector<std::uint8_t>> decompress(std::string_view compression,
                                                    std::span<const std::uint8_t> data,
                                                    std::uint64_t uncompressed_size, std::string& why);

}  // namespace panoptes::recording::format
