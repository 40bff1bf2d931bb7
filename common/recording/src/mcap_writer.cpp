// SPDX-License-Identifier: Apache-2.0
#include "panoptes/recording/mcap_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>
#include <vector>

#include "mcap_format.h"

namespace panoptes::recording {

namespace fmt = format;

namespace {

struct ChunkIndexEntry {
  std::uint64_t start_time = 0;
  std::uint64_t end_time = 0;
  std::uint64_t chunk_offset = 0;
  std::uint64_t chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::uint64_t compressed_size = 0;
  std::uint64_t uncompressed_size = 0;
  std::string compression;
};

using IndexEntries = std::vector<std::pair<std::uint64_t, std::uint64_t>>;  // log time, offset in chunk

}  // namespace

struct McapWriter::State {
  int fd = -1;
  std::uint64_t committed = 0;  // bytes of complete records in the file
  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  // The open chunk.
  std::vector<std::uint8_t> records;
  std::map<std::uint16_t, IndexEntries> index;
  std::uint64_t chunk_start = 0;
  std::uint64_t chunk_end = 0;
  std::size_t chunk_messages = 0;
  // Scratch buffers, reused.
  std::vector<std::uint8_t> compressed;
  std::vector<std::uint8_t> out;
  std::vector<ChunkIndexEntry> chunk_indexes;
  std::vector<std::map<std::uint16_t, std::uint64_t>> chunk_counts;  // by chunk: messages per channel
  Statistics statistics;
  bool closed = false;
};

namespace {

std::string errno_text(int error) {
  return std::strerror(error);
}

// Writes all of `data` at the end of the file; the errno text on failure.
std::optional<std::string> write_all(int fd, std::span<const std::uint8_t> data) {
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno_text(errno);
    if (n == 0) return std::string("wrote nothing");
    done += static_cast<std::size_t>(n);
  }
  return std::nullopt;
}

}  // namespace

McapWriter::McapWriter(const std::filesystem::path& path, const McapWriterOptions& options)
    : path_(path), options_(options), state_(std::make_unique<State>()) {
  state_->fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (state_->fd < 0) throw RecordingError(path.string() + ": cannot create: " + errno_text(errno));
  std::vector<std::uint8_t> bytes;
  fmt::Out o(bytes);
  o.bytes(fmt::kMagic.data(), fmt::kMagic.size());
  const std::size_t header = o.begin_record(fmt::kHeader);
  o.str(options_.profile);
  o.str(options_.library);
  o.finish_record(header);
  if (const auto error = write_all(state_->fd, bytes)) {
    ::close(state_->fd);
    state_->fd = -1;
    state_->closed = true;
    throw RecordingError(path.string() + ": cannot write the header: " + *error);
  }
  state_->committed = bytes.size();
  stats_.file_bytes = state_->committed;
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw; close() reports errors
  }
}

