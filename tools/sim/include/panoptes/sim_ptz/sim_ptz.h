// SPDX-License-Identifier: Apache-2.0
// panoptes_sim ptz: a simulated pan/tilt/zoom camera driven by recorded commands (docs/ptz.md).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "panoptes/time.h"

namespace panoptes::sim_tool {

struct PtzRunOptions {
  std::string scene;
  std::string ptz;
  std::string commands;
  std::string marker;
  std::string offset = "0,0,0";
  double skip_s = 1.0;
  std::string out_frames;
  double frames_every_s = 0.5;
  double frame_scale = 0.25;
  std::string summary_json;
  TimeNs epoch_ns = 1'700'000'000'000'000'000;
};

// Adds the subcommand's options to `app`; run_ptz runs it (exit code: 0, 2 on bad input).
CLI::App* add_ptz_subcommand(CLI::App& app, PtzRunOptions& options);
int run_ptz(const PtzRunOptions& options);

}  // namespace panoptes::sim_tool
