// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/command_gate.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

namespace panoptes::console {

namespace {

using nlohmann::json;

constexpr std::size_t kMaxCameraIdLength = 64;
constexpr std::size_t kMaxPolygonPoints = 32;

struct Range {
  double low;
  double high;
  bool integer;
};

// Arguments as numbers; a number written as a string is accepted too (what a form sends).
std::optional<std::vector<double>> numbers(const json& arguments, std::size_t first) {
  std::vector<double> out;
  for (std::size_t i = first; i < arguments.size(); ++i) {
    const json& value = arguments[i];
    if (value.is_number()) {
      out.push_back(value.get<double>());
    } else if (value.is_string()) {
      const std::string& text = value.get_ref<const std::string&>();
      std::size_t used = 0;
      try {
        out.push_back(std::stod(text, &used));
      } catch (const std::exception&) {
        return std::nullopt;
      }
      if (used != text.size()) return std::nullopt;
    } else {
      return std::nullopt;
    }
    if (!std::isfinite(out.back())) return std::nullopt;
  }
  return out;
}

std::string format_number(double value, bool integer) {
  std::ostringstream out;
  if (integer) {
    out << static_cast<long long>(value);
  } else {
    out << value;
  }
  return out.str();
}

struct Check {
  std::string counter;
  std::string reason;
};

std::optional<Check> check_values(const std::string& name, const std::vector<double>& values,
                                  const std::vector<Range>& ranges, std::size_t min_count) {
  if (values.size() < min_count || values.size() > ranges.size()) {
    return Check{"bad_arguments", name + " takes " +
                                      (min_count == ranges.size() ? std::to_string(min_count)
                                                                  : std::to_string(min_count) + " to " +
                                                                        std::to_string(ranges.size())) +
                                      " argument(s), got " + std::to_string(values.size())};
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    const Range& range = ranges[i];
    if (range.integer && values[i] != std::floor(values[i]))
      return Check{"bad_arguments", name + ": argument " + std::to_string(i + 1) + " must be an integer"};
    if (values[i] < range.low || values[i] > range.high) {
      return Check{"out_of_range", name + ": argument " + std::to_string(i + 1) + " = " +
                                       format_number(values[i], false) + " is outside [" +
                                       format_number(range.low, false) + ", " +
                                       format_number(range.high, false) + "]"};
    }
  }
  return std::nullopt;
}

// add_mask rect x y w h | add_mask poly x1 y1 ... : inside the image when its size is known.
std::optional<Check> check_mask(const json& arguments, const std::optional<std::pair<int, int>>& image_size,
                                std::vector<std::string>& out) {
  if (arguments.empty() || !arguments[0].is_string())
    return Check{"bad_arguments", "add_mask: first argument must be 'rect' or 'poly'"};
  const std::string kind = arguments[0].get<std::string>();
  const auto values = numbers(arguments, 1);
  if (!values) return Check{"bad_arguments", "add_mask: coordinates must be numbers"};
  const double width = image_size ? image_size->first : 65535.0;
  const double height = image_size ? image_size->second : 65535.0;
  const std::string where = image_size ? " (image " + std::to_string(image_size->first) + "x" +
                                             std::to_string(image_size->second) + ")"
                                       : "";
  if (kind == "rect") {
    if (values->size() != 4) return Check{"bad_arguments", "add_mask rect takes x y w h"};
    const double x = (*values)[0], y = (*values)[1], w = (*values)[2], h = (*values)[3];
    if (x < 0 || y < 0 || w < 1 || h < 1 || x + w > width || y + h > height)
      return Check{"out_of_range", "add_mask rect: the rectangle is not inside the image" + where};
  } else if (kind == "poly") {
    if (values->size() % 2 != 0 || values->size() < 6 || values->size() > 2 * kMaxPolygonPoints)
      return Check{"bad_arguments",
                   "add_mask poly takes 3 to " + std::to_string(kMaxPolygonPoints) + " points"};
    for (std::size_t i = 0; i < values->size(); i += 2) {
      if ((*values)[i] < 0 || (*values)[i] > width || (*values)[i + 1] < 0 || (*values)[i + 1] > height)
        return Check{"out_of_range", "add_mask poly: a point is outside the image" + where};
    }
  } else {
    return Check{"bad_arguments", "add_mask: first argument must be 'rect' or 'poly', got '" + kind + "'"};
  }
  out.push_back(kind);
  for (const double value : *values) out.push_back(format_number(std::round(value), true));
  return std::nullopt;
}

// Argument rules: ranges and how many are required. Thresholds cover 16-bit sensors; exposure up
// to one second; gain in dB as machine-vision cameras offer it.
const std::map<std::string, std::pair<std::vector<Range>, std::size_t>>& numeric_rules() {
  static const std::map<std::string, std::pair<std::vector<Range>, std::size_t>> rules = {
      {"set_threshold", {{{0, 65535, true}, {0, 65535, true}}, 1}},
      {"set_exposure", {{{1, 1e6, false}}, 1}},
      {"set_gain", {{{0, 48, false}}, 1}},
      {"capture_background", {{{1, 64, true}}, 0}},
      {"clear_background", {{}, 0}},
      {"clear_masks", {{}, 0}},
      {"restart", {{}, 0}},
      {"preview", {{{16, 4096, true}}, 0}},  // [max width]: one downscaled image on camera_preview
  };
  return rules;
}

// The browser's id for the reply (0 when missing).
std::int64_t request_of(const json& message) {
  const auto id = message.find("id");
  return id != message.end() && id->is_number_integer() ? id->get<std::int64_t>() : 0;
}

}  // namespace

const std::vector<std::string>& console_commands() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& [name, rule] : numeric_rules()) out.push_back(name);
    out.push_back("add_mask");
    std::sort(out.begin(), out.end());
    return out;
  }();
  return names;
}

