// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/camera_model.h"

#include <cstdio>

#include <nlohmann/json.hpp>

#include "json_helpers.h"

namespace panoptes::console {

namespace {

using detail::round_to;
using nlohmann::json;

json geometry_json(const CameraGeometry& geometry) {
  json out = {{"width", geometry.width},
              {"height", geometry.height},
              {"K", geometry.K},
              {"has_pose", geometry.has_pose}};
  if (geometry.has_pose) out["T_world_cam"] = detail::pose_json(geometry.T_world_cam);
  return out;
}

json status_json(const CameraStatusRecord& status) {
  return {{"fps", round_to(status.fps, 1)},
          {"frames", status.frames},
          {"drops_queue", status.drops_queue},
          {"drops_source", status.drops_source},
          {"detect_p99_ms", round_to(status.detect_p99_ms, 3)},
          {"threshold", status.threshold},
          {"exposure_us", status.exposure_us},
          {"gain_db", status.gain_db},
          {"clock_offset_ms", round_to(static_cast<double>(status.clock_offset_ns) * 1e-6, 3)},
          {"clock_drift_ppm", round_to(status.clock_drift_ppm, 2)},
          {"last_error", status.last_error}};
}

std::string format_reason(const char* format, double a, double b = 0) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, format, a, b);
  return buffer;
}

}  // namespace

Health camera_health(const HealthInputs& in, const StateOptions& options) {
  if (!in.has_frames) return {Light::kRed, "no frames received"};
  if (in.since_frame_ns > options.feature_timeout_ns)
    return {Light::kRed,
            format_reason("no frames for %.1f s", static_cast<double>(in.since_frame_ns) * 1e-9)};
  if (!in.has_status) return {Light::kAmber, "no camera_status yet"};
  if (in.since_status_ns > options.status_timeout_ns)
    return {Light::kRed,
            format_reason("no camera_status for %.1f s", static_cast<double>(in.since_status_ns) * 1e-9)};
  if (!in.last_error.empty()) return {Light::kAmber, "last error: " + in.last_error};
  if (in.drops_last_period > 0)
    return {Light::kAmber, format_reason("%.0f frames dropped in the last second",
                                         static_cast<double>(in.drops_last_period))};
  if (in.nominal_rate_hz > 0 && in.camera_fps < 0.9 * in.nominal_rate_hz)
    return {Light::kAmber, format_reason("%.1f fps, nominal %.1f", in.camera_fps, in.nominal_rate_hz)};
  if (in.nominal_rate_hz > 0 && in.detect_p99_ms > 0.5e3 / in.nominal_rate_hz)
    return {Light::kAmber, format_reason("detection p99 %.2f ms is over half the frame period (%.2f ms)",
                                         in.detect_p99_ms, 0.5e3 / in.nominal_rate_hz)};
  return {Light::kGreen, "ok"};
}

void CameraModel::on_info(const std::string& camera, CameraInfoRecord info) {
  cameras_[camera].info = std::move(info);
}

void CameraModel::on_status(const std::string& camera, CameraStatusRecord status, TimeNs now) {
  Camera& entry = cameras_[camera];
  const std::uint64_t drops = status.drops_queue + status.drops_source;
  const std::uint64_t drops_before =
      entry.status ? entry.status->drops_queue + entry.status->drops_source : drops;
  entry.drops_last_period = drops >= drops_before ? drops - drops_before : 0;
  entry.status = std::move(status);
  entry.status_ns = now;
}

void CameraModel::on_features(const std::string& camera, FeatureRecord features, TimeNs now) {
  Camera& entry = cameras_[camera];
  const double latency_ms = static_cast<double>(now - features.stamp_ns) * 1e-6;
  entry.latency_ms = entry.frames_received == 0 ? latency_ms : 0.9 * entry.latency_ms + 0.1 * latency_ms;
  entry.features = std::move(features);
  entry.features_ns = now;
  ++entry.frames_received;
  // The first frame opens the window; each later one ends a frame interval inside it.
  if (entry.rate_window_start_ns == 0) {
    entry.rate_window_start_ns = now;
    return;
  }
  ++entry.rate_window_frames;
  if (const TimeNs elapsed = now - entry.rate_window_start_ns; elapsed >= kNsPerSecond) {
    entry.received_fps = static_cast<double>(entry.rate_window_frames) * 1e9 / static_cast<double>(elapsed);
    entry.rate_window_start_ns = now;
    entry.rate_window_frames = 0;
  }
}

void CameraModel::on_predictions(const std::string& camera, std::vector<PredictedWindowRecord> windows,
                                 TimeNs now) {
  Camera& entry = cameras_[camera];
  entry.windows = std::move(windows);
  entry.windows_ns = now;
}

