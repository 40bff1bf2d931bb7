// SPDX-License-Identifier: Apache-2.0
// The console's calibration page runs docs/calibration.md's steps 2-4 as the CLI does: it starts
// `estimator_node calibrate capture` (the wand, later the wand on the floor), stops it with
// SIGINT, runs `calibrate solve` and `calibrate world --wand-floor`, and hands the page each
// step's log, the solve's report (report.json, report.txt, the plots) and the world frame's
// summary. Live coverage comes from the features the console already receives (ConsoleState).
// Only fixed argument lists are run: the page chooses an action, a wand definition and a floor
// offset, all checked by the gate; file names are the workflow's own. With the estimator's
// calibration file (panoptes_console --calibration) it also lists that file's versions and accepts
// or reverts one (docs/continuous_calibration.md, "A changed file").
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "panoptes/console/command_gate.h"
#include "panoptes/console/console_state.h"

namespace panoptes::console {

struct CalibrationWorkflowOptions {
  std::filesystem::path estimator_node;  // the program that runs the steps
  std::filesystem::path directory;       // wand.jsonl, floor.jsonl, calibration.yaml and its report
  std::string cameras_file;              // intrinsics for the solve ("" refuses the solve, naming the option)
  std::string dds_profile;               // passed to the captures
  // The estimator's calibration file ("": none): the page lists its versions and accepts or reverts
  // them (panoptes/calibration_history.h); a running estimator_node reloads the file.
  std::filesystem::path calibration_file;
};

class CalibrationWorkflow {
 public:
  CalibrationWorkflow(CalibrationWorkflowOptions options, ConsoleState& state);
  ~CalibrationWorkflow();  // a running step is stopped (SIGINT, then SIGKILL after 3 s)
  CalibrationWorkflow(const CalibrationWorkflow&) = delete;
  CalibrationWorkflow& operator=(const CalibrationWorkflow&) = delete;

  // Starts the step, or accepts or reverts a version at once; "" when it started or was applied,
  // else why not (another step running, no wand capture yet, no cameras file, no such version).
  // Thread-safe.
  std::string handle(const CalibrationRequest& request);
  // Reaps a finished step and publishes the job to the state; call a few times a second.
  void poll();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace panoptes::console
