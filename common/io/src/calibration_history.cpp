// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calibration_history.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>
#include <utility>

#include <nlohmann/json.hpp>

#include "panoptes/calibration_file.h"
#include "panoptes/errors.h"
#include "panoptes/time.h"

namespace panoptes {

namespace fs = std::filesystem;

namespace {

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string(), "", "cannot be read");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Written to a temporary file beside `path`, then renamed over it: a reader sees the old file or
// the new one, never half of one.
void write_bytes(const fs::path& path, const std::string& bytes) {
  const fs::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << bytes;
    out.flush();
    if (!out) throw ConfigError(temporary.string(), "", "cannot be written");
  }
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) throw ConfigError(path.string(), "", "cannot be replaced: " + error.message());
}

std::string iso_utc(std::int64_t time_ns) {
  const std::time_t seconds = static_cast<std::time_t>(time_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

VersionState parse_state(const std::string& text, const std::string& index, std::size_t line) {
  if (text == "applied") return VersionState::kApplied;
  if (text == "accepted") return VersionState::kAccepted;
  if (text == "reverted") return VersionState::kReverted;
  throw ConfigError(index, "line " + std::to_string(line) + ": state", "unknown state '" + text + "'");
}

nlohmann::json to_json(const CalibrationVersion& v) {
  nlohmann::json j = {{"version", v.version},
                      {"time_ns", v.time_ns},
                      {"time_utc", v.time_utc},
                      {"reason", v.change.reason},
                      {"cameras", v.change.cameras},
                      {"state", to_string(v.state)},
                      {"file", v.file}};
  j["residual_before_px"] = std::isfinite(v.change.residual_before_px)
                                ? nlohmann::json(v.change.residual_before_px)
                                : nlohmann::json(nullptr);
  j["residual_after_px"] = std::isfinite(v.change.residual_after_px)
                               ? nlohmann::json(v.change.residual_after_px)
                               : nlohmann::json(nullptr);
  return j;
}

CalibrationVersion from_json(const nlohmann::json& j, const std::string& index, std::size_t line) {
  CalibrationVersion v;
  try {
    v.version = j.at("version").get<int>();
    v.time_ns = j.at("time_ns").get<std::int64_t>();
    v.time_utc = j.at("time_utc").get<std::string>();
    v.change.reason = j.at("reason").get<std::string>();
    v.change.cameras = j.at("cameras").get<std::vector<std::string>>();
    v.file = j.at("file").get<std::string>();
    if (!j.at("residual_before_px").is_null())
      v.change.residual_before_px = j["residual_before_px"].get<double>();
    if (!j.at("residual_after_px").is_null())
      v.change.residual_after_px = j["residual_after_px"].get<double>();
    v.state = parse_state(j.at("state").get<std::string>(), index, line);
  } catch (const nlohmann::json::exception& error) {
    throw ConfigError(index, "line " + std::to_string(line), error.what());
  }
  return v;
}

std::string camera_yaml(const CameraCalibration& camera) {
  SystemCalibration one;
  one.cameras.push_back(camera);
  return calibration_to_yaml(one);
}

}  // namespace

std::string version_json(const CalibrationVersion& version) {
  return to_json(version).dump();
}

CalibrationChange change_because(std::string reason, std::vector<std::string> cameras,
                                 double residual_before_px, double residual_after_px) {
  CalibrationChange change;
  change.reason = std::move(reason);
  change.cameras = std::move(cameras);
  change.residual_before_px = residual_before_px;
  change.residual_after_px = residual_after_px;
  return change;
}

const char* to_string(VersionState state) {
  switch (state) {
    case VersionState::kApplied:
      return "applied";
    case VersionState::kAccepted:
      return "accepted";
    case VersionState::kReverted:
      return "reverted";
  }
  return "?";
}

std::vector<std::string> changed_cameras(const SystemCalibration& before, const SystemCalibration& after) {
  std::vector<std::string> changed;
  for (const auto& camera : after.cameras) {
    const CameraCalibration* old = before.find(camera.id);
    if (old == nullptr || camera_yaml(*old) != camera_yaml(camera)) changed.push_back(camera.id);
  }
  for (const auto& camera : before.cameras) {
    if (after.find(camera.id) == nullptr) changed.push_back(camera.id);
  }
  return changed;
}

CalibrationHistory::CalibrationHistory(fs::path calibration_file) : file_(std::move(calibration_file)) {}

fs::path CalibrationHistory::directory() const {
  return file_.string() + ".history";
}

fs::path CalibrationHistory::index() const {
  return directory() / "history.jsonl";
}

std::vector<CalibrationVersion> CalibrationHistory::versions() const {
  std::vector<CalibrationVersion> out;
  if (!fs::exists(index())) return out;
  std::ifstream in(index());
  if (!in) throw ConfigError(index().string(), "", "cannot be read");
  std::string text;
  for (std::size_t line = 1; std::getline(in, text); ++line) {
    if (text.empty()) continue;
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& error) {
      throw ConfigError(index().string(), "line " + std::to_string(line), error.what());
    }
    out.push_back(from_json(j, index().string(), line));
    if (out.back().version != static_cast<int>(out.size()))
      throw ConfigError(
          index().string(), "line " + std::to_string(line) + ": version",
          "expected " + std::to_string(out.size()) + ", got " + std::to_string(out.back().version));
  }
  return out;
}

