// SPDX-License-Identifier: Apache-2.0
#include "node_control.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "panoptes/camera/detector.h"
#include "panoptes/camera/sources.h"

namespace panoptes::camera {

namespace {

double parse_number(const Command& command, std::size_t index, const char* what) {
  if (index >= command.arguments.size()) {
    throw std::invalid_argument(command.command + ": missing argument <" + what + ">");
  }
  const std::string& text = command.arguments[index];
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size() && std::isfinite(value)) return value;
  } catch (const std::exception&) {
  }
  throw std::invalid_argument(command.command + ": <" + what + "> '" + text + "' is not a number");
}

int parse_count(const Command& command, std::size_t index, const char* what, int fallback, int low,
                int high) {
  if (index >= command.arguments.size()) return fallback;
  const double value = parse_number(command, index, what);
  if (value != std::floor(value) || value < low || value > high) {
    throw std::invalid_argument(command.command + ": <" + what + "> must be a whole number in [" +
                                std::to_string(low) + ", " + std::to_string(high) + "]");
  }
  return static_cast<int>(value);
}

std::string joined(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& word : words) text += (text.empty() ? "" : " ") + word;
  return text;
}

}  // namespace

CommandHandler::CommandHandler(std::string camera_id, Detector& detector, FrameSource& source)
    : camera_id_(std::move(camera_id)), detector_(detector), source_(source) {}

bool CommandHandler::addressed_to_me(const Command& command) const {
  return command.target.empty() || command.target == "*" || command.target == camera_id_;
}

const char* CommandHandler::usage() {
  return "set_threshold <T_a> [<T_r>] | set_exposure <us> | set_gain <dB> | set_frame_rate <Hz> | "
         "capture_background [<frames>] | clear_background | add_mask rect <x> <y> <w> <h> | "
         "add_mask poly <x1> <y1> <x2> <y2> <x3> <y3> ... | clear_masks | preview [<max width>] | restart";
}

std::string CommandHandler::apply(const Command& command, CommandEffects& effects) {
  const auto control = [&](Control which, const char* what) {
    const std::string error = source_.set_control(which, parse_number(command, 0, what));
    if (!error.empty()) throw std::invalid_argument(command.command + ": " + error);
  };
  try {
    const std::string& name = command.command;
    if (name == "set_threshold") {
      const int absolute = parse_count(command, 0, "T_a", -1, 0, 65535);
      if (absolute < 0) throw std::invalid_argument("set_threshold: missing argument <T_a>");
      detector_.set_threshold(absolute);
      if (command.arguments.size() > 1)
        detector_.set_relative_threshold(parse_count(command, 1, "T_r", 0, 0, 65535));
    } else if (name == "set_exposure") {
      control(Control::kExposureUs, "us");
    } else if (name == "set_gain") {
      control(Control::kGainDb, "dB");
    } else if (name == "set_frame_rate") {
      control(Control::kFrameRateHz, "Hz");
    } else if (name == "capture_background") {
      detector_.capture_background(parse_count(command, 0, "frames", 1, 1, 1000));
    } else if (name == "clear_background") {
      detector_.clear_background();
    } else if (name == "add_mask" || name == "set_mask") {
      detector_.add_mask(MaskRegion::parse(joined(command.arguments)));
    } else if (name == "clear_masks") {
      detector_.clear_masks();
    } else if (name == "preview") {
      effects.preview_requests = 1;
      effects.preview_max_width = parse_count(command, 0, "max width", 320, 16, 4096);
    } else if (name == "restart") {
      source_.restart();
    } else {
      throw std::invalid_argument("unknown command '" + name + "' (expected " + usage() + ")");
    }
    ++counters_["command_" + name];
    return {};
  } catch (const std::exception& error) {
    ++counters_["bad_command"];
    return error.what();
  }
}

Image make_preview(const Image& image, int max_width) {
  if (image.width <= 0 || image.height <= 0) return Image();
  const int factor = std::max(1, (image.width + max_width - 1) / std::max(1, max_width));
  const int width = image.width / factor, height = image.height / factor;
  Image preview(std::max(1, width), std::max(1, height), 8);
  const int shift = std::max(0, image.bits - 8);
  for (int y = 0; y < preview.height; ++y) {
    for (int x = 0; x < preview.width; ++x) {
      unsigned long sum = 0;
      for (int dy = 0; dy < factor; ++dy) {
        const int sy = std::min(image.height - 1, y * factor + dy);
        for (int dx = 0; dx < factor; ++dx) {
          const int sx = std::min(image.width - 1, x * factor + dx);
          sum += image.bytes_per_pixel() == 1 ? image.row8(sy)[sx] : (image.row16(sy)[sx] >> shift);
        }
      }
      preview.row8(y)[x] = static_cast<std::uint8_t>(
          std::min<unsigned long>(255, sum / (static_cast<unsigned long>(factor) * factor)));
    }
  }
  return preview;
}

}  // namespace panoptes::camera
