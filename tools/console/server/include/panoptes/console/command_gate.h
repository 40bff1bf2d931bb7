// SPDX-License-Identifier: Apache-2.0
// The gate every browser command passes before it becomes a camera_command: the message's shape,
// the command name, its arguments and their ranges, the camera (seen on the bus, and the mask
// inside its image) and a per-client rate limit. A command that fails any check is rejected with
// a reason and a counter name, and never forwarded (docs/console.md, "Commands").
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/time.h"

namespace panoptes::console {

class ConsoleState;

struct CameraCommandRequest {
  std::int64_t request = 0;  // the browser's id for the reply
  std::string camera;
  std::string command;
  std::vector<std::string> arguments;  // as camera_node parses them (docs/camera_node.md)
};

struct Rejection {
  std::int64_t request = 0;
  std::string counter;  // bad_message | unknown_command | bad_arguments | out_of_range | unknown_camera |
                        // rate_limited | oversized
  std::string reason;
};

using GateResult = std::variant<CameraCommandRequest, Rejection>;

// The commands the console forwards, with their argument rules.
const std::vector<std::string>& console_commands();

// Checks a decoded {"type":"command", "id", "camera", "command", "args"} message. `image_size`
// bounds masks when the camera's resolution is known.
GateResult check_command(const nlohmann::json& message, bool camera_known,
                         const std::optional<std::pair<int, int>>& image_size);

// A recorder command from the page: {"type":"recorder", "id", "recorder", "command": "start" | "stop",
// "name"}. The name is a bare file name ending in .mcap (no directory: the recorder writes it next
// to its --out file, docs/recording.md); without one, start uses the recorder's --out.
struct RecorderCommandRequest {
  std::int64_t request = 0;
  std::string recorder;
  std::string command;
  std::string path;
};
using RecorderGateResult = std::variant<RecorderCommandRequest, Rejection>;
RecorderGateResult check_recorder_command(const nlohmann::json& message, bool recorder_known);

// A calibration workflow step from the page (docs/calibration.md's steps, run by the console):
// {"type":"calibration", "id", "action": "capture" | "floor_capture" | "stop" | "solve" | "world",
//  "wand": "0,0.18,0.5" (solve, world), "floor_offset": metres (world), "time_service": bool (captures)}.
struct CalibrationRequest {
  std::int64_t request = 0;
  std::string action;
  std::string wand;  // canonical: numbers in metres joined by ','
  double floor_offset_m = 0;
  bool time_service = false;
  int version = 0;  // accept | revert: the calibration file's version (1 and up)
};
using CalibrationGateResult = std::variant<CalibrationRequest, Rejection>;
CalibrationGateResult check_calibration_request(const nlohmann::json& message);

// A rigid body made from live tracks selected in the 3D view (docs/bodies.md, "Bodies from
// markers"): {"type":"body", "id", "name", "tracks": [3 to 64 track ids], "pivot": a track id or
// null (the centroid)}. The name: 1 to 64 letters, digits, '_', '-' or '.'. Whether the tracks are
// live and make a body is for the console's body maker (panoptes::ctl::select_tracks, make_body).
struct BodyCreateRequest {
  std::int64_t request = 0;
  std::string name;
  std::vector<std::int64_t> tracks;
  std::optional<std::int64_t> pivot;
};
using BodyGateResult = std::variant<BodyCreateRequest, Rejection>;
BodyGateResult check_body_request(const nlohmann::json& message);

// Token bucket: `rate` commands per second on average, at most `burst` at once.
class RateLimiter {
 public:
  RateLimiter(double rate_per_s, double burst) : rate_(rate_per_s), burst_(burst), tokens_(burst) {}
  bool allow(TimeNs now);

 private:
  double rate_;
  double burst_;
  double tokens_;
  TimeNs last_ns_ = 0;
};

}  // namespace panoptes::console
