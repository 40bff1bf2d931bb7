// SPDX-License-Identifier: Apache-2.0
// bench_export: exporting 10 minutes of 41 markers (issue 17). The walking data (100 Hz, 238
// frames) is looped to --minutes of track records, one per marker and frame, stamped 100 Hz with a
// per-marker phase (asynchronous updates, as the estimator writes them). Measured, each step on
// its own, in one process: re-sampling the records to --rate, then writing C3D, TRC and CSV
// (encode + write to --dir), and as the reference the same bytes written by one fwrite of a
// ready buffer (the disk's floor). Prints JSON.
// --write-tracks FILE also writes the records as JSON Lines (estimator_node --out-tracks), to time
// the whole program: panoptes_export --tracks FILE --c3d ... (docs/benchmarks.md).
//   bench_export [--minutes 10] [--rate 100] [--dir /tmp] [--repeat 3] [--write-tracks FILE]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/csv.h"
#include "panoptes/formats/resample.h"
#include "panoptes/formats/trc.h"
#include "panoptes/jsonl.h"

namespace fs = std::filesystem;
using namespace panoptes;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Timing {
  double wall_s = 1e30;
  double cpu_s = 1e30;
};

// Best (least disturbed) of `repeat` runs of `step`: wall time and this thread's CPU time (user +
// system, so the kernel's share of writing counts; on a shared machine wall time includes waiting).
template <class Step>
Timing best_of(int repeat, Step&& step) {
  Timing best;
  for (int i = 0; i < repeat; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = thread_cpu_s();
    step();
    best.cpu_s = std::min(best.cpu_s, thread_cpu_s() - cpu_start);
    best.wall_s = std::min(best.wall_s, seconds_since(start));
  }
  return best;
}

void print_timing(const char* name, const Timing& timing) {
  std::printf("\"%s_wall_s\": %.3f, \"%s_cpu_s\": %.3f, ", name, timing.wall_s, name, timing.cpu_s);
}

std::vector<TrackRecord> looped_walk(const MarkerTrajectories& walk, double minutes) {
  const std::size_t frames = static_cast<std::size_t>(minutes * 60.0 * walk.data_rate_hz);
  const std::size_t markers = walk.marker_count();
  std::vector<TrackRecord> records;
  records.reserve(frames * markers);
  const TimeNs period = static_cast<TimeNs>(1e9 / walk.data_rate_hz);
  for (std::size_t f = 0; f < frames; ++f) {
    for (std::size_t m = 0; m < markers; ++m) {
      TrackRecord record;
      record.id = static_cast<std::int64_t>(m);
      // Each marker updated off the output grid: phase m * 0.2 ms.
      record.stamp_ns = static_cast<TimeNs>(f) * period + static_cast<TimeNs>(m) * 200'000;
      record.p = walk.position(f % walk.frame_count(), m);
      record.cameras = 4;
      record.position_covariance = {1e-6, 0, 0, 1e-6, 0, 1e-6};
      records.push_back(record);
    }
  }
  return records;
}

}  // namespace

static int run_main(int argc, char** argv) {
  CLI::App app{"bench_export: re-sample and write 10 min of 41 markers as C3D, TRC and CSV", "bench_export"};
  double minutes = 10.0;
  double rate_hz = 100.0;
  std::string dir = fs::temp_directory_path().string();
  int repeat = 3;
  app.add_option("--minutes", minutes, "length of the looped take")->capture_default_str();
  app.add_option("--rate", rate_hz, "output rate, Hz")->capture_default_str();
  app.add_option("--dir", dir, "where the files are written (and removed)")->capture_default_str();
  app.add_option("--repeat", repeat, "runs of each step; the best is reported")->capture_default_str();
  std::string write_tracks;
  app.add_option("--write-tracks", write_tracks, "also write the track records as JSON Lines here");
  if (const auto exit = parse_command_line(app, argc, argv)) return *exit;

  const MarkerTrajectories walk =
      load_trc(fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc");
  const std::vector<TrackRecord> records = looped_walk(walk, minutes);
  if (!write_tracks.empty()) {
    fs::remove(write_tracks);
    JsonlWriter writer(write_tracks);
    for (const TrackRecord& record : records) writer.write(record);
    writer.flush();
  }
  ResampleOptions options;
  options.rate_hz = rate_hz;
  MarkerTrajectories markers;
  const Timing resample = best_of(repeat, [&] {
    const SampleGrid grid = make_grid(records, {}, options);
    markers = resample_tracks(records, grid, options);
  });
  markers.units = "mm";
  const fs::path base = fs::path(dir) / "panoptes_bench_export";
  const Timing c3d = best_of(repeat, [&] { write_c3d(base.string() + ".c3d", markers); });
  const Timing trc = best_of(repeat, [&] { write_trc(base.string() + ".trc", markers); });
  const Timing csv = best_of(repeat, [&] { write_markers_csv(base.string() + ".csv", markers); });
  const auto c3d_bytes = fs::file_size(base.string() + ".c3d");
  const auto trc_bytes = fs::file_size(base.string() + ".trc");
  const auto csv_bytes = fs::file_size(base.string() + ".csv");
  // The floor: the C3D's bytes, ready in memory, written with one fwrite.
  const std::vector<std::uint8_t> ready = encode_c3d(markers, {});
  const Timing floor = best_of(repeat, [&] {
    std::FILE* file = std::fopen((base.string() + ".raw").c_str(), "wb");
    if (file == nullptr) return;
    std::fwrite(ready.data(), 1, ready.size(), file);
    std::fclose(file);
  });
  for (const char* extension : {".c3d", ".trc", ".csv", ".raw"}) fs::remove(base.string() + extension);
  std::printf("{\"frames\": %zu, \"markers\": %zu, \"records\": %zu, ", markers.frame_count(),
              markers.marker_count(), records.size());
  print_timing("resample", resample);
  print_timing("c3d", c3d);
  print_timing("trc", trc);
  print_timing("csv", csv);
  print_timing("c3d_fwrite_floor", floor);
  std::printf(
      "\"total_wall_s\": %.3f, \"total_cpu_s\": %.3f, \"c3d_over_floor_wall\": %.2f, \"c3d_bytes\": %ju, "
      "\"trc_bytes\": %ju, \"csv_bytes\": %ju}\n",
      resample.wall_s + c3d.wall_s + trc.wall_s + csv.wall_s,
      resample.cpu_s + c3d.cpu_s + trc.cpu_s + csv.cpu_s, c3d.wall_s / floor.wall_s,
      static_cast<std::uintmax_t>(c3d_bytes), static_cast<std::uintmax_t>(trc_bytes),
      static_cast<std::uintmax_t>(csv_bytes));
  return 0;
}

int main(int argc, char** argv) {
  return panoptes::run_program("bench_export", [&] { return run_main(argc, argv); });
}
