// SPDX-License-Identifier: Apache-2.0
#include "panoptes/export_job/export_job.h"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "panoptes/errors.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/csv.h"
#include "panoptes/formats/record_source.h"
#include "panoptes/formats/resample.h"
#include "panoptes/formats/trc.h"

namespace fs = std::filesystem;

namespace panoptes::export_job {
namespace {

struct Exported {
  MarkerTrajectories markers;
  BodyTrajectories bodies;
  std::size_t skipped = 0;
};

Exported from_records(const ExportOptions& options) {
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

}  // namespace

std::optional<OptionsProblem> find_problem(const ExportOptions& options) {
  const bool records = !options.tracks.empty() || !options.poses.empty();
  if (records == !options.markers.empty())
    return OptionsProblem{"input", "give --tracks and/or --poses, or --markers"};
  if (options.c3d.empty() && options.trc.empty() && options.csv.empty() && options.bodies_csv.empty())
    return OptionsProblem{"output", "give at least one of --c3d, --trc, --csv, --bodies-csv"};
  if (!options.markers.empty() && !options.bodies_csv.empty())
    return OptionsProblem{"--bodies-csv", "needs --poses"};
  return std::nullopt;
}

MarkerFileFormat marker_file_format(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".c3d" ? MarkerFileFormat::kC3d : MarkerFileFormat::kTrc;
}

ExportSummary run_export(const ExportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Exported data;
  if (!options.markers.empty()) {
    data.markers = marker_file_format(options.markers) == MarkerFileFormat::kC3d ? load_c3d(options.markers)
                                                                                 : load_trc(options.markers);
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
  ExportSummary summary;
  summary.frames = data.markers.frame_count();
  summary.markers = data.markers.marker_count();
  summary.bodies = data.bodies.body_count();
  summary.rate_hz = data.markers.data_rate_hz;
  summary.skipped_records = data.skipped;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

std::string summary_line(const ExportSummary& summary) {
  char line[256];
  std::snprintf(
      line, sizeof line,
      "{\"frames\": %zu, \"markers\": %zu, \"bodies\": %zu, \"rate_hz\": %.6g, \"skipped_records\": "
      "%zu, \"seconds\": %.3f}",
      summary.frames, summary.markers, summary.bodies, summary.rate_hz, summary.skipped_records,
      summary.seconds);
  return line;
}

}  // namespace panoptes::export_job
