// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera/node_clock.h"

#include <cmath>
#include <stdexcept>

#include "panoptes/simulator.h"

namespace panoptes::camera {

ClockSkew parse_clock_skew(const std::string& text) {
  if (text.empty()) return {};
  const auto bad = [&text](const std::string& why) {
    return std::invalid_argument("--clock-skew '" + text + "': " + why +
                                 " (expected <offset_ms>,<drift_ppm>)");
  };
  const auto comma = text.find(',');
  if (comma == std::string::npos) throw bad("no comma");
  double offset_ms = 0;
  double drift_ppm = 0;
  std::size_t used = 0;
  const std::string drift_text = text.substr(comma + 1);
  try {
    offset_ms = std::stod(text.substr(0, comma), &used);
  } catch (const std::logic_error&) {
    throw bad("not two numbers");
  }
  if (used != comma) throw bad("offset is not a number");
  try {
    drift_ppm = std::stod(drift_text, &used);
  } catch (const std::logic_error&) {
    throw bad("not two numbers");
  }
  if (used != drift_text.size()) throw bad("drift is not a number");
  if (!std::isfinite(offset_ms) || std::abs(offset_ms) > 3.6e6) throw bad("offset beyond ±1 h");
  if (!std::isfinite(drift_ppm) || std::abs(drift_ppm) > 1e4) throw bad("drift beyond ±10000 ppm");
  return {static_cast<TimeNs>(std::llround(offset_ms * 1e6)), drift_ppm};
}

TimeNs NodeClock::skew(TimeNs wall_ns) const {
  return skew_offset_ns_ +
         static_cast<TimeNs>(std::llround(skew_drift_ * static_cast<double>(wall_ns - start_wall_ns_)));
}

TimeNs source_clock_offset_ns(const std::string& spec) {
  if (spec.rfind("sim:", 0) != 0) return 0;
  const auto hash = spec.rfind('#');
  if (hash == std::string::npos || hash < 4) return 0;
  const Scene scene = Scene::load(spec.substr(4, hash - 4));
  const SimCameraConfig* camera = scene.find_camera(spec.substr(hash + 1));
  return camera != nullptr ? camera->clock_offset_ns : 0;
}

}  // namespace panoptes::camera
