// SPDX-License-Identifier: Apache-2.0
// The PTZ camera file (docs/ptz.md): angles in degrees, latency in milliseconds.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "panoptes/ptz/ptz.h"

namespace panoptes::ptz {

// Reads and validates a PTZ model; throws ConfigError naming the file and the key (a missing or
// unknown key, a value out of range, an unusable model as model_problem() explains it).
PtzModel load_ptz_model(const std::filesystem::path& path);

// A command as one JSON line: {"issued_ns", "pan", "tilt", "pan_rate", "tilt_rate", "fov"}
// (radians, rad/s). The parser returns nullopt (with the reason in `error`) for a line that is not
// such an object with finite values.
std::string command_to_json(const PtzCommand& command);
std::optional<PtzCommand> command_from_json(const std::string& line, std::string& error);

}  // namespace panoptes::ptz
