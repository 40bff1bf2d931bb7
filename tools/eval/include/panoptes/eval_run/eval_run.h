// SPDX-License-Identifier: Apache-2.0
// What panoptes_eval does (docs/estimator.md, "Evaluation"; docs/bodies.md), apart from its
// command line: Track and Pose JSON Lines judged against a simulator scene's ground truth, and
// the requirements (--require-*) they do not meet.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/eval/evaluation.h"

namespace panoptes::eval_run {

struct EvalOptions {
  std::string scene_file;
  std::string tracks_file;
  std::string poses_file;
  std::string summary_json;
  std::string plot_file;
  std::string plot_title;
  std::size_t plot_markers = 6;
  long long epoch_ns = 1'700'000'000'000'000'000LL;
  double warmup_s = 1.0;
  std::optional<double> until_s;  // judge up to this scene time (none: the scene's end)
  double match_distance_m = 0.02;
  double trackable_window_s = 0.1;
  bool every_frame = false;  // judge every camera frame, not only the records' stamps
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

// The pose requirements of `options` that `evaluation` does not meet, one line each.
std::vector<std::string> pose_failures(const estimator::PoseEvaluation& evaluation,
                                       const EvalOptions& options);

// The track requirements of `options` that `evaluation` does not meet, one line each (no judged
// instant at all is always a failure).
std::vector<std::string> track_failures(const estimator::Evaluation& evaluation, const EvalOptions& options);

// "<first>; <second>; ...".
std::string join_failures(const std::vector<std::string>& failures);

// Loads the scene, evaluates the poses and then the tracks file (whichever are given), printing
// each summary on stdout, writing --summary-json and --plot; malformed lines are reported on
// stderr and skipped. Returns the requirements not met (empty: all met). Throws on an unreadable
// scene or file, or an output that cannot be written.
std::vector<std::string> run_eval(const EvalOptions& options);

}  // namespace panoptes::eval_run
