// SPDX-License-Identifier: Apache-2.0
// MCAP writer and reader: round trips with every compression, the summary's statistics, recovery of
// a file cut anywhere (a killed writer), a write error that stops with a valid file, and a seeded
// fuzz of truncations and bit flips that the reader must survive.
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/recording/mcap_reader.h"
#include "panoptes/recording/mcap_writer.h"

namespace panoptes::recording {
namespace {

namespace fs = std::filesystem;

fs::path temp_file(const std::string& name) {
  return fs::temp_directory_path() / ("panoptes_mcap_" + std::to_string(::getpid()) + "_" + name);
}

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes, std::size_t n) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(n));
}

// A payload whose bytes depend on its channel and sequence, so a reader can check it.
std::vector<std::uint8_t> payload(std::uint16_t channel, std::uint32_t sequence) {
  std::vector<std::uint8_t> data(40 + (sequence * 7 + channel * 13) % 300);
  for (std::size_t i = 0; i < data.size(); ++i)
    data[i] = static_cast<std::uint8_t>(channel * 31 + sequence + i);
  return data;
}

struct Written {
  std::uint64_t messages = 0;
  // (file size after a chunk, messages written by then): a cut at or after the size keeps them all.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> chunk_ends;
};

// Three channels, `count` messages, small chunks; closed unless `close` is false.
Written write_recording(const fs::path& path, Compression compression, int count, bool close = true) {
  McapWriterOptions options;
  options.compression = compression;
  options.chunk_size = 4096;
  McapWriter writer(path, options);
  const auto schema = writer.add_schema("panoptes/msg/FeatureFrame", "ros2idl", "module panoptes { };");
  std::vector<std::uint16_t> channels;
  for (const char* topic : {"/panoptes/features", "/panoptes/tracks", "/panoptes/camera_status"})
    channels.push_back(writer.add_channel(schema, topic, "cdr", {{"offered_qos_profiles", ""}}));
  Written written;
  for (int i = 0; i < count; ++i) {
    const auto channel = channels[static_cast<std::size_t>(i) % 3];
    const auto sequence = static_cast<std::uint32_t>(i);
    const std::uint64_t chunks = writer.stats().chunks;
    writer.write(channel, sequence, 1'000'000'000ULL + i * 1000ULL, 1'000'000'000ULL + i * 900ULL,
                 payload(channel, sequence));
    if (writer.stats().chunks != chunks) written.chunk_ends.emplace_back(writer.stats().file_bytes, i + 1);
  }
  written.messages = static_cast<std::uint64_t>(count);
  if (close) writer.close();
  return written;
}

struct ReadBack {
  ReadReport report;
  std::map<std::string, std::uint64_t> per_topic;
  int bad_payloads = 0;
};

ReadBack read_recording(const fs::path& path) {
  McapReader reader(path);
  ReadBack back;
  back.report = reader.read([&](const MessageView& m) {
    ++back.per_topic[m.channel->topic];
    if (payload(m.channel->id, m.sequence) != std::vector<std::uint8_t>(m.data.begin(), m.data.end()))
      ++back.bad_payloads;
  });
  return back;
}

class McapRoundTrip : public ::testing::TestWithParam<Compression> {};

