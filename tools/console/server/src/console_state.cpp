// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/console_state.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

namespace panoptes::console {

namespace {

using nlohmann::json;

// Rounded to `decimals` so that the JSON carries short numbers (x * 10^d / 10^d prints shortest).
double round_to(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

json pose_json(const Pose& pose) {
  return {{"p", pose.position}, {"q", pose.orientation}};
}

json geometry_json(const CameraGeometry& geometry) {
  json out = {{"width", geometry.width},
              {"height", geometry.height},
              {"K", geometry.K},
              {"has_pose", geometry.has_pose}};
  if (geometry.has_pose) out["T_world_cam"] = pose_json(geometry.T_world_cam);
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

std::uint64_t counter(const CameraStatusRecord& status, const std::string& name) {
  const auto found = status.counters.find(name);
  return found == status.counters.end() ? 0 : found->second;
}

std::string format_reason(const char* format, double a, double b = 0) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, format, a, b);
  return buffer;
}

}  // namespace

Health camera_health(const HealthInputs& in, const StateOptions& options) {
  if (!in.has_frames) return {"red", "no frames received"};
  if (in.since_frame_ns > options.feature_timeout_ns)
    return {"red", format_reason("no frames for %.1f s", static_cast<double>(in.since_frame_ns) * 1e-9)};
  if (!in.has_status) return {"amber", "no camera_status yet"};
  if (in.since_status_ns > options.status_timeout_ns)
    return {"red",
            format_reason("no camera_status for %.1f s", static_cast<double>(in.since_status_ns) * 1e-9)};
  if (!in.last_error.empty()) return {"amber", "last error: " + in.last_error};
  if (in.drops_last_period > 0)
    return {"amber", format_reason("%.0f frames dropped in the last second",
                                   static_cast<double>(in.drops_last_period))};
  if (in.nominal_rate_hz > 0 && in.camera_fps < 0.9 * in.nominal_rate_hz)
    return {"amber", format_reason("%.1f fps, nominal %.1f", in.camera_fps, in.nominal_rate_hz)};
  if (in.nominal_rate_hz > 0 && in.detect_p99_ms > 0.5e3 / in.nominal_rate_hz)
    return {"amber", format_reason("detection p99 %.2f ms is over half the frame period (%.2f ms)",
                                   in.detect_p99_ms, 0.5e3 / in.nominal_rate_hz)};
  return {"green", "ok"};
}

void ConsoleState::on_info(const std::string& camera, CameraInfoRecord info, TimeNs /*now*/) {
  std::lock_guard lock(mutex_);
  cameras_[camera].info = std::move(info);
}

void ConsoleState::on_status(const std::string& camera, CameraStatusRecord status, TimeNs now) {
  std::lock_guard lock(mutex_);
  Camera& entry = cameras_[camera];
  const std::uint64_t drops = status.drops_queue + status.drops_source;
  const std::uint64_t drops_before =
      entry.status ? entry.status->drops_queue + entry.status->drops_source : drops;
  entry.drops_last_period = drops >= drops_before ? drops - drops_before : 0;
  resolve_pending(camera, status);
  entry.status = std::move(status);
  entry.status_ns = now;
}

void ConsoleState::on_predictions(const std::string& camera, std::vector<PredictedWindowRecord> windows,
                                  TimeNs now) {
  std::lock_guard lock(mutex_);
  Camera& entry = cameras_[camera];
  entry.windows = std::move(windows);
  entry.windows_ns = now;
}

void ConsoleState::on_preview(const std::string& camera, TimeNs stamp_ns, int width, int height,
                              std::string pixels) {
  // A preview whose size does not match its pixels is dropped (a bad message, never a bad image).
  if (width <= 0 || height <= 0 ||
      pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    return;
  std::lock_guard lock(mutex_);
  Camera& entry = cameras_[camera];
  entry.preview_stamp_ns = stamp_ns;
  entry.preview_width = width;
  entry.preview_height = height;
  entry.preview_pixels = std::move(pixels);
}

std::optional<std::string> ConsoleState::preview_pgm(const std::string& camera) const {
  std::lock_guard lock(mutex_);
  const auto entry = cameras_.find(camera);
  if (entry == cameras_.end() || entry->second.preview_stamp_ns == 0) return std::nullopt;
  const Camera& c = entry->second;
  return "P5\n" + std::to_string(c.preview_width) + " " + std::to_string(c.preview_height) + "\n255\n" +
         c.preview_pixels;
}

void ConsoleState::on_features(const std::string& camera, FeatureRecord features, TimeNs now) {
  std::lock_guard lock(mutex_);
  Camera& entry = cameras_[camera];
  const double latency_ms = static_cast<double>(now - features.stamp_ns) * 1e-6;
  entry.latency_ms = entry.frames_received == 0 ? latency_ms : 0.9 * entry.latency_ms + 0.1 * latency_ms;
  entry.features = std::move(features);
  entry.features_ns = now;
  ++entry.frames_received;
  if (entry.rate_window_start_ns == 0) entry.rate_window_start_ns = now;
  ++entry.rate_window_frames;
  if (const TimeNs elapsed = now - entry.rate_window_start_ns; elapsed >= kNsPerSecond) {
    entry.received_fps = static_cast<double>(entry.rate_window_frames) * 1e9 / static_cast<double>(elapsed);
    entry.rate_window_start_ns = now;
    entry.rate_window_frames = 0;
  }
}

void ConsoleState::on_calibration(const std::map<std::string, CameraGeometry>& cameras) {
  std::lock_guard lock(mutex_);
  for (const auto& [id, geometry] : cameras) cameras_[id].calibrated = geometry;
}

void ConsoleState::on_estimator(EstimatorRecord status, TimeNs now) {
  std::lock_guard lock(mutex_);
  estimator_ = std::move(status);
  estimator_ns_ = now;
}

void ConsoleState::on_tracks(std::vector<TrackPoint> tracks, TimeNs now) {
  std::lock_guard lock(mutex_);
  std::map<std::int64_t, TimeNs> first_seen;
  for (const TrackPoint& track : tracks) {
    const auto known = track_first_seen_ns_.find(track.id);
    first_seen[track.id] = known == track_first_seen_ns_.end() ? now : known->second;
  }
  track_first_seen_ns_ = std::move(first_seen);  // ids no longer published are forgotten
  tracks_ = std::move(tracks);
  tracks_ns_ = now;
}

void ConsoleState::on_body(BodyRecord body, TimeNs now) {
  std::lock_guard lock(mutex_);
  const auto known = bodies_.find(body.name);
  if (known == bodies_.end() || now - known->second.second > options_.body_timeout_ns)
    body_first_seen_ns_[body.name] = now;
  std::string name = body.name;
  bodies_[std::move(name)] = {std::move(body), now};
}

// A recording ends when its recorder stops or starts another file; it is listed with the figures
// of the last status that described it.
void ConsoleState::on_recorder_status(const std::string& recorder, RecorderRecord status, TimeNs now) {
  std::lock_guard lock(mutex_);
  Recorder& entry = recorders_[recorder];
  const RecorderRecord& before = entry.status;
  if (before.recording && (!status.recording || status.path != before.path)) {
    const bool same_file = status.path == before.path;
    recordings_.push_back({recorder, before.path, same_file ? status.messages : before.messages,
                           same_file ? status.bytes : before.bytes, entry.started_ns, now});
    if (recordings_.size() > options_.max_recordings) recordings_.erase(recordings_.begin());
  }
  if (status.recording && (!before.recording || status.path != before.path)) entry.started_ns = now;
  for (auto it = pending_recorder_.begin(); it != pending_recorder_.end();) {
    if (it->recorder != recorder || it->want_recording != status.recording) {
      ++it;
      continue;
    }
    outcomes_.push_back(
        {it->client, it->request, status.error.empty() ? "applied" : "rejected", status.error});
    it = pending_recorder_.erase(it);
  }
  entry.status = std::move(status);
  entry.status_ns = now;
}

void ConsoleState::on_recorder_command_sent(PendingRecorderCommand command) {
  std::lock_guard lock(mutex_);
  pending_recorder_.push_back(std::move(command));
}

bool ConsoleState::knows_recorder(const std::string& recorder) const {
  std::lock_guard lock(mutex_);
  return recorders_.count(recorder) > 0;
}

// Called with the lock held.
json ConsoleState::recorders_json(TimeNs now) const {
  json recorders = json::array();
  for (const auto& [id, recorder] : recorders_) {
    if (now - recorder.status_ns > options_.recorder_timeout_ns) continue;
    const RecorderRecord& s = recorder.status;
    recorders.push_back(
        {{"id", id},
         {"recording", s.recording},
         {"path", s.path},
         {"topics", s.topics},
         {"messages", s.messages},
         {"bytes", s.bytes},
         {"messages_per_s", round_to(s.messages_per_s, 1)},
         {"error", s.error},
         {"rejections", s.rejections},
         {"seconds",
          s.recording ? round_to(static_cast<double>(now - recorder.started_ns) * 1e-9, 1) : 0.0}});
  }
  json recordings = json::array();
  for (const RecordingEntry& r : recordings_) {
    recordings.push_back({{"recorder", r.recorder},
                          {"path", r.path},
                          {"messages", r.messages},
                          {"bytes", r.bytes},
                          {"started_ms", r.started_ns / 1'000'000},
                          {"seconds", round_to(static_cast<double>(r.stopped_ns - r.started_ns) * 1e-9, 1)}});
  }
  return {{"recorders", std::move(recorders)}, {"recordings", std::move(recordings)}};
}

void ConsoleState::start_coverage(TimeNs now) {
  std::lock_guard lock(mutex_);
  coverage_.clear();
  coverage_active_ = true;
  coverage_start_ns_ = now;
}

void ConsoleState::add_coverage_frame(const std::string& camera, const std::vector<BlobPoint>& blobs) {
  std::lock_guard lock(mutex_);
  Coverage& coverage = coverage_[camera];
  ++coverage.frames;
  if (!blobs.empty()) ++coverage.frames_with_blobs;
  if (const auto found = cameras_.find(camera); found != cameras_.end() && found->second.info)
    coverage.grid.set_size(found->second.info->geometry.width, found->second.info->geometry.height);
  for (const BlobPoint& blob : blobs) coverage.grid.add(blob.x, blob.y);
}

void ConsoleState::stop_coverage() {
  std::lock_guard lock(mutex_);
  if (coverage_active_) coverage_stop_ns_ = wall_now_ns();
  coverage_active_ = false;
}

void ConsoleState::set_calibration_job(std::string summary_json, std::string full_json) {
  std::lock_guard lock(mutex_);
  calibration_job_ = std::move(summary_json);
  calibration_job_full_ = std::move(full_json);
}

std::string ConsoleState::calibration_job() const {
  std::lock_guard lock(mutex_);
  return calibration_job_full_;
}

// Called with the lock held.
json ConsoleState::calibration_json(TimeNs now) const {
  json cameras = json::array();
  for (const auto& [id, coverage] : coverage_) {
    cameras.push_back({{"id", id},
                       {"frames", coverage.frames},
                       {"frames_with_blobs", coverage.frames_with_blobs},
                       {"coverage_percent", coverage.grid.percent()},
                       {"cells", coverage.grid.cells()}});
  }
  const TimeNs end = coverage_active_ ? now : coverage_stop_ns_;
  return {{"capturing", coverage_active_},
          {"seconds",
           coverage_start_ns_ == 0 ? 0.0 : round_to(static_cast<double>(end - coverage_start_ns_) * 1e-9, 1)},
          {"cameras", std::move(cameras)},
          {"job", json::parse(calibration_job_, nullptr, false)}};
}

json ConsoleState::details(const std::string& kind, const std::string& key, TimeNs now) const {
  std::lock_guard lock(mutex_);
  const auto seconds = [](TimeNs ns) { return round_to(static_cast<double>(ns) * 1e-9, 2); };
  const auto rounded = [](const auto& values, int decimals) {
    json out = json::array();
    for (const double value : values) out.push_back(round_to(value, decimals));
    return out;
  };
  if (kind == "track" && now - tracks_ns_ <= options_.track_timeout_ns) {
    for (const TrackPoint& track : tracks_) {
      if (std::to_string(track.id) != key) continue;
      const auto& c = track.covariance;  // xx xy xz yy yz zz
      const std::array<double, 3> sigma = {std::sqrt(std::max(0.0, c[0])), std::sqrt(std::max(0.0, c[3])),
                                           std::sqrt(std::max(0.0, c[5]))};
      const auto first = track_first_seen_ns_.find(track.id);
      return {{"kind", "track"},
              {"id", track.id},
              {"status", track.status == 0   ? "tentative"
                         : track.status == 1 ? "confirmed"
                                             : "coasting"},
              {"position_m", rounded(track.position, 4)},
              {"velocity_m_s", rounded(track.velocity, 3)},
              {"speed_m_s", round_to(std::hypot(track.velocity[0], track.velocity[1], track.velocity[2]), 3)},
              {"sigma_mm", rounded(std::array<double, 3>{1e3 * sigma[0], 1e3 * sigma[1], 1e3 * sigma[2]}, 2)},
              {"covariance_m2", track.covariance},
              {"cameras", track.cameras},
              {"age_s", seconds(first == track_first_seen_ns_.end() ? 0 : now - first->second)}};
    }
    return nullptr;
  }
  if (kind == "chain") return chain_details(key, now);
  if (kind == "body") {
    const auto found = bodies_.find(key);
    if (found == bodies_.end() || now - found->second.second > options_.body_timeout_ns) return nullptr;
    const BodyRecord& body = found->second.first;
    const auto first = body_first_seen_ns_.find(key);
    const auto& v = body.linear_velocity;
    return {
        {"kind", "body"},
        {"name", body.name},
        // The stamp of the pose shown: a test or user compares the figures with the pose the
        // estimator published at that stamp, not with whichever pose is newest when it looks.
        {"stamp_ns", body.stamp_ns},
        {"position_m", rounded(body.pose.position, 4)},
        {"orientation_xyzw", rounded(body.pose.orientation, 5)},
        {"velocity_m_s", rounded(body.linear_velocity, 3)},
        {"speed_m_s", round_to(std::hypot(v[0], v[1], v[2]), 3)},
        {"angular_velocity_rad_s", rounded(body.angular_velocity, 3)},
        {"sigma_position_mm",
         rounded(std::array<double, 3>{1e3 * body.sigma[0], 1e3 * body.sigma[1], 1e3 * body.sigma[2]}, 2)},
        {"sigma_rotation_deg",
         rounded(std::array<double, 3>{body.sigma[3] * 180 / M_PI, body.sigma[4] * 180 / M_PI,
                                       body.sigma[5] * 180 / M_PI},
                 3)},
        {"quality", round_to(body.quality, 3)},
        {"age_s", seconds(first == body_first_seen_ns_.end() ? 0 : now - first->second)},
        {"since_update_ms", round_to(static_cast<double>(now - found->second.second) * 1e-6, 1)}};
  }
  return nullptr;
}

bool ConsoleState::knows_camera(const std::string& camera) const {
  std::lock_guard lock(mutex_);
  return cameras_.count(camera) > 0;
}

std::optional<std::pair<int, int>> ConsoleState::image_size(const std::string& camera) const {
  std::lock_guard lock(mutex_);
  const auto found = cameras_.find(camera);
  if (found == cameras_.end() || !found->second.info) return std::nullopt;
  const CameraGeometry& geometry = found->second.info->geometry;
  if (geometry.width <= 0 || geometry.height <= 0) return std::nullopt;
  return std::make_pair(geometry.width, geometry.height);
}

void ConsoleState::on_command_sent(PendingCommand command) {
  std::lock_guard lock(mutex_);
  if (const auto found = cameras_.find(command.camera); found != cameras_.end() && found->second.status) {
    command.applied_before = counter(*found->second.status, "command_" + command.command);
    command.rejected_before = counter(*found->second.status, "bad_command");
  }
  pending_.push_back(std::move(command));
}

// Called with the lock held. A status counts every command applied or rejected so far; pending
// commands of that camera take those counts in the order they were sent (the camera applies them
// in order), each count going to one command only.
void ConsoleState::resolve_pending(const std::string& camera, const CameraStatusRecord& status) {
  std::map<std::string, std::uint64_t> applied_taken;
  std::uint64_t rejected_taken = 0;
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (it->camera != camera) {
      ++it;
      continue;
    }
    const std::string name = "command_" + it->command;
    if (counter(status, name) > it->applied_before + applied_taken[name]) {
      ++applied_taken[name];
      outcomes_.push_back({it->client, it->request, "applied", ""});
    } else if (counter(status, "bad_command") > it->rejected_before + rejected_taken) {
      ++rejected_taken;
      outcomes_.push_back({it->client, it->request, "rejected", status.last_error});
    } else {
      ++it;
      continue;
    }
    it = pending_.erase(it);
  }
}

std::vector<CommandOutcome> ConsoleState::take_outcomes(TimeNs now) {
  std::lock_guard lock(mutex_);
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (now - it->sent_ns <= options_.ack_timeout_ns) {
      ++it;
      continue;
    }
    outcomes_.push_back({it->client, it->request, "no_ack", "the camera's status did not count the command"});
    it = pending_.erase(it);
  }
  for (auto it = pending_recorder_.begin(); it != pending_recorder_.end();) {
    if (now - it->sent_ns <= options_.ack_timeout_ns) {
      ++it;
      continue;
    }
    outcomes_.push_back({it->client, it->request, "no_ack", "the recorder's status did not show the change"});
    it = pending_recorder_.erase(it);
  }
  std::vector<CommandOutcome> out;
  out.swap(outcomes_);
  return out;
}

