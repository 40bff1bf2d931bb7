// SPDX-License-Identifier: Apache-2.0
// panoptes_eval: compares Track and Pose JSONL with the ground truth of a simulator scene
// (docs/estimator.md, "Evaluation"; docs/bodies.md).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "eval_plot.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/eval/evaluation.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/jsonl.h"
#include "panoptes/simulator.h"

int main(int argc, char** argv) {
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
  CLI::App app{"panoptes_eval: accuracy of tracks against simulator ground truth", "panoptes_eval"};
  app.add_option("--scene", scene_file, "simulator scene YAML that produced the features")->required();
  app.add_option("--tracks", tracks_file, "Track JSONL written by estimator_node --out-tracks");
  app.add_option("--poses", poses_file, "Pose JSONL written by estimator_node --out-poses");
  double require_pose_rmse_mm = 0, require_pose_rmse_deg = 0, require_pose_tracked = 0;
  bool require_no_wrong_poses = false;
  app.add_option("--require-pose-rmse-mm", require_pose_rmse_mm,
                 "exit 1 unless every body's position RMSE is below this");
  app.add_option("--require-pose-rmse-deg", require_pose_rmse_deg,
                 "exit 1 unless every body's orientation RMSE is below this");
  app.add_option("--require-pose-tracked", require_pose_tracked,
                 "exit 1 unless every body is tracked this fraction of the time")
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--require-no-wrong-poses", require_no_wrong_poses,
               "exit 1 if any pose is off by > 2 cm or > 5 degrees");
  app.add_option("--epoch-ns", epoch_ns, "absolute stamp of scene time 0 (panoptes_sim's default)")
      ->capture_default_str();
  app.add_option("--warmup", warmup_s, "seconds at the start that are not judged")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--match-distance", match_distance_m, "metres within which a track observes a marker")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--trackable-window", trackable_window_s,
                 "seconds: a marker shown by 2 cameras within this is trackable")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--summary-json", summary_json, "write the evaluation as JSON to this file");
  app.add_option("--plot", plot_file,
                 "write a PNG of the error over time (worst markers, ID switches, gaps)");
  app.add_option("--plot-markers", plot_markers, "markers drawn individually in the plot")
      ->capture_default_str()
      ->check(CLI::Range(1, 10));
  app.add_option("--plot-title", plot_title, "plot title (default: the tracks file)");
  double require_rmse_mm = 0;
  double require_tracked = 0;
  double require_coverage = 0;
  bool require_no_switches = false;
  int require_max_switches = -1;
  double require_max_false_fraction = -1;
  app.add_option("--require-rmse-mm", require_rmse_mm, "exit 1 unless every marker's RMSE is below this (mm)")
      ->check(CLI::PositiveNumber);
  app.add_option("--require-tracked", require_tracked,
                 "exit 1 unless every marker is tracked this fraction of the time")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--require-coverage", require_coverage,
                 "exit 1 unless this fraction of the trackable marker-time is tracked")
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--require-no-id-switches", require_no_switches, "exit 1 if any marker changed track id");
  app.add_option("--require-max-id-switches", require_max_switches, "exit 1 if there are more ID switches")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--require-max-false-fraction", require_max_false_fraction,
                 "exit 1 if a larger fraction of the track records matches no marker")
      ->check(CLI::Range(0.0, 1.0));
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (tracks_file.empty() && poses_file.empty())
          throw CLI::ValidationError("give --tracks and/or --poses");
      }))
    return *exit_code;
  // Reads a JSONL file, reporting (not failing on) malformed lines.
  const auto read_reporting = [](const std::string& file, auto reader) {
    std::vector<std::string> errors;
    auto records = reader(file, &errors);
    if (!errors.empty())
      std::fprintf(stderr, "panoptes_eval: skipped %zu malformed lines, first: %s\n", errors.size(),
                   errors[0].c_str());
    return records;
  };
  const auto base_options = [&] {
    panoptes::estimator::EvaluationOptions options;
    options.epoch_ns = epoch_ns;
    options.warmup_ns = panoptes::seconds_to_ns(warmup_s);
    return options;
  };
  try {
    const auto scene = panoptes::Scene::load(scene_file);
    std::vector<std::string> failures;
    if (!poses_file.empty()) {
      const auto poses = read_reporting(poses_file, panoptes::read_poses);
      const auto options = base_options();
      const auto evaluation = panoptes::estimator::evaluate_poses(scene, poses, options);
      std::cout << evaluation.summary();
      if (!summary_json.empty() && tracks_file.empty()) {
        std::ofstream out(summary_json);
        if (!out) throw std::runtime_error(summary_json + ": cannot open for writing");
        out << evaluation.to_json() << "\n";
      }
      for (const auto& e : evaluation.bodies) {
        if (require_pose_rmse_mm > 0 && !(e.rmse_m * 1e3 < require_pose_rmse_mm))
          failures.push_back(e.body + " RMSE " + std::to_string(e.rmse_m * 1e3) + " mm");
        if (require_pose_rmse_deg > 0 && !(e.rmse_deg < require_pose_rmse_deg))
          failures.push_back(e.body + " RMSE " + std::to_string(e.rmse_deg) + " deg");
        if (require_pose_tracked > 0 && e.tracked_fraction < require_pose_tracked)
          failures.push_back(e.body + " tracked " + std::to_string(e.tracked_fraction));
        if (require_no_wrong_poses && e.wrong > 0)
          failures.push_back(e.body + " " + std::to_string(e.wrong) + " wrong poses");
      }
    }
    if (!tracks_file.empty()) {
      const auto tracks = read_reporting(tracks_file, panoptes::read_tracks);
      auto options = base_options();
      options.match_distance_m = match_distance_m;
      options.trackable_window_ns = panoptes::seconds_to_ns(trackable_window_s);
      options.keep_series = !plot_file.empty();
      const auto evaluation = panoptes::estimator::evaluate(scene, tracks, options);
      std::cout << evaluation.summary();
      if (!summary_json.empty()) {
        std::ofstream out(summary_json);
        if (!out) throw std::runtime_error(summary_json + ": cannot open for writing");
        out << evaluation.to_json() << "\n";
      }
      if (!plot_file.empty()) {
        panoptes::estimator::PlotOptions plot;
        plot.worst_markers = plot_markers;
        plot.title = plot_title.empty() ? "panoptes_eval: " + tracks_file : plot_title;
        panoptes::estimator::write_error_plot(evaluation, plot, plot_file);
      }

      if (evaluation.instants == 0) failures.push_back("no track records to judge");
      if (require_rmse_mm > 0 && evaluation.worst_marker_rmse_m * 1e3 >= require_rmse_mm)
        failures.push_back("worst marker RMSE " + std::to_string(evaluation.worst_marker_rmse_m * 1e3) +
                           " mm");
      if (require_tracked > 0 && evaluation.min_tracked_fraction < require_tracked)
        failures.push_back("min tracked fraction " + std::to_string(evaluation.min_tracked_fraction));
      if (require_coverage > 0 && evaluation.coverage() < require_coverage)
        failures.push_back("coverage " + std::to_string(evaluation.coverage()));
      if (require_no_switches && evaluation.id_switch_count > 0)
        failures.push_back(std::to_string(evaluation.id_switch_count) + " ID switches");
      if (require_max_switches >= 0 &&
          evaluation.id_switch_count > static_cast<std::size_t>(require_max_switches))
        failures.push_back(std::to_string(evaluation.id_switch_count) + " ID switches");
      if (require_max_false_fraction >= 0 && evaluation.false_record_fraction() > require_max_false_fraction)
        failures.push_back("false record fraction " + std::to_string(evaluation.false_record_fraction()));
    }
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
