// SPDX-License-Identifier: Apache-2.0
#include "panoptes/recording/mcap_reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "mcap_format.h"

namespace panoptes::recording {

namespace fmt = format;

namespace {

constexpr std::size_t kMaxProblems = 100;
constexpr std::size_t kFooterRecord = fmt::kRecordPrefix + 20;

std::string hex(std::uint8_t v) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02x", v);
  return text;
}

bool is_magic(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= fmt::kMagic.size() &&
         std::equal(fmt::kMagic.begin(), fmt::kMagic.end(), bytes.begin());
}

}  // namespace

McapReader::McapReader(const std::filesystem::path& path) : path_(path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw RecordingError(path.string() + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw RecordingError(path.string() + ": not a regular file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ == 0) {
    ::close(fd);
    throw RecordingError(path.string() + ": empty file (not an MCAP recording)");
  }
  void* mapped = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (mapped == MAP_FAILED) throw RecordingError(path.string() + ": cannot map: " + std::strerror(errno));
  data_ = static_cast<const std::uint8_t*>(mapped);
  const std::span<const std::uint8_t> all(data_, size_);
  if (!is_magic(all)) {
    ::munmap(mapped, size_);
    data_ = nullptr;
    throw RecordingError(path.string() + ": byte 0: not an MCAP file (no MCAP magic)");
  }
  fmt::In in(all.subspan(fmt::kMagic.size()));
  const std::uint8_t op = in.u8();
  fmt::In header(in.take(in.u64()));
  profile_ = header.str();
  library_ = header.str();
  if (!in.ok() || op != fmt::kHeader || !header.ok()) {
    ::munmap(mapped, size_);
    data_ = nullptr;
    throw RecordingError(path.string() +
                         ": byte 8: no valid MCAP header record (truncated or not an MCAP file)");
  }
}

McapReader::~McapReader() {
  if (data_ != nullptr) ::munmap(const_cast<std::uint8_t*>(data_), size_);
}

// One pass over the data section.
class McapReader::Scan {
 public:
  Scan(McapReader& reader, const MessageCallback& on_message) : r_(reader), on_message_(on_message) {}

  ReadReport run() {
    std::size_t pos = fmt::kMagic.size();
    pos = skip_record(pos);  // the header, checked by the constructor
    while (pos < r_.size_) {
      if (r_.size_ - pos < fmt::kRecordPrefix) {
        problem(pos,
                "truncated record (" + std::to_string(r_.size_ - pos) + " bytes left): the file was cut");
        break;
      }
      const std::uint8_t op = r_.data_[pos];
      const std::uint64_t length = le64(pos + 1);
      const bool fits = length <= r_.size_ - pos - fmt::kRecordPrefix;
      if (!fmt::valid_opcode(op) || !fits) {
        if (op == fmt::kChunk) ++report_.chunks_skipped;
        problem(pos, !fits ? "record " + hex(op) + " of " + std::to_string(length) +
                                 " bytes runs past the end of the file: truncated or corrupted"
                           : "invalid opcode " + hex(op) + ": corrupted");
        const auto next = resync(pos + 1);
        if (!next) break;
        problem(*next, "resuming at the next intact chunk");
        pos = *next;
        continue;
      }
      const std::span<const std::uint8_t> body(r_.data_ + pos + fmt::kRecordPrefix,
                                               static_cast<std::size_t>(length));
      if (op == fmt::kDataEnd) {
        report_.data_end = true;
        break;
      }
      if (op == fmt::kFooter) break;
      record(op, body, pos);
      pos += fmt::kRecordPrefix + static_cast<std::size_t>(length);
    }
    if (pos >= r_.size_ && !report_.data_end)
      problem(r_.size_, "no data end record: the file was cut (recovered)");
    if (report_.data_end) read_summary();
    return std::move(report_);
  }

 private:
  std::uint64_t le64(std::size_t at) const {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(r_.data_[at + i]) << (8 * i);
    return v;
  }
  std::size_t skip_record(std::size_t pos) const { return pos + fmt::kRecordPrefix + le64(pos + 1); }

  void problem(std::uint64_t offset, const std::string& what) {
    ++report_.problem_count;
    if (report_.problems.size() < kMaxProblems)
      report_.problems.push_back(r_.path_.string() + ": byte " + std::to_string(offset) + ": " + what);
  }

  // Schema, channel, message or chunk at `offset` (of the file; inside a chunk, of the chunk record).
  void record(std::uint8_t op, std::span<const std::uint8_t> body, std::uint64_t offset) {
    switch (op) {
      case fmt::kSchema:
        return schema(body, offset);
      case fmt::kChannel:
        return channel(body, offset);
      case fmt::kMessage:
        return message(body, offset);
      case fmt::kChunk:
        return chunk(body, offset);
      default:
        return;  // indexes, attachments, metadata, unknown records: not needed to read messages
    }
  }

  void schema(std::span<const std::uint8_t> body, std::uint64_t offset) {
    fmt::In in(body);
    Schema s;
    s.id = in.u16();
    s.name = in.str();
    s.encoding = in.str();
    s.data = in.str();
    if (!in.ok()) {
      ++report_.records_skipped;
      return problem(offset, "malformed schema record: skipped");
    }
    if (s.id != 0) r_.schemas_[s.id] = std::move(s);
  }

  void channel(std::span<const std::uint8_t> body, std::uint64_t offset) {
    fmt::In in(body);
    Channel c;
    c.id = in.u16();
    c.schema_id = in.u16();
    c.topic = in.str();
    c.message_encoding = in.str();
    c.metadata = in.string_map();
    if (!in.ok()) {
      ++report_.records_skipped;
      return problem(offset, "malformed channel record: skipped");
    }
    r_.channels_[c.id] = std::move(c);
  }

  void message(std::span<const std::uint8_t> body, std::uint64_t offset) {
    fmt::In in(body);
    MessageView m;
    const std::uint16_t channel_id = in.u16();
    m.sequence = in.u32();
    m.log_time = in.u64();
    m.publish_time = in.u64();
    m.data = in.rest();
    const auto it = r_.channels_.find(channel_id);
    if (!in.ok() || it == r_.channels_.end()) {
      ++report_.records_skipped;
      return problem(offset, !in.ok()
                                 ? "malformed message record: skipped"
                                 : "message of unknown channel " + std::to_string(channel_id) + ": skipped");
    }
    m.channel = &it->second;
    ++report_.messages;
    if (on_message_) on_message_(m);
  }

  struct ChunkFields {
    std::uint64_t uncompressed_size = 0;
    std::uint32_t crc = 0;
    std::string compression;
    std::span<const std::uint8_t> records;
  };
  static std::optional<ChunkFields> parse_chunk(std::span<const std::uint8_t> body) {
    fmt::In in(body);
    ChunkFields f;
    in.u64();
    in.u64();
    f.uncompressed_size = in.u64();
    f.crc = in.u32();
    f.compression = in.str();
    f.records = in.take(in.u64());
    if (!in.ok() || in.remaining() != 0) return std::nullopt;
    return f;
  }

  void chunk(std::span<const std::uint8_t> body, std::uint64_t offset) {
    const auto fields = parse_chunk(body);
    if (!fields) {
      ++report_.chunks_skipped;
      return problem(offset, "malformed chunk record: skipped");
    }
    std::string why;
    const auto records =
        fmt::decompress(fields->compression, fields->records, fields->uncompressed_size, why);
    if (!records) {
      ++report_.chunks_skipped;
      return problem(offset, "chunk cannot be decompressed (" + why + "): skipped");
    }
    if (fields->crc != 0 && fmt::crc32(*records) != fields->crc) {
      ++report_.chunks_skipped;
      return problem(offset, "chunk CRC mismatch (corrupted): skipped");
    }
    ++report_.chunks;
    fmt::In in(*records);
    while (in.ok() && in.remaining() > 0) {
      const std::size_t at = in.pos();
      const std::uint8_t op = in.u8();
      const auto inner = in.take(in.u64());
      if (!in.ok()) {
        ++report_.records_skipped;
        return problem(offset,
                       "record at byte " + std::to_string(at) + " of the chunk is truncated: skipped");
      }
      if (op != fmt::kChunk) record(op, inner, offset);
    }
  }

  // The next offset after `from` where an intact-looking chunk record starts.
  std::optional<std::size_t> resync(std::size_t from) const {
    for (std::size_t p = from; p + fmt::kRecordPrefix <= r_.size_; ++p) {
      if (r_.data_[p] != fmt::kChunk) continue;
      const std::uint64_t length = le64(p + 1);
      if (length > r_.size_ - p - fmt::kRecordPrefix) continue;
      const auto fields = parse_chunk({r_.data_ + p + fmt::kRecordPrefix, static_cast<std::size_t>(length)});
      if (fields &&
          (fields->compression.empty() || fields->compression == "zstd" || fields->compression == "lz4"))
        return p;
    }
    return std::nullopt;
  }

  // The footer, the summary's CRC and its statistics; problems only, never fatal.
  void read_summary() {
    if (r_.size_ < fmt::kMagic.size() * 2 + kFooterRecord ||
        !is_magic({r_.data_ + r_.size_ - fmt::kMagic.size(), fmt::kMagic.size()})) {
      return problem(r_.size_, "no footer and trailing magic after the data end: summary not read");
    }
    const std::size_t footer = r_.size_ - fmt::kMagic.size() - kFooterRecord;
    fmt::In in({r_.data_ + footer, kFooterRecord});
    const std::uint8_t op = in.u8();
    const std::uint64_t length = in.u64();
    const std::uint64_t summary_start = in.u64();
    in.u64();
    const std::uint32_t crc = in.u32();
    if (op != fmt::kFooter || length != 20 || summary_start > footer)
      return problem(footer, "malformed footer: summary not read");
    if (summary_start == 0) return;
    const std::span<const std::uint8_t> covered(r_.data_ + summary_start,
                                                footer + fmt::kRecordPrefix + 16 - summary_start);
    if (crc != 0 && fmt::crc32(covered) != crc)
      return problem(summary_start, "summary CRC mismatch: summary not read");
    report_.summary = true;
    fmt::In records({r_.data_ + summary_start, footer - summary_start});
    while (records.ok() && records.remaining() > 0) {
      const std::uint8_t record_op = records.u8();
      fmt::In body(records.take(records.u64()));
      if (record_op == fmt::kStatistics) report_.statistics = statistics(body);
    }
  }

  static Statistics statistics(fmt::In& in) {
    Statistics s;
    s.message_count = in.u64();
    s.schema_count = in.u16();
    s.channel_count = in.u32();
    s.attachment_count = in.u32();
    s.metadata_count = in.u32();
    s.chunk_count = in.u32();
    s.message_start_time = in.u64();
    s.message_end_time = in.u64();
    s.channel_message_counts = in.u16_u64_map();
    return s;
  }

  McapReader& r_;
  const MessageCallback& on_message_;
  ReadReport report_;
};

ReadReport McapReader::read(const MessageCallback& on_message) {
  Scan scan(*this, on_message);
  return scan.run();
}

}  // namespace panoptes::recording