TEST_P(McapRoundTrip, EveryMessageComesBackWithTheSummaryStatistics) {
  const auto path = temp_file("roundtrip.mcap");
  const auto written = write_recording(path, GetParam(), 3000);
  const auto back = read_recording(path);
  EXPECT_EQ(back.report.messages, written.messages);
  EXPECT_EQ(back.bad_payloads, 0);
  EXPECT_EQ(back.report.chunks_skipped, 0u);
  EXPECT_GT(back.report.chunks, 10u);
  EXPECT_TRUE(back.report.data_end);
  EXPECT_TRUE(back.report.summary);
  EXPECT_EQ(back.report.problem_count, 0u) << (back.report.problems.empty() ? "" : back.report.problems[0]);
  ASSERT_TRUE(back.report.statistics.has_value());
  EXPECT_EQ(back.report.statistics->message_count, 3000u);
  EXPECT_EQ(back.report.statistics->channel_count, 3u);
  EXPECT_EQ(back.report.statistics->chunk_count, back.report.chunks);
  EXPECT_EQ(back.report.statistics->channel_message_counts.at(1), 1000u);
  EXPECT_EQ(back.per_topic.at("/panoptes/tracks"), 1000u);
  // PANOPTES_MCAP_KEEP=<dir> keeps the file for the independent reader (tests/mcap/check_mcap.mjs).
  if (const char* keep = std::getenv("PANOPTES_MCAP_KEEP"); keep != nullptr && *keep != '\0') {
    fs::copy_file(path, fs::path(keep) / ("roundtrip_" + std::string(compression_name(GetParam())) + ".mcap"),
                  fs::copy_options::overwrite_existing);
  }
  fs::remove(path);
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapRoundTrip,
                         ::testing::Values(Compression::kZstd, Compression::kLz4, Compression::kNone));

TEST(McapReader, RecoversEveryCompleteChunkOfACutFile) {
  const auto path = temp_file("cut_source.mcap");
  const auto written = write_recording(path, Compression::kZstd, 3000, /*close=*/false);
  const auto bytes = read_bytes(path);  // what a writer killed now leaves: no summary, no footer
  ASSERT_GT(written.chunk_ends.size(), 10u);
  const auto cut_path = temp_file("cut.mcap");
  for (std::size_t k = 0; k < written.chunk_ends.size(); k += 3) {
    // Cut just after a complete chunk's indexes, and a little later (inside the next chunk).
    for (const std::uint64_t extra : {0ULL, 57ULL}) {
      const std::uint64_t cut = std::min<std::uint64_t>(written.chunk_ends[k].first + extra, bytes.size());
      write_bytes(cut_path, bytes, cut);
      const auto back = read_recording(cut_path);
      EXPECT_GE(back.report.messages, written.chunk_ends[k].second) << "cut at " << cut;
      EXPECT_EQ(back.bad_payloads, 0);
      EXPECT_FALSE(back.report.summary);
      EXPECT_FALSE(back.report.problems.empty());
    }
  }
  fs::remove(path);
  fs::remove(cut_path);
}

TEST(McapReader, CountsAndSkipsACorruptedChunkNamingTheOffset) {
  const auto path = temp_file("corrupt.mcap");
  const auto written = write_recording(path, Compression::kNone, 3000);
  auto bytes = read_bytes(path);
  // A bit flip in the middle of the third chunk's message data (uncompressed: the CRC catches it).
  const std::uint64_t third = written.chunk_ends[1].first;
  bytes[third + 200] ^= 0x10;
  write_bytes(path, bytes, bytes.size());
  const auto back = read_recording(path);
  EXPECT_EQ(back.report.chunks_skipped, 1u);
  EXPECT_LT(back.report.messages, written.messages);
  EXPECT_GT(back.report.messages, written.messages - 100);
  EXPECT_EQ(back.bad_payloads, 0);
  ASSERT_FALSE(back.report.problems.empty());
  EXPECT_NE(back.report.problems[0].find("byte " + std::to_string(third)), std::string::npos)
      << back.report.problems[0];
  EXPECT_NE(back.report.problems[0].find("CRC"), std::string::npos) << back.report.problems[0];
  fs::remove(path);
}