void CalibrationHistory::write_index(const std::vector<CalibrationVersion>& versions) const {
  std::string text;
  for (const auto& v : versions) text += to_json(v).dump() + "\n";
  write_bytes(index(), text);
}

std::string CalibrationHistory::bytes_of(int version) const {
  const auto all = versions();
  if (version < 1 || version > static_cast<int>(all.size()))
    throw ConfigError(
        index().string(), "version",
        "no version " + std::to_string(version) + " (" + std::to_string(all.size()) + " stored)");
  return read_bytes(directory() / all[static_cast<std::size_t>(version - 1)].file);
}

CalibrationVersion CalibrationHistory::append(const std::string& bytes, const CalibrationChange& change) {
  auto all = versions();
  CalibrationVersion v;
  v.version = static_cast<int>(all.size()) + 1;
  v.time_ns = wall_now_ns();
  v.time_utc = iso_utc(v.time_ns);
  v.change = change;
  char name[32];
  std::snprintf(name, sizeof name, "v%04d%s", v.version, file_.extension().string().c_str());
  v.file = name;
  write_bytes(directory() / v.file, bytes);
  all.push_back(v);
  write_index(all);
  return v;
}

void CalibrationHistory::begin_if_needed() {
  std::error_code error;
  fs::create_directories(directory(), error);
  if (error) throw ConfigError(directory().string(), "", "cannot be created: " + error.message());
  const auto all = versions();
  if (!fs::exists(file_)) return;  // a history of a file that does not exist yet starts with the first record
  const std::string current = read_bytes(file_);
  if (all.empty()) {
    append(current, change_because("initial"));
  } else if (read_bytes(directory() / all.back().file) != current) {
    append(current, change_because("edited outside the history"));
  }
}

CalibrationVersion CalibrationHistory::record(const SystemCalibration& calibration,
                                              const CalibrationChange& change) {
  return record_text(calibration_to_yaml(calibration), change);
}

// The version is listed before the file changes: a reader that sees the new file (the running
// estimator's reload names the version it applied) finds it in the history, never the one before.
CalibrationVersion CalibrationHistory::record_text(const std::string& yaml, const CalibrationChange& change) {
  begin_if_needed();
  CalibrationVersion version = append(yaml, change);
  write_bytes(file_, yaml);
  return version;
}

void write_calibration_text(const fs::path& path, const std::string& yaml, CalibrationChange change) {
  CalibrationHistory history(path);
  if (!fs::is_directory(history.directory())) return write_bytes(path, yaml);
  if (change.cameras.empty() && fs::exists(path)) {
    const fs::path next = path.string() + ".next";
    write_bytes(next, yaml);
    change.cameras = changed_cameras(load_calibration(path), load_calibration(next));
    fs::remove(next);
  }
  history.record_text(yaml, change);
}

CalibrationVersion CalibrationHistory::revert(int version) {
  begin_if_needed();
  const std::string bytes = bytes_of(version);  // throws for a version that does not exist
  const auto all_before = versions();
  if (bytes == read_bytes(directory() / all_before.back().file)) return all_before.back();  // already current
  CalibrationChange change;
  change.reason = "revert to " + std::to_string(version);
  const auto& target = versions()[static_cast<std::size_t>(version - 1)];
  change.cameras = changed_cameras(load_calibration(file_), load_calibration(directory() / target.file));
  auto all = versions();
  for (auto& v : all) {
    if (v.version > version && v.state != VersionState::kReverted) v.state = VersionState::kReverted;
  }
  write_index(all);
  CalibrationVersion reverted = append(bytes, change);  // listed first, as in record_text
  write_bytes(file_, bytes);
  return reverted;
}

void CalibrationHistory::start() {
  if (!fs::exists(file_))
    throw ConfigError(file_.string(), "", "does not exist: nothing to keep versions of");
  begin_if_needed();
}

void CalibrationHistory::accept(int version) {
  auto all = versions();
  if (version < 1 || version > static_cast<int>(all.size()))
    throw ConfigError(
        index().string(), "version",
        "no version " + std::to_string(version) + " (" + std::to_string(all.size()) + " stored)");
  auto& v = all[static_cast<std::size_t>(version - 1)];
  if (v.state == VersionState::kReverted)
    throw ConfigError(index().string(), "version", "version " + std::to_string(version) + " was reverted");
  v.state = VersionState::kAccepted;
  write_index(all);
}

}  // namespace panoptes
