// SPDX-License-Identifier: Apache-2.0
// panoptes_label: marker sets on people (docs/marker_sets.md). `model` builds a subject model from
// a static trial, or from an already-labelled dynamic one; `run` labels a trial's tracks offline
// and fills gaps. The work is panoptes_label_job's (panoptes/label_job/label_job.h); this is its
// command line.
#include <cstdio>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "angles_command.h"
#include "panoptes/cli.h"
#include "panoptes/label_job/label_job.h"
#include "panoptes/process.h"

using panoptes::label_job::ModelCommandOptions;
using panoptes::label_job::RunCommandOptions;

static void add_run_options(CLI::App& run, RunCommandOptions& options) {
  run.add_option("--tracks", options.tracks,
                 "the trial's tracks: estimator_node --out-tracks JSON Lines, or a .c3d/.trc file (its names "
                 "are not read)")
      ->check(CLI::ExistingFile);
  run.add_option(
         "--in-recording", options.in_recording,
         "or an MCAP recording (panoptes_record): the tracks of its /panoptes/frames as published live")
      ->check(CLI::ExistingFile);
  run.add_option("--subjects", options.subjects, "subject model YAML (panoptes_label model), one per subject")
      ->required()
      ->check(CLI::ExistingFile);
  run.add_option("--out", options.out, "labelled trajectories to write: .c3d, .trc or .csv")->required();
  run.add_option("--report", options.report, "also write the report as JSON here");
  run.add_option("--max-gap-s", options.max_gap_s, "longest gap filled, seconds")->capture_default_str();
  run.add_option("--fill", options.fill,
                 "gap filling: pattern (from how the trial's markers move together; relational where "
                 "too few frames show them), relational (rigid body from the segment's other markers, "
                 "spline where they are missing), spline, linear or none")
      ->capture_default_str();
  run.add_option("--rate-hz", options.rate_hz, "sample rate for JSON Lines tracks (resampled)")
      ->capture_default_str()
      ->check(panoptes::positive_number());
  run.add_option("--soft-segments", options.soft_segments,
                 "segments whose markers move against each other (wider tolerances)")
      ->capture_default_str();
}

static int label_trial(const RunCommandOptions& options) {
  const auto summary = panoptes::label_job::run_labelling(options);
  std::printf("%s", panoptes::label_job::run_report(options, summary).c_str());
  std::printf("wrote %s\n%s\n", options.out.c_str(),
              panoptes::label_job::run_report_json(options, summary).c_str());
  return panoptes::kExitOk;
}

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
  RunCommandOptions run_options;
  CLI::App* run = app.add_subcommand(
      "run", "label a trial's tracks offline (forward and backward), fill gaps, write them");
  add_run_options(*run, run_options);
  panoptes::label_job::AnglesCommandOptions angles_options;
  CLI::App* angles = panoptes::label_job::add_angles_command(app, angles_options);
  const auto exit = panoptes::parse_command_line(app, argc, argv, [&] {
    std::optional<std::string> problem;
    if (run->parsed()) {
      problem = panoptes::label_job::find_problem(run_options);
    } else if (model->parsed()) {
      problem = panoptes::label_job::find_problem(options);
    }
    if (problem) throw CLI::ValidationError(*problem);
  });
  if (exit) return *exit;
  if (run->parsed()) return label_trial(run_options);
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