GateResult check_command(const json& message, bool camera_known,
                         const std::optional<std::pair<int, int>>& image_size) {
  const std::int64_t request = request_of(message);
  const auto reject = [&](std::string counter, std::string reason) -> GateResult {
    return Rejection{request, std::move(counter), std::move(reason)};
  };
  const auto camera = message.find("camera");
  const auto command = message.find("command");
  const auto arguments = message.find("args");
  if (camera == message.end() || !camera->is_string() || command == message.end() || !command->is_string())
    return reject("bad_message", "a command needs string fields 'camera' and 'command'");
  if (arguments != message.end() && !arguments->is_array())
    return reject("bad_message", "'args' must be an array");
  const json no_arguments = json::array();
  const json& args = arguments == message.end() ? no_arguments : *arguments;
  const std::string& name = command->get_ref<const std::string&>();
  const std::string& camera_id = camera->get_ref<const std::string&>();
  const auto rule = numeric_rules().find(name);
  if (rule == numeric_rules().end() && name != "add_mask")
    return reject("unknown_command", "unknown command '" + name.substr(0, 64) + "'");
  if (camera_id.empty() || camera_id.size() > kMaxCameraIdLength || !camera_known)
    return reject("unknown_camera",
                  "camera '" + camera_id.substr(0, kMaxCameraIdLength) + "' is not on the bus");
  CameraCommandRequest out{request, camera_id, name, {}};
  if (name == "add_mask") {
    if (const auto failed = check_mask(args, image_size, out.arguments))
      return reject(failed->counter, failed->reason);
    return out;
  }
  const auto values = numbers(args, 0);
  if (!values) return reject("bad_arguments", name + ": arguments must be numbers");
  const auto& [ranges, min_count] = rule->second;
  if (const auto failed = check_values(name, *values, ranges, min_count))
    return reject(failed->counter, failed->reason);
  for (std::size_t i = 0; i < values->size(); ++i)
    out.arguments.push_back(format_number((*values)[i], ranges[i].integer));
  return out;
}