TEST(McapReader, EmptyAndForeignFilesGiveAClearError) {
  const auto empty = temp_file("empty.mcap");
  write_bytes(empty, {}, 0);
  try {
    McapReader reader(empty);
    FAIL() << "an empty file was accepted";
  } catch (const RecordingError& error) {
    EXPECT_NE(std::string(error.what()).find("empty file"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find(empty.string()), std::string::npos) << error.what();
  }
  const auto foreign = temp_file("foreign.mcap");
  const std::string text = "{\"camera_id\": \"cam0\"}\n";
  write_bytes(foreign, std::vector<std::uint8_t>(text.begin(), text.end()), text.size());
  try {
    McapReader reader(foreign);
    FAIL() << "a JSON file was accepted";
  } catch (const RecordingError& error) {
    EXPECT_NE(std::string(error.what()).find("not an MCAP file"), std::string::npos) << error.what();
  }
  EXPECT_THROW(McapReader(temp_file("missing.mcap")), RecordingError);
  fs::remove(empty);
  fs::remove(foreign);
}

TEST(McapWriter, AWriteErrorStopsWithAClearErrorAndAValidFile) {
  const auto path = temp_file("full.mcap");
  // The file size limit makes write(2) fail with EFBIG, as a full disk fails with ENOSPC.
  ::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  ::getrlimit(RLIMIT_FSIZE, &old);
  rlimit limited = old;
  limited.rlim_cur = 60'000;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
  std::string error;
  std::uint64_t accepted = 0;
  {
    McapWriterOptions options;
    options.chunk_size = 8192;
    options.compression = Compression::kNone;
    McapWriter writer(path, options);
    const auto channel = writer.add_channel(writer.add_schema("s", "ros2msg", ""), "/t", "cdr");
    try {
      for (std::uint32_t i = 0; i < 100000; ++i) {
        writer.write(channel, i, i, i, payload(channel, i));
        accepted = i + 1;
      }
    } catch (const RecordingError& e) {
      error = e.what();
    }
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  EXPECT_NE(error.find("cannot write"), std::string::npos) << error;
  EXPECT_LT(fs::file_size(path), 60'000u);
  const auto back = read_recording(path);
  EXPECT_TRUE(back.report.summary) << error;
  ASSERT_TRUE(back.report.statistics.has_value());
  EXPECT_EQ(back.report.statistics->message_count, back.report.messages);  // the lost chunk not counted
  EXPECT_EQ(back.report.chunks_skipped, 0u);
  EXPECT_GT(back.report.messages, 0u);
  EXPECT_LE(back.report.messages, accepted);
  EXPECT_EQ(back.bad_payloads, 0);
  fs::remove(path);
}

TEST(McapReader, FuzzedTruncationsAndBitFlipsNeverCrash) {
  const auto source = temp_file("fuzz_source.mcap");
  const auto written = write_recording(source, Compression::kZstd, 1500);
  const auto lz4_source = temp_file("fuzz_source_lz4.mcap");
  write_recording(lz4_source, Compression::kLz4, 1500);
  const auto fuzzed = temp_file("fuzz.mcap");
  std::mt19937_64 random(17);
  int opened = 0;
  int refused = 0;
  for (int round = 0; round < 400; ++round) {
    auto bytes = read_bytes(round % 2 == 0 ? source : lz4_source);
    std::size_t n = bytes.size();
    if (round % 3 != 0) n = std::uniform_int_distribution<std::size_t>(0, bytes.size())(random);
    const int flips = std::uniform_int_distribution<int>(0, 8)(random);
    for (int f = 0; f < flips && n > 0; ++f) {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, n - 1)(random);
      bytes[at] ^= static_cast<std::uint8_t>(1U << std::uniform_int_distribution<int>(0, 7)(random));
    }
    write_bytes(fuzzed, bytes, n);
    try {
      const auto back = read_recording(fuzzed);
      ++opened;
      EXPECT_LE(back.report.messages, written.messages);
      if (flips == 0 && n == bytes.size()) {
        EXPECT_EQ(back.report.messages, written.messages);
      }
    } catch (const RecordingError&) {
      ++refused;  // header damaged or cut: a clear error is the right answer
    }
  }
  EXPECT_GT(opened, 300);
  EXPECT_EQ(opened + refused, 400);
  fs::remove(source);
  fs::remove(lz4_source);
  fs::remove(fuzzed);
}

}  // namespace
}  // namespace panoptes::recording