namespace {

// One Schema or Channel record; the data section and the summary repeat them alike.
void append_schema(fmt::Out& o, const Schema& schema) {
  const std::size_t r = o.begin_record(fmt::kSchema);
  o.u16(schema.id);
  o.str(schema.name);
  o.str(schema.encoding);
  o.str(schema.data);
  o.finish_record(r);
}

void append_channel(fmt::Out& o, const Channel& channel) {
  const std::size_t r = o.begin_record(fmt::kChannel);
  o.u16(channel.id);
  o.u16(channel.schema_id);
  o.str(channel.topic);
  o.str(channel.message_encoding);
  o.map(channel.metadata);
  o.finish_record(r);
}

void append_summary(std::vector<std::uint8_t>& out, std::uint64_t summary_start,
                    const std::vector<Schema>& schemas, const std::vector<Channel>& channels,
                    const Statistics& statistics, const std::vector<ChunkIndexEntry>& chunk_indexes) {
  fmt::Out o(out);
  struct Group {
    std::uint8_t op;
    std::uint64_t start;
    std::uint64_t length;
  };
  std::vector<Group> groups;
  const auto group = [&](std::uint8_t op, std::size_t begin) {
    if (out.size() > begin) groups.push_back({op, summary_start + begin, out.size() - begin});
  };
  std::size_t begin = out.size();
  for (const auto& schema : schemas) append_schema(o, schema);
  group(fmt::kSchema, begin);
  begin = out.size();
  for (const auto& channel : channels) append_channel(o, channel);
  group(fmt::kChannel, begin);
  begin = out.size();
  {
    const std::size_t r = o.begin_record(fmt::kStatistics);
    o.u64(statistics.message_count);
    o.u16(static_cast<std::uint16_t>(schemas.size()));
    o.u32(static_cast<std::uint32_t>(channels.size()));
    o.u32(0);
    o.u32(0);
    o.u32(static_cast<std::uint32_t>(chunk_indexes.size()));
    o.u64(statistics.message_start_time);
    o.u64(statistics.message_end_time);
    const std::size_t map_start = out.size();
    o.u32(0);
    for (const auto& [channel, count] : statistics.channel_message_counts) {
      o.u16(channel);
      o.u64(count);
    }
    const auto map_length = static_cast<std::uint32_t>(out.size() - map_start - 4);
    for (int i = 0; i < 4; ++i) out[map_start + i] = static_cast<std::uint8_t>(map_length >> (8 * i));
    o.finish_record(r);
  }
  group(fmt::kStatistics, begin);
  begin = out.size();
  for (const auto& c : chunk_indexes) {
    const std::size_t r = o.begin_record(fmt::kChunkIndex);
    o.u64(c.start_time);
    o.u64(c.end_time);
    o.u64(c.chunk_offset);
    o.u64(c.chunk_length);
    o.u32(static_cast<std::uint32_t>(c.message_index_offsets.size() * 10));
    for (const auto& [channel, offset] : c.message_index_offsets) {
      o.u16(channel);
      o.u64(offset);
    }
    o.u64(c.message_index_length);
    o.str(c.compression);
    o.u64(c.compressed_size);
    o.u64(c.uncompressed_size);
    o.finish_record(r);
  }
  group(fmt::kChunkIndex, begin);
  const std::uint64_t summary_offset_start = summary_start + out.size();
  for (const auto& g : groups) {
    const std::size_t r = o.begin_record(fmt::kSummaryOffset);
    o.u8(g.op);
    o.u64(g.start);
    o.u64(g.length);
    o.finish_record(r);
  }
  // The summary CRC covers the footer's own opcode, length and offsets: its length is written now.
  o.u8(fmt::kFooter);
  o.u64(20);
  o.u64(summary_start);
  o.u64(summary_offset_start);
  o.u32(fmt::crc32(std::span<const std::uint8_t>(out.data(), out.size())));
  o.bytes(fmt::kMagic.data(), fmt::kMagic.size());
}

}  // namespace

// Appends `bytes` (complete records) to the file. On failure the file is cut back to its last
// complete record and closed with a summary if that still fits; then RecordingError.
void McapWriter::commit(std::span<const std::uint8_t> bytes, const char* what) {
  if (state_->closed || state_->fd < 0) throw RecordingError(path_.string() + ": the recording is closed");
  if (const auto error = write_all(state_->fd, bytes)) {
    const std::uint64_t at = state_->committed;
    const bool saved = close_after_error();
    throw RecordingError(path_.string() + ": cannot write " + what + " at byte " + std::to_string(at) + ": " +
                         *error +
                         (saved ? "; recording stopped, the file was closed with its summary"
                                : "; recording stopped, the file holds every complete chunk "
                                  "(readable without its summary)"));
  }
  state_->committed += bytes.size();
  stats_.file_bytes = state_->committed;
}

