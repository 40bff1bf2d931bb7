// SPDX-License-Identifier: Apache-2.0
// What panoptes_ctl does (docs/camera_node.md), apart from its command line: commands to running
// camera nodes over DDS (one, or a script of them), their CameraStatus as JSON lines, a preview
// image, and predicted search windows for testing the guided search.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/ctl_actions/body_create.h"
#include "panoptes/dds/security.h"

namespace panoptes::msg {
class CameraStatus;
}

namespace panoptes::ctl {

struct CtlOptions {
  std::string dds_profile;
  dds::SecurityOptions security;
  double timeout_s = 10;
  // command
  std::string target;
  std::string command;
  std::vector<std::string> arguments;
  // script: the script file is `out`
  // status / preview / predict
  std::string camera;
  int count = 1;
  std::string out;
  int width = 320;
  std::vector<double> window;  // predict: x y half_width half_height (px)
  double duration_s = 5;
  double rate_hz = 100;
  // body create: the body and how many frames of positions to average
  BodyRequest body;
  int body_frames = 30;
};

enum class Action { kCommand, kScript, kStatus, kPreview, kPredict, kBodyCreate };

// Runs `action` and returns the exit code: 0, 1 for a failure on the bus (no node listening, no
// reply in time, no estimator frames), 2 for a bad script or a body that cannot be made (ConfigError). Throws
// ConfigError for input refused before joining the bus (DDS Security files, PANOPTES_DOMAIN); any other
// failure is rethrown as std::runtime_error (a run-time failure). Stops early when a stop is requested
// (install_stop_handlers).
int run_action(Action action, const CtlOptions& options);

// The words of each line of a script, '#' starting a comment; empty lines stay (numbering).
std::vector<std::vector<std::string>> read_script_lines(std::istream& file);

// A script's "sleep <seconds>" or "wait_nodes <nodes> <seconds>" line.
struct ScriptPause {
  bool wait_nodes = false;  // until `nodes` camera nodes listen for commands, at most `seconds`
  int nodes = 1;
  double seconds = 0;
};

// Whether a script line (its words) is a pause: its first word is "sleep" or "wait_nodes".
bool is_pause(const std::vector<std::string>& tokens);

// The pause `tokens` (is_pause) describe, or nullopt when malformed (see pause_usage).
std::optional<ScriptPause> parse_pause(const std::vector<std::string>& tokens);

// What a pause line of this kind should look like: "sleep <seconds>" or
// "wait_nodes <nodes >= 1> <seconds>".
std::string pause_usage(const std::vector<std::string>& tokens);

// One CameraStatus as the JSON object `panoptes_ctl status` prints on one line.
nlohmann::json status_json(const msg::CameraStatus& status);

}  // namespace panoptes::ctl
