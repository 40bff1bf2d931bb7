// SPDX-License-Identifier: Apache-2.0
// What panoptes_demo does (docs/quickstart.md), apart from its command line: one camera_node per
// simulated camera and one estimator_node over Fast DDS, the tracks watched as an application
// would, and the accuracy against the scene's ground truth judged against the demo's targets.
#pragma once

#include <filesystem>
#include <string>

#include "panoptes/eval/evaluation.h"

namespace panoptes::demo_run {

struct DemoOptions {
  std::filesystem::path bin_dir;  // where camera_node and estimator_node are
  std::string scene_file;
  double duration_s = 20.0;     // seconds of tracking; cut to the scene's duration
  std::string summary_json;     // empty: none
  std::string dds_profile;      // empty: the bus's default ($PANOPTES_DDS_PROFILE or loopback)
  std::string log_dir;          // empty: a temporary folder
  bool check = false;           // exit 1 unless the targets are met
  std::string frames = "auto";  // the estimator's --frames (docs/frames.md)
};

// The demo's targets: every marker's RMSE < 2 mm, tracked >= 95% of the time, no ID switch, and
// at least one instant judged.
bool targets_met(const estimator::Evaluation& evaluation);

// The --summary-json document: the evaluation's JSON with the scene, duration, number of cameras
// and whether the targets were met.
std::string summary_json(const estimator::Evaluation& evaluation, const std::string& scene_file,
                         double duration_s, std::size_t cameras);

// Runs the demo and returns its exit code: 0, or 1 when a process failed, the summary could not be
// written or (with `check`) the targets were not met. Throws InputError for a scene that cannot
// be loaded. Stops early when a stop is requested (install_stop_handlers).
int run_demo(DemoOptions options);

}  // namespace panoptes::demo_run
