// SPDX-License-Identifier: Apache-2.0
// panoptes_eval: compares Track JSONL with the ground truth of a simulator scene.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/estimator/evaluation.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/simulator.h"

int main(int argc, char** argv) {
  std::string scene_file;
  std::string tracks_file;
  std::string summary_json;
  long long epoch_ns = 1'700'000'000'000'000'000LL;
  double warmup_s = 1.0;
  double match_distance_m = 0.02;
  CLI::App app{"panoptes_eval: accuracy of tracks against simulator ground truth", "panoptes_eval"};
  app.add_option("--scene", scene_file, "simulator scene YAML that produced the features")->required();
  app.add_option("--tracks", tracks_file, "Track JSONL written by estimator_node --out-tracks")->required();
  app.add_option("--epoch-ns", epoch_ns, "absolute stamp of scene time 0 (panoptes_sim's default)")
      ->capture_default_str();
  app.add_option("--warmup", warmup_s, "seconds at the start that are not judged")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--match-distance", match_distance_m, "metres within which a track observes a marker")
      ->check(CLI::PositiveNumber);
  app.add_option("--summary-json", summary_json, "write the evaluation as JSON to this file");
  double require_rmse_mm = 0;
  double require_tracked = 0;
  bool require_no_switches = false;
  app.add_option("--require-rmse-mm", require_rmse_mm, "exit 1 unless every marker's RMSE is below this (mm)")
      ->check(CLI::PositiveNumber);
  app.add_option("--require-tracked", require_tracked,
                 "exit 1 unless every marker is tracked this fraction of the time")
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--require-no-id-switches", require_no_switches, "exit 1 if any marker changed track id");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  try {
    const auto scene = panoptes::Scene::load(scene_file);
    std::vector<std::string> errors;
    const auto tracks = panoptes::read_tracks(tracks_file, &errors);
    if (!errors.empty())
      std::fprintf(stderr, "panoptes_eval: skipped %zu malformed lines, first: %s\n", errors.size(),
                   errors[0].c_str());
    panoptes::estimator::EvaluationOptions options;
    options.epoch_ns = epoch_ns;
    options.warmup_ns = panoptes::seconds_to_ns(warmup_s);
    options.match_distance_m = match_distance_m;
    const auto evaluation = panoptes::estimator::evaluate(scene, tracks, options);
    std::cout << evaluation.summary();
    if (!summary_json.empty()) {
      std::ofstream out(summary_json);
      if (!out) throw std::runtime_error(summary_json + ": cannot open for writing");
      out << evaluation.to_json() << "\n";
    }
    bool pass = evaluation.instants > 0;
    if (require_rmse_mm > 0 && evaluation.worst_marker_rmse_m * 1e3 >= require_rmse_mm) pass = false;
    if (require_tracked > 0 && evaluation.min_tracked_fraction < require_tracked) pass = false;
    if (require_no_switches && evaluation.id_switch_count > 0) pass = false;
    if (!pass) {
      std::fprintf(stderr, "panoptes_eval: requirements not met\n");
      return panoptes::kExitFailure;
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_eval: %s\n", error.what());
    return panoptes::kExitBadInput;
  }
  return panoptes::kExitOk;
}
