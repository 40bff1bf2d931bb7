// SPDX-License-Identifier: Apache-2.0
#include "panoptes/eval_run/eval_run.h"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "panoptes/eval_plot/eval_plot.h"
#include "panoptes/jsonl.h"
#include "panoptes/records.h"
#include "panoptes/simulator.h"

namespace panoptes::eval_run {
namespace {

using estimator::Evaluation;
using estimator::EvaluationOptions;

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

EvaluationOptions base_options(const EvalOptions& options) {
  EvaluationOptions evaluation;
  evaluation.epoch_ns = options.epoch_ns;
  evaluation.warmup_ns = seconds_to_ns(options.warmup_s);
  if (options.until_s) evaluation.until_ns = seconds_to_ns(*options.until_s);
  return evaluation;
}

// Evaluates the poses file; appends the requirements it does not meet to `failures`.
void judge_poses(const EvalOptions& options, const Scene& scene, std::vector<std::string>& failures) {
  const auto poses = read_reporting(options.poses_file, read_poses);
  const auto evaluation = estimator::evaluate_poses(scene, poses, base_options(options));
  std::cout << evaluation.summary();
  if (!options.summary_json.empty() && options.tracks_file.empty())
    write_summary(options.summary_json, evaluation.to_json());
  for (std::string& failure : pose_failures(evaluation, options)) failures.push_back(std::move(failure));
}

// Evaluates the tracks file (and plots it); appends the requirements it does not meet to `failures`.
void judge_tracks(const EvalOptions& options, const Scene& scene, std::vector<std::string>& failures) {
  const auto tracks = read_reporting(options.tracks_file, read_tracks);
  auto evaluation_options = base_options(options);
  evaluation_options.match_distance_m = options.match_distance_m;
  evaluation_options.trackable_window_ns = seconds_to_ns(options.trackable_window_s);
  evaluation_options.judge_every_frame = options.every_frame;
  evaluation_options.keep_series = !options.plot_file.empty();
  const Evaluation evaluation = estimator::evaluate(scene, tracks, evaluation_options);
  std::cout << evaluation.summary();
  if (!options.summary_json.empty()) write_summary(options.summary_json, evaluation.to_json());
  if (!options.plot_file.empty()) {
    estimator::PlotOptions plot;
    plot.worst_markers = options.plot_markers;
    plot.title = options.plot_title.empty() ? "panoptes_eval: " + options.tracks_file : options.plot_title;
    estimator::write_error_plot(evaluation, plot, options.plot_file);
  }
  for (std::string& failure : track_failures(evaluation, options)) failures.push_back(std::move(failure));
}

}  // namespace

std::vector<std::string> pose_failures(const estimator::PoseEvaluation& evaluation,
                                       const EvalOptions& options) {
  std::vector<std::string> failures;
  for (const auto& e : evaluation.bodies) {
    if (options.require_pose_rmse_mm > 0 && !(e.rmse_m * 1e3 < options.require_pose_rmse_mm))
      failures.push_back(e.body + " RMSE " + std::to_string(e.rmse_m * 1e3) + " mm");
    if (options.require_pose_rmse_deg > 0 && !(e.rmse_deg < options.require_pose_rmse_deg))
      failures.push_back(e.body + " RMSE " + std::to_string(e.rmse_deg) + " deg");
    if (options.require_pose_tracked > 0 && e.tracked_fraction < options.require_pose_tracked)
      failures.push_back(e.body + " tracked " + std::to_string(e.tracked_fraction));
    if (options.require_no_wrong_poses && e.wrong > 0)
      failures.push_back(e.body + " " + std::to_string(e.wrong) + " wrong poses");
  }
  return failures;
}

std::vector<std::string> track_failures(const estimator::Evaluation& evaluation, const EvalOptions& options) {
  std::vector<std::string> failures;
  if (evaluation.instants == 0) failures.push_back("no track records to judge");
  if (options.require_rmse_mm > 0 && evaluation.worst_marker_rmse_m * 1e3 >= options.require_rmse_mm)
    failures.push_back("worst marker RMSE " + std::to_string(evaluation.worst_marker_rmse_m * 1e3) + " mm");
  if (options.require_tracked > 0 && evaluation.min_tracked_fraction < options.require_tracked)
    failures.push_back("min tracked fraction " + std::to_string(evaluation.min_tracked_fraction));
  if (options.require_coverage > 0 && evaluation.coverage() < options.require_coverage)
    failures.push_back("coverage " + std::to_string(evaluation.coverage()));
  if (options.require_no_switches && evaluation.id_switch_count > 0)
    failures.push_back(std::to_string(evaluation.id_switch_count) + " ID switches");
  if (options.require_max_switches >= 0 &&
      evaluation.id_switch_count > static_cast<std::size_t>(options.require_max_switches))
    failures.push_back(std::to_string(evaluation.id_switch_count) + " ID switches");
  if (options.require_max_false_fraction >= 0 &&
      evaluation.false_record_fraction() > options.require_max_false_fraction)
    failures.push_back("false record fraction " + std::to_string(evaluation.false_record_fraction()));
  return failures;
}

std::string join_failures(const std::vector<std::string>& failures) {
  std::string reasons;
  for (const auto& failure : failures) reasons += (reasons.empty() ? "" : "; ") + failure;
  return reasons;
}

std::vector<std::string> run_eval(const EvalOptions& options) {
  const auto scene = Scene::load(options.scene_file);
  std::vector<std::string> failures;
  if (!options.poses_file.empty()) judge_poses(options, scene, failures);
  if (!options.tracks_file.empty()) judge_tracks(options, scene, failures);
  return failures;
}

}  // namespace panoptes::eval_run
