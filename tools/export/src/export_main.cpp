// SPDX-License-Identifier: Apache-2.0
// panoptes_export: the estimator's tracks and body poses (today its JSON Lines outputs,
// estimator_node --out-tracks / --out-poses) re-sampled to a fixed rate and written as C3D, TRC
// and CSV; or a marker file (TRC, C3D) converted to the others. docs/recording.md, "Export".
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/errors.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/csv.h"
#include "panoptes/formats/record_source.h"
#include "panoptes/formats/resample.h"
#include "panoptes/formats/trc.h"
#include "panoptes/process.h"

namespace fs = std::filesystem;
using namespace panoptes;

namespace {

struct Options {
  std::string tracks;
  std::string poses;
  std::string markers;  // a TRC or C3D file to convert instead of records
  std::string c3d;
  std::string trc;
  std::string csv;
  std::string bodies_csv;
  std::string units = "mm";
  double rate_hz = 100.0;
  double max_gap_ms = 100.0;
  bool include_tentative = false;
  bool no_body_points = false;
};

bool has_extension(const std::string& path, const std::string& extension) {
  std::string actual = fs::path(path).extension().string();
  for (char& c : actual) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return actual == extension;
}

struct Exported {
  MarkerTrajectories markers;
  BodyTrajectories bodies;
  std::size_t skipped = 0;
};

Exported from_records(const Options& options) {
  JsonlRecordSource source(options.tracks.empty() ? std::nullopt : std::optional<fs::path>(options.tracks),
                           options.poses.empty() ? std::nullopt : std::optional<fs::path>(options.poses));
  ExportRecords records = source.read();
  for (const std::string& error : records.skipped) std::fprintf(stderr, "skipped %s\n", error.c_str());
  ResampleOptions resample;
  resample.rate_hz = options.rate_hz;
  resample.max_gap_ns = static_cast<TimeNs>(options.max_gap_ms * 1e6);
  resample.include_tentative = options.include_tentative;
  if (records.tracks.empty() && records.poses.empty()) {
    throw ConfigError(source.describe(), "", "no track or pose records to export");
  }
  const SampleGrid grid = make_grid(records.tracks, records.poses, resample);
  Exported out;
  out.markers = resample_tracks(records.tracks, grid, resample);
  out.bodies = resample_poses(records.poses, grid, resample);
  if (!options.no_body_points) append_body_origins(out.markers, out.bodies);
  out.skipped = records.skipped.size();
  return out;
}

int run(const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Exported data;
  if (!options.markers.empty()) {
    data.markers =
        has_extension(options.markers, ".c3d") ? load_c3d(options.markers) : load_trc(options.markers);
  } else {
    data = from_records(options);
  }
  data.markers.units = options.units;
  const bool any_markers = data.markers.marker_count() > 0;
  if (!any_markers && (!options.c3d.empty() || !options.trc.empty() || !options.csv.empty())) {
    throw ConfigError(options.tracks.empty() ? options.poses : options.tracks, "",
                      "no confirmed tracks or bodies to write as markers");
  }
  if (!options.c3d.empty())
    write_c3d(options.c3d, data.markers, C3dWriteOptions{options.units, "panoptes_export"});
  if (!options.trc.empty()) write_trc(options.trc, data.markers);
  if (!options.csv.empty()) write_markers_csv(options.csv, data.markers);
  if (!options.bodies_csv.empty()) write_bodies_csv(options.bodies_csv, data.bodies);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "{\"frames\": %zu, \"markers\": %zu, \"bodies\": %zu, \"rate_hz\": %.6g, \"skipped_records\": %zu, "
      "\"seconds\": %.3f}\n",
      data.markers.frame_count(), data.markers.marker_count(), data.bodies.body_count(),
      data.markers.data_rate_hz, data.skipped, seconds);
  return kExitOk;
}

}  // namespace

static int run_main(int argc, char** argv) {
  CLI::App app{
      "panoptes_export: tracks and body poses to C3D, TRC and CSV at a fixed rate (docs/recording.md)",
      "panoptes_export"};
  Options options;
  app.add_option("--tracks", options.tracks, "tracks JSON Lines file (estimator_node --out-tracks)")
      ->check(CLI::ExistingFile);
  app.add_option("--poses", options.poses, "body poses JSON Lines file (estimator_node --out-poses)")
      ->check(CLI::ExistingFile);
  app.add_option("--markers", options.markers, "convert a marker file (.trc or .c3d) instead of records")
      ->check(CLI::ExistingFile);
  app.add_option("--c3d", options.c3d, "write markers (tracks, body origins) as C3D");
  app.add_option("--trc", options.trc, "write markers as TRC");
  app.add_option("--csv", options.csv, "write markers as CSV (metres)");
  app.add_option("--bodies-csv", options.bodies_csv, "write body poses as CSV with quaternions");
  app.add_option("--rate", options.rate_hz, "output rate, Hz")
      ->capture_default_str()
      ->check(positive_number());
  app.add_option("--max-gap-ms", options.max_gap_ms,
                 "updates further apart leave the samples between invalid, ms")
      ->capture_default_str()
      ->check(positive_number());
  app.add_option("--units", options.units, "units of the C3D and TRC files")
      ->capture_default_str()
      ->check(CLI::IsMember({"mm", "cm", "m"}));
  app.add_flag("--include-tentative", options.include_tentative, "export tentative tracks too");
  app.add_flag("--no-body-points", options.no_body_points,
               "leave the bodies' origins out of the marker files");
  const auto exit = parse_command_line(app, argc, argv, [&] {
    const bool records = !options.tracks.empty() || !options.poses.empty();
    if (records == !options.markers.empty()) {
      throw CLI::ValidationError("input", "give --tracks and/or --poses, or --markers");
    }
    if (options.c3d.empty() && options.trc.empty() && options.csv.empty() && options.bodies_csv.empty()) {
      throw CLI::ValidationError("output", "give at least one of --c3d, --trc, --csv, --bodies-csv");
    }
    if (!options.markers.empty() && !options.bodies_csv.empty()) {
      throw CLI::ValidationError("--bodies-csv", "needs --poses");
    }
  });
  if (exit) return *exit;
  return run(options);
}

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_export", [&] { return run_main(argc, argv); });
}