RecorderGateResult check_recorder_command(const json& message, bool recorder_known) {
  constexpr std::size_t kMaxFileNameLength = 128;
  const std::int64_t request = request_of(message);
  const auto reject = [&](std::string counter, std::string reason) -> RecorderGateResult {
    return Rejection{request, std::move(counter), std::move(reason)};
  };
  const auto recorder = message.find("recorder");
  const auto command = message.find("command");
  const auto name = message.find("name");
  if (recorder == message.end() || !recorder->is_string() || command == message.end() ||
      !command->is_string())
    return reject("bad_message", "a recorder command needs string fields 'recorder' and 'command'");
  if (name != message.end() && !name->is_string() && !name->is_null())
    return reject("bad_message", "'name' must be a string");
  const std::string& verb = command->get_ref<const std::string&>();
  if (verb != "start" && verb != "stop")
    return reject("unknown_command", "unknown recorder command '" + verb.substr(0, 64) + "' (start | stop)");
  const std::string& id = recorder->get_ref<const std::string&>();
  if (id.empty() || id.size() > kMaxCameraIdLength || !recorder_known)
    return reject("unknown_recorder",
                  "recorder '" + id.substr(0, kMaxCameraIdLength) + "' is not on the bus");
  RecorderCommandRequest out{request, id, verb, {}};
  if (verb == "start" && name != message.end() && name->is_string()) {
    const std::string& file = name->get_ref<const std::string&>();
    const bool allowed_characters = std::all_of(file.begin(), file.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' || c == '.';
    });
    const bool mcap = file.size() > 5 && file.compare(file.size() - 5, 5, ".mcap") == 0;
    if (!file.empty() &&
        (!allowed_characters || !mcap || file.front() == '.' || file.size() > kMaxFileNameLength))
      return reject("bad_arguments", "recording name '" + file.substr(0, kMaxFileNameLength) +
                                         "': a file name of letters, digits, '-', '_', '.' ending in .mcap "
                                         "(no directory)");
    out.path = file;
  }
  return out;
}

CalibrationGateResult check_calibration_request(const json& message) {
  constexpr std::size_t kMaxWandMarkers = 8;
  constexpr double kMaxWandLength = 5;     // metres
  constexpr double kMaxFloorOffset = 0.1;  // metres
  const std::int64_t request = request_of(message);
  const auto reject = [&](std::string counter, std::string reason) -> CalibrationGateResult {
    return Rejection{request, std::move(counter), std::move(reason)};
  };
  const auto action = message.find("action");
  if (action == message.end() || !action->is_string())
    return reject("bad_message", "a calibration message needs a string field 'action'");
  const std::string& name = action->get_ref<const std::string&>();
  static const std::vector<std::string> actions = {"capture", "floor_capture", "stop",  "solve",
                                                   "world",   "accept",        "revert"};
  if (std::find(actions.begin(), actions.end(), name) == actions.end())
    return reject("unknown_command",
                  "unknown calibration action '" + name.substr(0, 64) +
                      "' (capture | floor_capture | stop | solve | world | accept | revert)");
  CalibrationRequest out{request, name, {}, 0, false, 0};
  if (name == "accept" || name == "revert") {  // a version of the estimator's calibration file
    constexpr std::int64_t kMaxVersion = 1'000'000;
    const auto version = message.find("version");
    if (version == message.end() || !version->is_number_integer())
      return reject("bad_arguments", name + ": needs 'version', the calibration file's version (an integer)");
    const auto number = version->get<std::int64_t>();
    if (number < 1 || number > kMaxVersion) return reject("out_of_range", name + ": version 1 to 1000000");
    out.version = static_cast<int>(number);
    return out;
  }
  if (const auto flag = message.find("time_service"); flag != message.end()) {
    if (!flag->is_boolean()) return reject("bad_message", "'time_service' must be true or false");
    out.time_service = flag->get<bool>();
  }
  if (name == "solve" || name == "world") {
    const auto wand = message.find("wand");
    if (wand == message.end() || !wand->is_string())
      return reject("bad_arguments",
                    name + ": needs 'wand', the marker positions along the bar in metres (0,0.18,0.5)");
    json values = json::array();
    std::string text = wand->get<std::string>();
    for (std::size_t start = 0; start <= text.size();) {
      const auto comma = std::min(text.find(',', start), text.size());
      values.push_back(text.substr(start, comma - start));
      start = comma + 1;
    }
    const auto positions = numbers(values, 0);
    if (!positions || positions->empty() || positions->size() > kMaxWandMarkers)
      return reject("bad_arguments", "wand '" + text.substr(0, 64) + "': 1 to 8 numbers separated by ','");
    for (const double position : *positions) {
      if (position < 0 || position > kMaxWandLength)
        return reject("out_of_range", "wand: a marker position outside 0-5 m");
      out.wand += (out.wand.empty() ? "" : ",") + format_number(position, false);
    }
  }
  if (const auto offset = message.find("floor_offset"); name == "world" && offset != message.end()) {
    if (!offset->is_number()) return reject("bad_arguments", "'floor_offset' must be a number (metres)");
    out.floor_offset_m = offset->get<double>();
    if (!(out.floor_offset_m >= 0 && out.floor_offset_m <= kMaxFloorOffset))
      return reject("out_of_range", "floor_offset: 0 to 0.1 m");
  }
  return out;
}

