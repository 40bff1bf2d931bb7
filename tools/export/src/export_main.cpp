// SPDX-License-Identifier: Apache-2.0
// panoptes_export: the estimator's tracks and body poses (today its JSON Lines outputs,
// estimator_node --out-tracks / --out-poses) re-sampled to a fixed rate and written as C3D, TRC
// and CSV; or a marker file (TRC, C3D) converted to the others. docs/recording.md, "Export".
// The work is panoptes_export_job's (panoptes/export_job/export_job.h); this is its command line.
#include <cstdio>
#include <string>

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