bool McapWriter::close_after_error() {
  State& s = *state_;
  s.closed = true;
  bool saved = false;
  // The summary goes after the last complete chunk; where it does not fit (a file size limit),
  // the newest chunks are given up one by one until it does: a valid file beats one more chunk.
  while (!saved && ::ftruncate(s.fd, static_cast<off_t>(s.committed)) == 0 &&
         ::lseek(s.fd, static_cast<off_t>(s.committed), SEEK_SET) >= 0) {
    std::vector<std::uint8_t> tail;
    append_data_end_and_summary(tail);
    if (!write_all(s.fd, tail)) {
      saved = true;
    } else if (!drop_last_chunk()) {
      (void)::ftruncate(s.fd, static_cast<off_t>(s.committed));  // the reader recovers the chunks
      break;
    }
  }
  ::close(s.fd);
  s.fd = -1;
  return saved;
}

bool McapWriter::drop_last_chunk() {
  State& s = *state_;
  if (s.chunk_indexes.empty()) return false;
  s.committed = s.chunk_indexes.back().chunk_offset;
  Statistics& st = s.statistics;
  for (const auto& [channel, count] : s.chunk_counts.back()) {
    st.channel_message_counts[channel] -= count;
    st.message_count -= count;
  }
  s.chunk_indexes.pop_back();
  s.chunk_counts.pop_back();
  --stats_.chunks;
  st.message_start_time = st.message_end_time = 0;
  for (std::size_t i = 0; i < s.chunk_indexes.size(); ++i) {
    st.message_start_time = i == 0 ? s.chunk_indexes[i].start_time
                                   : std::min(st.message_start_time, s.chunk_indexes[i].start_time);
    st.message_end_time = std::max(st.message_end_time, s.chunk_indexes[i].end_time);
  }
  stats_.file_bytes = s.committed;
  return true;
}

void McapWriter::append_data_end_and_summary(std::vector<std::uint8_t>& out) const {
  const State& s = *state_;
  fmt::Out o(out);
  const std::size_t data_end = o.begin_record(fmt::kDataEnd);
  o.u32(0);  // data section CRC: not computed (the specification allows 0)
  o.finish_record(data_end);
  std::vector<std::uint8_t> summary;
  append_summary(summary, s.committed + out.size(), s.schemas, s.channels, s.statistics, s.chunk_indexes);
  out.insert(out.end(), summary.begin(), summary.end());
}

std::uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding,
                                     const std::string& data) {
  Schema schema{static_cast<std::uint16_t>(state_->schemas.size() + 1), name, encoding, data};
  std::vector<std::uint8_t> bytes;
  fmt::Out o(bytes);
  append_schema(o, schema);
  commit(bytes, "a schema");
  state_->schemas.push_back(std::move(schema));
  state_->statistics.schema_count = static_cast<std::uint16_t>(state_->schemas.size());
  return state_->schemas.back().id;
}

std::uint16_t McapWriter::add_channel(std::uint16_t schema_id, const std::string& topic,
                                      const std::string& message_encoding,
                                      const std::map<std::string, std::string>& metadata) {
  if (schema_id > state_->schemas.size())
    throw RecordingError(path_.string() + ": channel " + topic + ": unknown schema id " +
                         std::to_string(schema_id));
  Channel channel{static_cast<std::uint16_t>(state_->channels.size() + 1), schema_id, topic, message_encoding,
                  metadata};
  std::vector<std::uint8_t> bytes;
  fmt::Out o(bytes);
  append_channel(o, channel);
  commit(bytes, "a channel");
  state_->channels.push_back(std::move(channel));
  return state_->channels.back().id;
}