BodyGateResult check_body_request(const json& message) {
  constexpr std::size_t kMaxName = 64;
  constexpr std::size_t kMinTracks = 3;
  constexpr std::size_t kMaxTracks = 64;
  const std::int64_t request = request_of(message);
  const auto reject = [&](std::string counter, std::string reason) -> BodyGateResult {
    return Rejection{request, std::move(counter), std::move(reason)};
  };
  const auto name = message.find("name");
  if (name == message.end() || !name->is_string())
    return reject("bad_message", "a body message needs a string field 'name'");
  const std::string& text = name->get_ref<const std::string&>();
  const bool name_ok =
      !text.empty() && text.size() <= kMaxName && std::all_of(text.begin(), text.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '.';
      });
  if (!name_ok) return reject("bad_arguments", "name: 1 to 64 letters, digits, '_', '-' or '.'");
  BodyCreateRequest out{request, text, {}, std::nullopt};
  const auto tracks = message.find("tracks");
  if (tracks == message.end() || !tracks->is_array())
    return reject("bad_message", "a body message needs 'tracks', an array of track ids");
  if (tracks->size() < kMinTracks || tracks->size() > kMaxTracks)
    return reject("bad_arguments",
                  "tracks: a body needs 3 to 64 markers, got " + std::to_string(tracks->size()));
  for (const auto& id : *tracks) {
    if (!id.is_number_integer() || id.get<std::int64_t>() < 0)
      return reject("bad_arguments", "tracks: track ids are non-negative integers");
    out.tracks.push_back(id.get<std::int64_t>());
  }
  if (const auto pivot = message.find("pivot"); pivot != message.end() && !pivot->is_null()) {
    if (!pivot->is_number_integer() || pivot->get<std::int64_t>() < 0)
      return reject("bad_arguments", "pivot: a track id, or null for the centroid");
    out.pivot = pivot->get<std::int64_t>();
  }
  return out;
}

bool RateLimiter::allow(TimeNs now) {
  if (last_ns_ != 0) tokens_ = std::min(burst_, tokens_ + rate_ * static_cast<double>(now - last_ns_) * 1e-9);
  last_ns_ = now;
  if (tokens_ < 1.0) return false;
  tokens_ -= 1.0;
  return true;
}

}  // namespace panoptes::console
