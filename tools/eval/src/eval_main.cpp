// SPDX-License-Identifier: Apache-2.0
// panoptes_eval: compares Track and Pose JSONL with the ground truth of a simulator scene
// (docs/estimator.md, "Evaluation"; docs/bodies.md).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/eval/evaluation.h"
#include "panoptes/eval_plot/eval_plot.h"
#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/simulator.h"

namespace {

using panoptes::estimator::Evaluation;
using panoptes::estimator::EvaluationOptions;

// The command line.
struct EvalArgs {
  std::string scene_file;
  std::string tracks_file;
  std::string poses_file;
  std::string summary_json;
  std::string plot_file;
  std::string plot_title;
  std::size_t plot_markers = 6;
  long long epoch_ns = 1'700'000'000'000'000'000LL;
  double warmup_s = 1.0;
  double match_distance_m = 0.02;
  double trackable_window_s = 0.1;
  // Requirements on poses; 0 (or false) = not required.
  double require_pose_rmse_mm = 0, require_pose_rmse_deg = 0, require_pose_tracked = 0;
  bool require_no_wrong_poses = false;
  // Requirements on tracks; 0, false or -1 = not required.
  double require_rmse_mm = 0;
  double require_tracked = 0;
  double require_coverage = 0;
  bool require_no_switches = false;
  int require_max_switches = -1;
  double require_max_false_fraction = -1;
};

void add_options(CLI::App& app, EvalArgs& args) {
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
  app.add_option("--match-distance", args.match_distance_m, "metres within which a track observes a marker")
      ->check(CLI::PositiveNumber);
  app.add_option("--trackable-window", args.trackable_window_s,
                 "seconds: a marker shown by 2 cameras within this is trackable")
      ->check(CLI::PositiveNumber);
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

// Reads a JSONL file, reporting (not failing on) malformed lines.
template <class Reader>
auto read_reporting(const std::string& file, Reader reader) {
  std::vector<std::string> errors;
  auto records = reader(file, &errors);
  if (!errors.empty())
    std::fprintf(stderr, "panoptes_eval: skipped %zu malformed lines, first: %s\n", errors.size(),
                 errors[0].c_str());
  return records;
}

void write_summary(const std::string& file, const std::string& json) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file + ": cannot open for writing");
  out << json << "\n";
}

EvaluationOptions base_options(const EvalArgs& args) {
  EvaluationOptions options;
  options.epoch_ns = args.epoch_ns;
  options.warmup_ns = panoptes::seconds_to_ns(args.warmup_s);
  return options;
}

// Evaluates the poses file; appends the requirements it does not meet to `failures`.
void judge_poses(const EvalArgs& args, const panoptes::Scene& scene, std::vector<std::string>& failures) {
  const auto poses = read_reporting(args.poses_file, panoptes::read_poses);
  const auto evaluation = panoptes::estimator::evaluate_poses(scene, poses, base_options(args));
  std::cout << evaluation.summary();
  if (!args.summary_json.empty() && args.tracks_file.empty())
    write_summary(args.summary_json, evaluation.to_json());
  for (const auto& e : evaluation.bodies) {
    if (args.require_pose_rmse_mm > 0 && !(e.rmse_m * 1e3 < args.require_pose_rmse_mm))
      failures.push_back(e.body + " RMSE " + std::to_string(e.rmse_m * 1e3) + " mm");
    if (args.require_pose_rmse_deg > 0 && !(e.rmse_deg < args.require_pose_rmse_deg))
      failures.push_back(e.body + " RMSE " + std::to_string(e.rmse_deg) + " deg");
    if (args.require_pose_tracked > 0 && e.tracked_fraction < args.require_pose_tracked)
      failures.push_back(e.body + " tracked " + std::to_string(e.tracked_fraction));
    if (args.require_no_wrong_poses && e.wrong > 0)
      failures.push_back(e.body + " " + std::to_string(e.wrong) + " wrong poses");
  }
}

// Evaluates the tracks file (and plots it); appends the requirements it does not meet to `failures`.
void judge_tracks(const EvalArgs& args, const panoptes::Scene& scene, std::vector<std::string>& failures) {
  const auto tracks = read_reporting(args.tracks_file, panoptes::read_tracks);
  auto options = base_options(args);
  options.match_distance_m = args.match_distance_m;
  options.trackable_window_ns = panoptes::seconds_to_ns(args.trackable_window_s);
  options.keep_series = !args.plot_file.empty();
  const Evaluation evaluation = panoptes::estimator::evaluate(scene, tracks, options);
  std::cout << evaluation.summary();
  if (!args.summary_json.empty()) write_summary(args.summary_json, evaluation.to_json());
  if (!args.plot_file.empty()) {
    panoptes::estimator::PlotOptions plot;
    plot.worst_markers = args.plot_markers;
    plot.title = args.plot_title.empty() ? "panoptes_eval: " + args.tracks_file : args.plot_title;
    panoptes::estimator::write_error_plot(evaluation, plot, args.plot_file);
  }

  if (evaluation.instants == 0) failures.push_back("no track records to judge");
  if (args.require_rmse_mm > 0 && evaluation.worst_marker_rmse_m * 1e3 >= args.require_rmse_mm)
    failures.push_back("worst marker RMSE " + std::to_string(evaluation.worst_marker_rmse_m * 1e3) + " mm");
  if (args.require_tracked > 0 && evaluation.min_tracked_fraction < args.require_tracked)
    failures.push_back("min tracked fraction " + std::to_string(evaluation.min_tracked_fraction));
  if (args.require_coverage > 0 && evaluation.coverage() < args.require_coverage)
    failures.push_back("coverage " + std::to_string(evaluation.coverage()));
  if (args.require_no_switches && evaluation.id_switch_count > 0)
    failures.push_back(std::to_string(evaluation.id_switch_count) + " ID switches");
  if (args.require_max_switches >= 0 &&
      evaluation.id_switch_count > static_cast<std::size_t>(args.require_max_switches))
    failures.push_back(std::to_string(evaluation.id_switch_count) + " ID switches");
  if (args.require_max_false_fraction >= 0 &&
      evaluation.false_record_fraction() > args.require_max_false_fraction)
    failures.push_back("false record fraction " + std::to_string(evaluation.false_record_fraction()));
}

int run(int argc, char** argv) {
  EvalArgs args;
  CLI::App app{"panoptes_eval: accuracy of tracks against simulator ground truth", "panoptes_eval"};
  add_options(app, args);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (args.tracks_file.empty() && args.poses_file.empty())
          throw CLI::ValidationError("give --tracks and/or --poses");
      }))
    return *exit_code;
  try {
    const auto scene = panoptes::Scene::load(args.scene_file);
    std::vector<std::string> failures;
    if (!args.poses_file.empty()) judge_poses(args, scene, failures);
    if (!args.tracks_file.empty()) judge_tracks(args, scene, failures);
    if (!failures.empty()) {
      std::string reasons;
      for (const auto& failure : failures) reasons += (reasons.empty() ? "" : "; ") + failure;
      std::fprintf(stderr, "panoptes_eval: requirements not met: %s\n", reasons.c_str());
      return panoptes::kExitFailure;
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_eval: %s\n", error.what());
    return panoptes::kExitBadInput;
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_eval", [&] { return run(argc, argv); });
}
