// SPDX-License-Identifier: Apache-2.0
#include "mcap_format.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <cstring>
#include <limits>

namespace panoptes::recording {

const char* compression_name(Compression compression) {
  switch (compression) {
    case Compression::kZstd:
      return "zstd";
    case Compression::kLz4:
      return "lz4";
    case Compression::kNone:
      break;
  }
  return "";
}

namespace format {

void Out::bytes(const void* data, std::size_t n) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  b_.insert(b_.end(), p, p + n);
}

void Out::str(std::string_view s) {
  u32(static_cast<std::uint32_t>(s.size()));
  bytes(s.data(), s.size());
}

void Out::map(const std::map<std::string, std::string>& m) {
  const std::size_t start = b_.size();
  u32(0);
  for (const auto& [key, value] : m) {
    str(key);
    str(value);
  }
  const auto length = static_cast<std::uint32_t>(b_.size() - start - 4);
  for (int i = 0; i < 4; ++i) b_[start + i] = static_cast<std::uint8_t>(length >> (8 * i));
}

std::size_t Out::begin_record(std::uint8_t op) {
  const std::size_t start = b_.size();
  u8(op);
  u64(0);
  return start;
}

void Out::finish_record(std::size_t start) {
  const std::uint64_t length = b_.size() - start - kRecordPrefix;
  for (int i = 0; i < 8; ++i) b_[start + 1 + i] = static_cast<std::uint8_t>(length >> (8 * i));
}

std::uint64_t In::le(int n) {
  if (!ok_ || remaining() < static_cast<std::size_t>(n)) {
    ok_ = false;
    return 0;
  }
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(d_[pos_ + i]) << (8 * i);
  pos_ += static_cast<std::size_t>(n);
  return v;
}

std::span<const std::uint8_t> In::take(std::uint64_t n) {
  if (!ok_ || n > remaining()) {
    ok_ = false;
    return {};
  }
  auto out = d_.subspan(pos_, static_cast<std::size_t>(n));
  pos_ += static_cast<std::size_t>(n);
  return out;
}

std::string In::str() {
  const auto s = take(u32());
  return {reinterpret_cast<const char*>(s.data()), s.size()};
}

std::map<std::string, std::string> In::string_map() {
  In entries(take(u32()));
  std::map<std::string, std::string> m;
  while (ok_ && entries.ok() && entries.remaining() > 0) {
    std::string key = entries.str();
    std::string value = entries.str();
    if (entries.ok()) m[std::move(key)] = std::move(value);
  }
  if (!entries.ok()) ok_ = false;
  return m;
}

std::map<std::uint16_t, std::uint64_t> In::u16_u64_map() {
  In entries(take(u32()));
  std::map<std::uint16_t, std::uint64_t> m;
  while (ok_ && entries.ok() && entries.remaining() > 0) {
    const std::uint16_t key = entries.u16();
    const std::uint64_t value = entries.u64();
    if (entries.ok()) m[key] = value;
  }
  if (!entries.ok()) ok_ = false;
  return m;
}

std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t previous) {
  uLong crc = previous;
  std::size_t done = 0;
  while (done < data.size()) {
    const std::size_t n = std::min<std::size_t>(data.size() - done, std::numeric_limits<uInt>::max());
    crc = ::crc32(crc, data.data() + done, static_cast<uInt>(n));
    done += n;
  }
  return static_cast<std::uint32_t>(crc);
}

void compress(Compression compression, int level, std::span<const std::uint8_t> data,
              std::vector<std::uint8_t>& out) {
  switch (compression) {
    case Compression::kZstd: {
      out.resize(ZSTD_compressBound(data.size()));
      const std::size_t n = ZSTD_compress(out.data(), out.size(), data.data(), data.size(), level);
      if (ZSTD_isError(n))
        throw RecordingError(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
      out.resize(n);
      return;
    }
    case Compression::kLz4: {
      LZ4F_preferences_t preferences{};
      preferences.compressionLevel = level;
      preferences.frameInfo.contentSize = data.size();
      out.resize(LZ4F_compressFrameBound(data.size(), &preferences));
      const std::size_t n =
          LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), &preferences);
      if (LZ4F_isError(n))
        throw RecordingError(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
      out.resize(n);
      return;
    }
    case Compression::kNone:
      out.assign(data.begin(), data.end());
      return;
  }
}

namespace {

std::optional<std::vector<std::uint8_t>> lz4_decompress(std::span<const std::uint8_t> data,
                                                        std::vector<std::uint8_t> out, std::string& why) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    why = "lz4: cannot create a decompression context";
    return std::nullopt;
  }
  std::size_t in_done = 0;
  std::size_t out_done = 0;
  std::size_t hint = 1;
  while (hint != 0 && in_done < data.size()) {
    std::size_t out_n = out.size() - out_done;
    std::size_t in_n = data.size() - in_done;
    hint = LZ4F_decompress(context, out.data() + out_done, &out_n, data.data() + in_done, &in_n, nullptr);
    if (LZ4F_isError(hint)) {
      why = std::string("lz4: ") + LZ4F_getErrorName(hint);
      break;
    }
    in_done += in_n;
    out_done += out_n;
    if (in_n == 0 && out_n == 0) {
      why = "lz4: decompressed data longer than the chunk's uncompressed size";
      break;
    }
  }
  LZ4F_freeDecompressionContext(context);
  if (!why.empty()) return std::nullopt;
  if (hint != 0 || out_done != out.size()) {
    why = "lz4: decompressed " + std::to_string(out_done) + " bytes, the chunk says " +
          std::to_string(out.size());
    return std::nullopt;
  }
  return out;
}

}  // namespace

std::optional<std::vector<std::uint8_t>> decompress(std::string_view compression,
                                                    std::span<const std::uint8_t> data,
                                                    std::uint64_t uncompressed_size, std::string& why) {
  // A corrupted size field must not make the reader allocate without bound.
  constexpr std::uint64_t kMaxChunk = 1ULL << 31;
  if (uncompressed_size > kMaxChunk) {
    why = "uncompressed size " + std::to_string(uncompressed_size) + " is implausible";
    return std::nullopt;
  }
  std::vector<std::uint8_t> out(static_cast<std::size_t>(uncompressed_size));
  if (compression.empty()) {
    if (data.size() != uncompressed_size) {
      why = "uncompressed chunk of " + std::to_string(data.size()) + " bytes, the chunk says " +
            std::to_string(uncompressed_size);
      return std::nullopt;
    }
    std::memcpy(out.data(), data.data(), data.size());
    return out;
  }
  if (compression == "zstd") {
    const std::size_t n = ZSTD_decompress(out.data(), out.size(), data.data(), data.size());
    if (ZSTD_isError(n)) {
      why = std::string("zstd: ") + ZSTD_getErrorName(n);
      return std::nullopt;
    }
    if (n != out.size()) {
      why =
          "zstd: decompressed " + std::to_string(n) + " bytes, the chunk says " + std::to_string(out.size());
      return std::nullopt;
    }
    return out;
  }
  if (compression == "lz4") return lz4_decompress(data, std::move(out), why);
  why = "unknown compression '" + std::string(compression) + "'";
  return std::nullopt;
}

}  // namespace format
}  // namespace panoptes::recording
