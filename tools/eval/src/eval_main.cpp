// SPDX-License-Identifier: Apache-2.0
// panoptes_eval: compares Track and Pose JSONL with the ground truth of a simulator scene
// (docs/estimator.md, "Evaluation"; docs/bodies.md). The work is panoptes_eval_run's
// (panoptes/eval_run/eval_run.h); this is its command line.
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/errors.h"
#include "panoptes/eval_run/eval_run.h"
#include "panoptes/process.h"

namespace {

using panoptes::eval_run::EvalOptions;

void add_options(CLI::App& app, EvalOptions& args) {
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--scene", args.scene_file, "simulator scene YAML that produced the features")->required();
  app.add_option("--tracks", args.tracks_file, "Track JSONL written by estimator_node --out-tracks");
  app.add_option("--poses", args.poses_file, "Pose JSONL written by estimator_node --out-poses");
  app.add_option("--require-pose-rmse-mm", args.require_pose_rmse_mm,
                 "exit 1 unless every body's position RMSE is below this")
      ->default_str("off");
  app.add_option("--require-pose-rmse-deg", args.require_pose_rmse_deg,
                 "exit 1 unless every body's orientation RMSE is below this")
      ->default_str("off");
  app.add_option("--require-pose-tracked", args.require_pose_tracked,
                 "exit 1 unless every body is tracked this fraction of the time")
      ->check(CLI::Range(0.0, 1.0))
      ->default_str("off");
  app.add_flag("--require-no-wrong-poses", args.require_no_wrong_poses,
               "exit 1 if any pose is off by > 2 cm or > 5 degrees");
  app.add_option("--epoch-ns", args.epoch_ns, "absolute stamp of scene time 0 (panoptes_sim's default)");
  app.add_option("--warmup", args.warmup_s, "seconds at the start that are not judged")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--until", args.until_s,
                 "judge scene time up to this many seconds (with --warmup: a window of the scene)")
      ->check(CLI::NonNegativeNumber)
      ->default_str("the scene's end");
  app.add_option("--match-distance", args.match_distance_m, "metres within which a track observes a marker")
      ->check(CLI::PositiveNumber);
  app.add_option("--trackable-window", args.trackable_window_s,
                 "seconds: a marker shown by 2 cameras within this is trackable")
      ->check(CLI::PositiveNumber);
  app.add_flag("--every-frame", args.every_frame,
               "judge every camera frame of the scene, also those at which no track was published (the "
               "tracks file has no line for them); default: only the records' stamps");
  app.add_option("--summary-json", args.summary_json, "write the evaluation as JSON to this file");
  app.add_option("--plot", args.plot_file,
                 "write a PNG of the error over time (worst markers, ID switches, gaps)");
  app.add_option("--plot-markers", args.plot_markers, "markers drawn individually in the plot")
      ->check(CLI::Range(1, 10));
  app.add_option("--plot-title", args.plot_title, "plot title")->default_str("the tracks file");
  app.add_option("--require-rmse-mm", args.require_rmse_mm,
                 "exit 1 unless every marker's RMSE is below this (mm)")
      ->check(CLI::PositiveNumber)
      ->default_str("off");
  app.add_option("--require-tracked", args.require_tracked,
                 "exit 1 unless every marker is tracked this fraction of the time")
      ->check(CLI::Range(0.0, 1.0))
      ->default_str("off");
  app.add_option("--require-coverage", args.require_coverage,
                 "exit 1 unless this fraction of the trackable marker-time is tracked")
      ->check(CLI::Range(0.0, 1.0))
      ->default_str("off");
  app.add_flag("--require-no-id-switches", args.require_no_switches, "exit 1 if any marker changed track id");
  app.add_option("--require-max-id-switches", args.require_max_switches,
                 "exit 1 if there are more ID switches")
      ->check(CLI::NonNegativeNumber)
      ->default_str("off");
  app.add_option("--require-max-false-fraction", args.require_max_false_fraction,
                 "exit 1 if a larger fraction of the track records matches no marker")
      ->check(CLI::Range(0.0, 1.0))
      ->default_str("off");
}

int run(int argc, char** argv) {
  EvalOptions args;
  CLI::App app{"panoptes_eval: accuracy of tracks against simulator ground truth", "panoptes_eval"};
  add_options(app, args);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (args.tracks_file.empty() && args.poses_file.empty())
          throw CLI::ValidationError("give --tracks and/or --poses");
      }))
    return *exit_code;
  // Every failure to read, evaluate or write is reported as the input's (exit 2).
  const std::vector<std::string> failures =
      panoptes::as_input_error([&] { return panoptes::eval_run::run_eval(args); });
  if (!failures.empty()) {
    std::fprintf(stderr, "panoptes_eval: requirements not met: %s\n",
                 panoptes::eval_run::join_failures(failures).c_str());
    return panoptes::kExitFailure;
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_eval", [&] { return run(argc, argv); });
}
