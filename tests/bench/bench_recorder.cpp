// SPDX-License-Identifier: Apache-2.0
// bench_recorder: the MCAP writer of panoptes_record (issue 17) on one core. Synthetic FeatureFrame
// CDR payloads, serialized by the real message type, at the size of the reference load: 32
// cameras x 120 Hz, 40 blobs per frame (seeded noise in the blob fields, so chunks compress as real
// data does). Two measurements, one after the other in this thread:
//   throughput: every payload written as fast as possible (messages/s, MB/s, multiple of the load);
//   1x load:    the payloads paced at 32 x 120 Hz for --seconds, the thread's CPU time / wall time.
//   bench_recorder [--cameras 32] [--rate 120] [--markers 40] [--seconds 5] [--compression zstd] [--keep
//   f.mcap]
#include <time.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/cdr.h"
#include "panoptes/process.h"
#include "panoptes/recording/mcap_writer.h"

namespace {

namespace rec = panoptes::recording;
using Clock = std::chrono::steady_clock;

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

// One second of the load: cameras x rate frames, each with `markers` blobs.
std::vector<std::vector<std::uint8_t>> make_payloads(int cameras, int rate, int markers) {
  std::mt19937 random(17);
  std::normal_distribution<float> noise(0.0F, 1.0F);
  std::vector<std::vector<std::uint8_t>> payloads;
  for (int f = 0; f < rate; ++f) {
    for (int c = 0; c < cameras; ++c) {
      panoptes::msg::FeatureFrame frame;
      frame.camera_id("cam" + std::to_string(c));
      frame.frame(f);
      frame.stamp_ns(1'700'000'000'000'000'000LL + f * 8'333'333LL);
      frame.arrival_ns(frame.stamp_ns() + 2'000'000);
      frame.processing_ns(900'000 + static_cast<std::int64_t>(noise(random) * 1e5F));
      frame.publish_ns(frame.arrival_ns() + frame.processing_ns());
      for (int m = 0; m < markers; ++m) {
        panoptes::msg::Blob blob;
        const float x = 640.0F + 300.0F * noise(random);
        const float y = 512.0F + 250.0F * noise(random);
        blob.x(x);
        blob.y(y);
        blob.area(28.0F + noise(random));
        blob.sum(5000.0F + 200.0F * noise(random));
        blob.peak(static_cast<std::uint16_t>(220 + static_cast<int>(5 * noise(random))));
        blob.m20(1.5F + 0.1F * noise(random));
        blob.m11(0.05F * noise(random));
        blob.m02(1.5F + 0.1F * noise(random));
        blob.bbox({static_cast<std::uint16_t>(x - 3), static_cast<std::uint16_t>(y - 3),
                   static_cast<std::uint16_t>(x + 4), static_cast<std::uint16_t>(y + 4)});
        frame.blobs().push_back(blob);
      }
      payloads.push_back(panoptes::dds::encode_cdr(frame));
    }
  }
  return payloads;
}

struct Run {
  double wall_s = 0;
  double cpu_s = 0;
  std::uint64_t messages = 0;
  std::uint64_t payload_bytes = 0;
  std::uint64_t file_bytes = 0;
};

// Writes `seconds` of payloads, paced at `per_second` messages/s (0: as fast as possible).
Run write(const std::filesystem::path& path, const rec::McapWriterOptions& options,
          const std::vector<std::vector<std::uint8_t>>& payloads, double seconds, double per_second,
          const std::string& keep = {}) {
  rec::McapWriter writer(path, options);
  const auto channel = writer.add_channel(writer.add_schema("panoptes/msg/FeatureFrame", "ros2idl", "struct"),
                                          "/panoptes/features", "cdr");
  const auto total = static_cast<std::uint64_t>(seconds * static_cast<double>(payloads.size()));
  const double cpu0 = thread_cpu_s();
  const auto start = Clock::now();
  const std::uint64_t t0 = 1'700'000'000'000'000'000ULL;
  const double period_ns = 1e9 / static_cast<double>(payloads.size());
  for (std::uint64_t i = 0; i < total; ++i) {
    if (per_second > 0)
      std::this_thread::sleep_until(start + std::chrono::nanoseconds(static_cast<std::int64_t>(
                                                static_cast<double>(i) * 1e9 / per_second)));
    const auto log_time = t0 + static_cast<std::uint64_t>(static_cast<double>(i) * period_ns);
    writer.write(channel, static_cast<std::uint32_t>(i), log_time, log_time, payloads[i % payloads.size()]);
  }
  writer.close();
  Run run;
  run.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  run.cpu_s = thread_cpu_s() - cpu0;
  run.messages = writer.stats().messages;
  run.payload_bytes = writer.stats().message_bytes;
  run.file_bytes = writer.stats().file_bytes;
  if (keep.empty()) {
    std::filesystem::remove(path);
  } else {
    std::filesystem::rename(path, keep);
  }
  return run;
}

int run(int argc, char** argv) {
  int cameras = 32;
  int rate = 120;
  int markers = 40;
  double seconds = 5;
  double fast_seconds = 20;
  std::string compression = "zstd";
  std::string dir = std::filesystem::temp_directory_path().string();
  CLI::App app{"bench_recorder: MCAP writer throughput and CPU share at the reference load",
               "bench_recorder"};
  app.add_option("--cameras", cameras, "cameras")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--rate", rate, "frames per second per camera")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--markers", markers, "blobs per frame")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--seconds", seconds, "seconds of the paced 1x run")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--fast-seconds", fast_seconds, "seconds of load written as fast as possible")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--compression", compression, "chunk compression")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}))
      ->capture_default_str();
  app.add_option("--dir", dir, "where the (deleted) test files go")->capture_default_str();
  std::string keep;
  app.add_option(
      "--keep", keep,
      "keep the throughput run's file here: --fast-seconds of the load at its pace, for panoptes_replay "
      "into a live panoptes_record (docs/benchmarks.md)");
  if (const auto code = panoptes::parse_command_line(app, argc, argv)) return *code;

  const auto payloads = make_payloads(cameras, rate, markers);
  rec::McapWriterOptions options;
  options.compression = compression == "lz4"    ? rec::Compression::kLz4
                        : compression == "none" ? rec::Compression::kNone
                                                : rec::Compression::kZstd;
  const std::filesystem::path path = std::filesystem::path(dir) / "bench_recorder.mcap";
  const double load = static_cast<double>(payloads.size());
  const Run fast = write(path, options, payloads, fast_seconds, 0, keep);
  const Run paced = write(path, options, payloads, seconds, load);
  const double payload_avg = static_cast<double>(fast.payload_bytes) / static_cast<double>(fast.messages);
  const double rate_fast = static_cast<double>(fast.messages) / fast.cpu_s;
  std::printf("load: %d cameras x %d Hz x %d markers = %.0f messages/s, payload %.0f bytes (%.2f MB/s), %s\n",
              cameras, rate, markers, load, payload_avg, load * payload_avg / 1e6, compression.c_str());
  std::printf(
      "throughput (one core, CPU time): %.0f messages/s, %.1f MB/s payload = %.1fx the load; "
      "file %.1f%% of payload\n",
      rate_fast, rate_fast * payload_avg / 1e6, rate_fast / load,
      100.0 * static_cast<double>(fast.file_bytes) / static_cast<double>(fast.payload_bytes));
  std::printf("1x load for %.1f s: %.2f%% of one core (%.3f s CPU, %llu messages)\n", paced.wall_s,
              100.0 * paced.cpu_s / paced.wall_s, paced.cpu_s,
              static_cast<unsigned long long>(paced.messages));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_recorder", [&] { return run(argc, argv); });
}
