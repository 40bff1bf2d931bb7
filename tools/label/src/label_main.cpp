// SPDX-License-Identifier: Apache-2.0
// panoptes_label: marker sets on people (docs/marker_sets.md). `model` builds a subject model from
// a static trial, or from an already-labelled dynamic one. The work is panoptes_label_job's
// (panoptes/label_job/label_job.h); this is its command line.
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "angles_command.h"
#include "panoptes/cli.h"
#include "panoptes/label_job/label_job.h"
#include "panoptes/process.h"

using panoptes::label_job::ModelCommandOptions;

static int run_main(int argc, char** argv) {
  CLI::App app{"panoptes_label: named markers on people from a marker set (docs/marker_sets.md)",
               "panoptes_label"};
  app.require_subcommand(1);
  ModelCommandOptions options;
  CLI::App* model = app.add_subcommand("model", "build a subject model from a static trial");
  model->add_option("--static", options.static_trial, "static trial: a .trc or .c3d file")
      ->check(CLI::ExistingFile);
  model
      ->add_option(
          "--labelled", options.labelled,
          "or train from an already-labelled dynamic trial (.trc or .c3d): calibration-only markers may be "
          "absent, tolerances cover the distances' ranges")
      ->check(CLI::ExistingFile);
  model->add_option("--frames", options.frames, "FIRST:LAST: only frames FIRST (0-based) to LAST (excluded)");
  model->add_option("--markerset", options.marker_set, "marker set YAML (deploy/markersets/)")
      ->required()
      ->check(CLI::ExistingFile);
  model->add_option("--out", options.out, "subject model YAML to write")->required();
  model->add_option("--subject", options.subject,
                    "subject name (default: the static file's name without extension)");
  model->add_option("--sigmas", options.sigmas, "distance tolerance in standard deviations")
      ->capture_default_str()
      ->check(panoptes::positive_number());
  model->add_option("--min-tolerance-mm", options.min_tolerance_mm, "smallest distance tolerance, mm")
      ->capture_default_str()
      ->check(panoptes::positive_number());
  model->add_option("--still-mm", options.still_mm, "a marker spreading more (RMS) is flagged as moved, mm")
      ->capture_default_str()
      ->check(panoptes::positive_number());
  panoptes::label_job::AnglesCommandOptions angles_options;
  CLI::App* angles = panoptes::label_job::add_angles_command(app, angles_options);
  const auto exit = panoptes::parse_command_line(app, argc, argv, [&] {
    if (!model->parsed()) return;
    if (const auto problem = panoptes::label_job::find_problem(options)) throw CLI::ValidationError(*problem);
  });
  if (exit) return *exit;
  if (angles->parsed()) return panoptes::label_job::run_angles_command(angles_options);
  const auto subject = panoptes::label_job::run_model(options);
  std::printf("%s", panoptes::label_job::model_report(subject).c_str());
  std::printf("wrote %s\n%s\n", options.out.c_str(),
              panoptes::label_job::model_summary_line(subject).c_str());
  return panoptes::kExitOk;
}

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_label", [&] { return run_main(argc, argv); });
}
