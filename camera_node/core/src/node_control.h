// SPDX-License-Identifier: Apache-2.0
// camera_node's command handling and preview images, free of DDS so they can be unit-tested:
// the node decodes rt/panoptes/camera_command into a Command and applies it between frames, so
// a command changes behaviour from the next frame on.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "panoptes/camera/command.h"
#include "panoptes/image.h"

namespace panoptes::camera {

class Detector;
class FrameSource;

class CommandHandler {
 public:
  CommandHandler(std::string camera_id, Detector& detector, FrameSource& source);

  // True if the command is addressed to this camera.
  bool addressed_to_me(const Command& command) const;
  // Applies a command addressed to this camera. Returns "" on success, otherwise a one-line
  // error naming the command and what was wrong (also counted by reason in counters()).
  std::string apply(const Command& command, CommandEffects& effects);
  const std::map<std::string, std::uint64_t>& counters() const { return counters_; }

  // The commands and their arguments, for --help and docs/camera_node.md.
  static const char* usage();

 private:
  std::string camera_id_;
  Detector& detector_;
  FrameSource& source_;
  std::map<std::string, std::uint64_t> counters_;
};

// A downscaled 8-bit copy of `image` at most `max_width` wide (block averages; 16-bit images are
// scaled to 8 bits by their significant bit depth).
Image make_preview(const Image& image, int max_width);

}  // namespace panoptes::camera
