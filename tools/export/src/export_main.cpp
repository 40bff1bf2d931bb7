// SPDX-License-Identifier: Apache-2.0
// panoptes_export: the estimator's tracks and body poses (its JSON Lines outputs, estimator_node
// --out-tracks / --out-poses, or the MocapFrames of an MCAP recording as published live)
// re-sampled to a fixed rate and written as C3D, TRC and CSV; a recording's records also as JSON
// Lines; or a marker file (TRC, C3D) converted to the others. docs/recording.md, "Export".
// The work is panoptes_export_job's (panoptes/export_job/export_job.h); this is its command line.
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/export_job/export_job.h"
#include "panoptes/process.h"

using namespace panoptes;
using panoptes::export_job::ExportOptions;

static int run_main(int argc, char** argv) {
  CLI::App app{
      "panoptes_export: tracks and body poses to C3D, TRC and CSV at a fixed rate (docs/recording.md)",
      "panoptes_export"};
  ExportOptions options;
  app.add_option("--tracks", options.tracks, "tracks JSON Lines file (estimator_node --out-tracks)")
      ->check(CLI::ExistingFile);
  app.add_option("--poses", options.poses, "body poses JSON Lines file (estimator_node --out-poses)")
      ->check(CLI::ExistingFile);
  app.add_option("--markers", options.markers, "convert a marker file (.trc or .c3d) instead of records")
      ->check(CLI::ExistingFile);
  app.add_option("--in-recording", options.in_recording,
                 "an MCAP recording (panoptes_record): its MocapFrames as published live")
      ->check(CLI::ExistingFile);
  app.add_option_function<std::vector<std::string>>(
         "--out",
         [&](const std::vector<std::string>& paths) {
           for (const auto& path : paths)
             if (!export_job::set_output(options, path))
               throw CLI::ValidationError("--out", path + ": give a .c3d, .trc or .csv file");
         },
         "marker files by extension: .c3d, .trc, .csv")
      ->type_name("FILE");
  app.add_option("--out-tracks", options.out_tracks,
                 "with --in-recording: the track records as JSON Lines (as estimator_node --out-tracks)");
  app.add_option_function<std::string>(
         "--out-poses",
         [&](const std::string& path) {
           if (!export_job::set_poses_output(options, path))
             throw CLI::ValidationError("--out-poses", path + ": give a .jsonl or .csv file");
         },
         "with --in-recording: the pose records, .jsonl (as estimator_node --out-poses) or .csv (as "
         "--bodies-csv)")
      ->type_name("FILE");
  app.add_option("--c3d", options.c3d, "write markers (tracks, body origins) as C3D");
  app.add_option("--trc", options.trc, "write markers as TRC");
  app.add_option("--csv", options.csv, "write markers as CSV (metres)");
  app.add_option("--bodies-csv", options.bodies_csv, "write body poses as CSV with quaternions");
  auto* rate = app.add_option("--rate", options.rate_hz,
                              "output rate, Hz (a recording of fixed-rate frames: its own rate by default)");
  rate->capture_default_str()->check(positive_number());
  app.add_option("--max-gap-ms", options.max_gap_ms,
                 "updates further apart leave the samples between invalid, ms")
      ->capture_default_str()
      ->check(positive_number());
  app.add_option("--units", options.units, "units of the C3D and TRC files")
      ->capture_default_str()
      ->check(CLI::IsMember({"mm", "cm", "m"}));
  app.add_option_function<std::string>(
         "--up-axis", [&](const std::string& text) { options.up_axis = parse_up_axis(text, "--up-axis"); },
         "world up axis of the C3D, TRC and CSV files: z (as recorded) or y ((x, y, z) -> (x, z, -y))")
      ->default_str("z");
  app.add_flag("--include-tentative", options.include_tentative, "export tentative tracks too");
  app.add_flag("--no-body-points", options.no_body_points,
               "leave the bodies' origins out of the marker files");
  const auto exit = parse_command_line(app, argc, argv, [&] {
    options.rate_given = rate->count() > 0;
    if (const auto problem = export_job::find_problem(options))
      throw CLI::ValidationError(problem->option, problem->reason);
  });
  if (exit) return *exit;
  std::printf("%s\n", export_job::summary_line(export_job::run_export(options)).c_str());
  return kExitOk;
}

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_export", [&] { return run_main(argc, argv); });
}