void McapWriter::write(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time,
                       std::uint64_t publish_time, std::span<const std::uint8_t> data) {
  State& s = *state_;
  if (s.closed) throw RecordingError(path_.string() + ": the recording is closed");
  if (channel_id == 0 || channel_id > s.channels.size())
    throw RecordingError(path_.string() + ": unknown channel id " + std::to_string(channel_id));
  if (s.chunk_messages > 0 && options_.chunk_duration_ns > 0 && log_time > s.chunk_start &&
      log_time - s.chunk_start >= options_.chunk_duration_ns) {
    flush();
  }
  const std::uint64_t offset = s.records.size();
  fmt::Out o(s.records);
  const std::size_t r = o.begin_record(fmt::kMessage);
  o.u16(channel_id);
  o.u32(sequence);
  o.u64(log_time);
  o.u64(publish_time);
  o.bytes(data.data(), data.size());
  o.finish_record(r);
  s.index[channel_id].emplace_back(log_time, offset);
  if (s.chunk_messages == 0 || log_time < s.chunk_start) s.chunk_start = log_time;
  if (s.chunk_messages == 0 || log_time > s.chunk_end) s.chunk_end = log_time;
  ++s.chunk_messages;
  ++stats_.messages;
  stats_.message_bytes += data.size();
  ++stats_.per_channel[channel_id];
  if (s.records.size() >= options_.chunk_size) flush();
}

void McapWriter::flush() {
  State& s = *state_;
  if (s.closed || s.chunk_messages == 0) return;
  ChunkIndexEntry entry;
  entry.start_time = s.chunk_start;
  entry.end_time = s.chunk_end;
  entry.chunk_offset = s.committed;
  entry.uncompressed_size = s.records.size();
  entry.compression = compression_name(options_.compression);
  fmt::compress(options_.compression, options_.compression_level, s.records, s.compressed);
  entry.compressed_size = s.compressed.size();
  auto& out = s.out;
  out.clear();
  fmt::Out o(out);
  const std::size_t chunk = o.begin_record(fmt::kChunk);
  o.u64(s.chunk_start);
  o.u64(s.chunk_end);
  o.u64(s.records.size());
  o.u32(fmt::crc32(s.records));
  o.str(entry.compression);
  o.u64(s.compressed.size());
  o.bytes(s.compressed.data(), s.compressed.size());
  o.finish_record(chunk);
  entry.chunk_length = out.size();
  for (auto& [channel, entries] : s.index) {
    std::stable_sort(entries.begin(), entries.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    entry.message_index_offsets[channel] = s.committed + out.size();
    const std::size_t r = o.begin_record(fmt::kMessageIndex);
    o.u16(channel);
    o.u32(static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, offset] : entries) {
      o.u64(time);
      o.u64(offset);
    }
    o.finish_record(r);
  }
  entry.message_index_length = out.size() - entry.chunk_length;
  // The summary's statistics count the messages of the chunks in the file only.
  std::map<std::uint16_t, std::uint64_t> chunk_counts;
  for (const auto& [channel, entries] : s.index) chunk_counts[channel] = entries.size();
  s.records.clear();
  s.index.clear();
  const std::size_t messages = s.chunk_messages;
  s.chunk_messages = 0;
  commit(out, "a chunk");
  Statistics& st = s.statistics;
  if (st.message_count == 0 || entry.start_time < st.message_start_time)
    st.message_start_time = entry.start_time;
  if (st.message_count == 0 || entry.end_time > st.message_end_time) st.message_end_time = entry.end_time;
  st.message_count += messages;
  for (const auto& [channel, count] : chunk_counts) st.channel_message_counts[channel] += count;
  if (options_.fsync_chunks) ::fdatasync(s.fd);
  s.chunk_indexes.push_back(std::move(entry));
  s.chunk_counts.push_back(std::move(chunk_counts));
  ++stats_.chunks;
}

void McapWriter::close() {
  State& s = *state_;
  if (s.closed) return;
  flush();
  std::vector<std::uint8_t> tail;
  append_data_end_and_summary(tail);
  commit(tail, "the summary");
  s.closed = true;
  if (::close(s.fd) != 0) {
    s.fd = -1;
    throw RecordingError(path_.string() + ": closing failed: " + errno_text(errno));
  }
  s.fd = -1;
}

}  // namespace panoptes::recording