Health ConsoleState::health_of(const std::string& /*id*/, const Camera& camera, TimeNs now) const {
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

nlohmann::json ConsoleState::snapshot(TimeNs now, bool full) const {
  std::lock_guard lock(mutex_);
  json cameras = json::array();
  for (const auto& [id, camera] : cameras_) {
    json blobs = json::array();
    const bool fresh = now - camera.features_ns <= options_.feature_timeout_ns;
    if (fresh) {
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
    const Health health = health_of(id, camera, now);
    json entry = {{"id", id},
                  {"frame", camera.features.frame},
                  {"blobs", std::move(blobs)},
                  {"windows", std::move(windows)},
                  {"preview_stamp_ns", camera.preview_stamp_ns},
                  {"rx_fps", round_to(camera.received_fps, 1)},
                  {"latency_ms", round_to(camera.latency_ms, 2)},
                  {"health", {{"light", health.light}, {"reason", health.reason}}}};
    if (full) {
      if (camera.info) {
        entry["info"] = {{"model", camera.info->model},
                         {"backend", camera.info->backend},
                         {"nominal_rate_hz", camera.info->nominal_rate_hz}};
      }
      const CameraGeometry* geometry = camera.calibrated ? &*camera.calibrated
                                       : camera.info     ? &camera.info->geometry
                                                         : nullptr;
      if (geometry) entry["geometry"] = geometry_json(*geometry);
      if (camera.status) entry["status"] = status_json(*camera.status);
      if (estimator_) {
        if (const auto usage = estimator_->cameras.find(id); usage != estimator_->cameras.end()) {
          entry["usage"] = {{"utilisation", round_to(usage->second.utilisation, 3)},
                            {"latency_p99_ms", round_to(usage->second.latency_p99_ms, 2)}};
        }
      }
    }
    cameras.push_back(std::move(entry));
  }
  json tracks = json::array();
  if (now - tracks_ns_ <= options_.track_timeout_ns) {
    for (const TrackPoint& track : tracks_) {
      tracks.push_back({track.id, round_to(track.position[0], 4), round_to(track.position[1], 4),
                        round_to(track.position[2], 4), track.status});
    }
  }
  json bodies = json::array();
  for (const auto& [name, body] : bodies_) {
    if (now - body.second > options_.body_timeout_ns) continue;
    bodies.push_back({{"name", name}, {"pose", pose_json(body.first.pose)}, {"quality", body.first.quality}});
  }
  json out = {{"type", "state"},
              {"full", full},
              {"cameras", std::move(cameras)},
              {"tracks", std::move(tracks)},
              {"bodies", std::move(bodies)},
              {"chains", chains_json(now)}};
  if (full) {
    out["chain_samples"] = {{"received", chain_samples_.received},
                            {"dropped", chain_samples_.dropped},
                            {"last_error", chain_samples_.last_error}};
  }
  if (full && estimator_) {
    out["estimator"] = {{"tracks_confirmed", estimator_->tracks_confirmed},
                        {"tracks_tentative", estimator_->tracks_tentative},
                        {"cpu_percent", round_to(estimator_->cpu_percent, 1)},
                        {"update_p99_ms", round_to(estimator_->update_p99_ms, 3)},
                        {"age_s", round_to(static_cast<double>(now - estimator_ns_) * 1e-9, 1)}};
  }
  if (full) {
    out.update(recorders_json(now));
    out["calibration"] = calibration_json(now);
  }
  return out;
}

}  // namespace panoptes::console
