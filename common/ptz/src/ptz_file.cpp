// SPDX-License-Identifier: Apache-2.0
#include "panoptes/ptz/ptz_file.h"

#include <cmath>
#include <numbers>

#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "panoptes/config.h"

namespace panoptes::ptz {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

AxisLimits read_axis(const YamlReader& parent, const std::string& key, const AxisLimits& fallback) {
  if (!parent.has(key)) return fallback;
  const YamlReader axis = parent.child(key);
  axis.expect_only({"min_deg", "max_deg", "max_speed_dps", "max_accel_dps2"});
  AxisLimits limits;
  limits.min_rad = axis.get_double("min_deg", fallback.min_rad / kDegree) * kDegree;
  limits.max_rad = axis.get_double("max_deg", fallback.max_rad / kDegree) * kDegree;
  limits.max_speed_radps = axis.get_double("max_speed_dps", fallback.max_speed_radps / kDegree) * kDegree;
  limits.max_accel_radps2 = axis.get_double("max_accel_dps2", fallback.max_accel_radps2 / kDegree) * kDegree;
  return limits;
}

}  // namespace

PtzModel load_ptz_model(const std::filesystem::path& path) {
  const YamlReader root(path.string(), load_yaml_file(path));
  root.expect_only({"ptz"});
  const YamlReader node = root.child("ptz");
  node.expect_only(
      {"name", "position", "base_yaw_deg", "pan", "tilt", "zoom", "command_latency_ms", "image"});
  PtzModel model;
  model.name = node.get_string("name", model.name);
  const std::vector<double> position = node.get_doubles("position", 3);
  model.position = {position[0], position[1], position[2]};
  model.base_yaw_rad = node.get_double("base_yaw_deg", 0.0) * kDegree;
  model.pan = read_axis(node, "pan", model.pan);
  model.tilt = read_axis(node, "tilt", model.tilt);
  if (node.has("zoom")) {
    const YamlReader zoom = node.child("zoom");
    zoom.expect_only({"fov_min_deg", "fov_max_deg", "speed_dps"});
    model.fov_min_rad = zoom.get_double("fov_min_deg", model.fov_min_rad / kDegree) * kDegree;
    model.fov_max_rad = zoom.get_double("fov_max_deg", model.fov_max_rad / kDegree) * kDegree;
    model.zoom_speed_radps = zoom.get_double("speed_dps", model.zoom_speed_radps / kDegree) * kDegree;
  }
  model.command_latency_s = node.get_double("command_latency_ms", model.command_latency_s * 1e3) * 1e-3;
  if (node.has("image")) {
    const YamlReader image = node.child("image");
    image.expect_only({"width", "height"});
    model.width = static_cast<int>(image.get_int("width", model.width));
    model.height = static_cast<int>(image.get_int("height", model.height));
  }
  if (const std::string problem = model_problem(model); !problem.empty()) {
    const auto colon = problem.find(':');
    node.fail(problem.substr(0, colon), problem.substr(colon + 2));
  }
  return model;
}

std::string command_to_json(const PtzCommand& command) {
  const nlohmann::json line = {{"issued_ns", command.issued_ns}, {"pan", command.pan},
                               {"tilt", command.tilt},           {"pan_rate", command.pan_rate},
                               {"tilt_rate", command.tilt_rate}, {"fov", command.fov}};
  return line.dump();
}

std::optional<PtzCommand> command_from_json(const std::string& line, std::string& error) {
  const nlohmann::json json = nlohmann::json::parse(line, nullptr, false);
  if (!json.is_object()) {
    error = "not a JSON object";
    return std::nullopt;
  }
  PtzCommand command;
  if (!json.contains("issued_ns") || !json["issued_ns"].is_number_integer()) {
    error = "issued_ns: missing or not an integer";
    return std::nullopt;
  }
  command.issued_ns = json["issued_ns"].get<TimeNs>();
  const std::pair<const char*, double*> fields[] = {{"pan", &command.pan},
                                                    {"tilt", &command.tilt},
                                                    {"pan_rate", &command.pan_rate},
                                                    {"tilt_rate", &command.tilt_rate},
                                                    {"fov", &command.fov}};
  for (const auto& [key, value] : fields) {
    if (!json.contains(key) || !json[key].is_number() || !std::isfinite(json[key].get<double>())) {
      error = std::string(key) + ": missing or not a finite number";
      return std::nullopt;
    }
    *value = json[key].get<double>();
  }
  return command;
}

}  // namespace panoptes::ptz