bool CameraModel::on_preview(const std::string& camera, TimeNs stamp_ns, int width, int height,
                             std::string pixels) {
  if (width <= 0 || height <= 0 ||
      pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    return false;
  Camera& entry = cameras_[camera];
  entry.preview_stamp_ns = stamp_ns;
  entry.preview_width = width;
  entry.preview_height = height;
  entry.preview_pixels = std::move(pixels);
  return true;
}

void CameraModel::on_calibration(const std::map<std::string, CameraGeometry>& cameras) {
  for (const auto& [id, geometry] : cameras) cameras_[id].calibrated = geometry;
}

bool CameraModel::knows(const std::string& camera) const {
  return cameras_.count(camera) > 0;
}

const CameraStatusRecord* CameraModel::status(const std::string& camera) const {
  const auto found = cameras_.find(camera);
  return found == cameras_.end() || !found->second.status ? nullptr : &*found->second.status;
}

std::optional<std::pair<int, int>> CameraModel::info_size(const std::string& camera) const {
  const auto found = cameras_.find(camera);
  if (found == cameras_.end() || !found->second.info) return std::nullopt;
  const CameraGeometry& geometry = found->second.info->geometry;
  return std::make_pair(geometry.width, geometry.height);
}

std::optional<std::string> CameraModel::preview_pgm(const std::string& camera) const {
  const auto entry = cameras_.find(camera);
  if (entry == cameras_.end() || entry->second.preview_stamp_ns == 0) return std::nullopt;
  const Camera& c = entry->second;
  return "P5\n" + std::to_string(c.preview_width) + " " + std::to_string(c.preview_height) + "\n255\n" +
         c.preview_pixels;
}

Health CameraModel::health(const std::string& camera, TimeNs now) const {
  const auto found = cameras_.find(camera);
  return found == cameras_.end() ? camera_health({}, options_) : health_of(found->second, now);
}

Health CameraModel::health_of(const Camera& camera, TimeNs now) const {
  HealthInputs in;
  in.has_status = camera.status.has_value();
  in.since_status_ns = now - camera.status_ns;
  in.has_frames = camera.frames_received > 0;
  in.since_frame_ns = now - camera.features_ns;
  in.nominal_rate_hz = camera.info ? camera.info->nominal_rate_hz : 0;
  in.drops_last_period = camera.drops_last_period;
  if (camera.status) {
    in.camera_fps = camera.status->fps;
    in.detect_p99_ms = camera.status->detect_p99_ms;
    in.last_error = camera.status->last_error;
  }
  return camera_health(in, options_);
}

double CameraModel::received_fps_at(const Camera& camera, TimeNs now) {
  // Frames stopped: nothing is received now, whatever the last whole second counted.
  if (camera.frames_received == 0 || now - camera.features_ns > kNsPerSecond) return 0;
  // The window is closed by a frame; one left open past its second (frames slowed down) is the
  // better figure.
  if (const TimeNs open = now - camera.rate_window_start_ns; open > kNsPerSecond)
    return static_cast<double>(camera.rate_window_frames) * 1e9 / static_cast<double>(open);
  return camera.received_fps;
}

json CameraModel::camera_json(const std::string& id, const Camera& camera, TimeNs now, bool full,
                              const std::map<std::string, CameraUsageRecord>& usage) const {
  json blobs = json::array();
  if (now - camera.features_ns <= options_.feature_timeout_ns) {
    for (const BlobPoint& blob : camera.features.blobs)
      blobs.push_back({round_to(blob.x, 2), round_to(blob.y, 2), round_to(blob.area, 1)});
  }
  // The estimator's predicted windows, as stale as the blobs may be.
  json windows = json::array();
  if (now - camera.windows_ns <= options_.feature_timeout_ns) {
    for (const PredictedWindowRecord& window : camera.windows)
      windows.push_back({round_to(window.x, 1), round_to(window.y, 1), round_to(window.half_width, 1),
                         round_to(window.half_height, 1)});
  }
  const Health health = health_of(camera, now);
  json entry = {{"id", id},
                {"frame", camera.features.frame},
                {"blobs", std::move(blobs)},
                {"windows", std::move(windows)},
                {"preview_stamp_ns", camera.preview_stamp_ns},
                {"rx_fps", round_to(received_fps_at(camera, now), 1)},
                {"latency_ms", round_to(camera.latency_ms, 2)},
                {"health", {{"light", health.light}, {"reason", health.reason}}}};
  if (!full) return entry;
  if (camera.info) {
    entry["info"] = {{"model", camera.info->model},
                     {"backend", camera.info->backend},
                     {"nominal_rate_hz", camera.info->nominal_rate_hz}};
  }
  const CameraGeometry* geometry = camera.calibrated ? &*camera.calibrated
                                   : camera.info     ? &camera.info->geometry
                                                     : nullptr;
  if (geometry) entry["geometry"] = geometry_json(*geometry);
  if (camera.status) {
    entry["status"] = status_json(*camera.status);
    // The page greys out a camera's own figures once they are this old (issue 32: a stopped
    // camera's last "60.0 fps" stayed beside its red light).
    entry["status_age_s"] = round_to(static_cast<double>(now - camera.status_ns) * 1e-9, 1);
  }
  if (const auto found = usage.find(id); found != usage.end()) {
    entry["usage"] = {{"utilisation", round_to(found->second.utilisation, 3)},
                      {"latency_p99_ms", round_to(found->second.latency_p99_ms, 2)},
                      {"state", found->second.state},
                      {"since_last_frame_s", round_to(found->second.since_last_frame_s, 1)},
                      {"refused_frames", found->second.refused_frames}};
    if (!found->second.calibration.empty()) {
      entry["usage"]["calibration"] = {{"state", found->second.calibration},
                                       {"reason", found->second.calibration_reason},
                                       {"quarantines", found->second.quarantines}};
    }
  }
  return entry;
}

json CameraModel::to_json(TimeNs now, bool full,
                          const std::map<std::string, CameraUsageRecord>& usage) const {
  json cameras = json::array();
  for (const auto& [id, camera] : cameras_) cameras.push_back(camera_json(id, camera, now, full, usage));
  return cameras;
}

}  // namespace panoptes::console
