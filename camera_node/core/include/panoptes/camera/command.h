// SPDX-License-Identifier: Apache-2.0
// A command to camera_node as decoded from rt/panoptes/camera_command (applied between frames by
// CommandHandler, src/node_control.h), and what the node must do after it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace panoptes::camera {

struct Command {
  std::string target;  // camera id, or "" / "*" for every camera
  std::uint64_t seq = 0;
  std::string command;
  std::vector<std::string> arguments;
};

// What the node must do after a command that the handler cannot do itself.
struct CommandEffects {
  int preview_requests = 0;  // publish this many previews (one per following frame)
  int preview_max_width = 0;
};

}  // namespace panoptes::camera
