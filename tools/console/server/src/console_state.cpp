// SPDX-License-Identifier: Apache-2.0
// The coordinator: each call takes the lock of the model it changes (console_state.h, "Locking").
#include "panoptes/console/console_state.h"

#include <nlohmann/json.hpp>

namespace panoptes::console {

using nlohmann::json;

void ConsoleState::on_info(const std::string& camera, CameraInfoRecord info, TimeNs /*now*/) {
  std::lock_guard lock(cameras_.mutex);
  cameras_.model.on_info(camera, std::move(info));
}

void ConsoleState::on_status(const std::string& camera, CameraStatusRecord status, TimeNs now) {
  std::scoped_lock lock(cameras_.mutex, commands_.mutex);
  commands_.model.on_camera_status(camera, status);
  cameras_.model.on_status(camera, std::move(status), now);
}

void ConsoleState::on_features(const std::string& camera, FeatureRecord features, TimeNs now) {
  std::lock_guard lock(cameras_.mutex);
  cameras_.model.on_features(camera, std::move(features), now);
}

void ConsoleState::on_predictions(const std::string& camera, std::vector<PredictedWindowRecord> windows,
                                  TimeNs now) {
  std::lock_guard lock(cameras_.mutex);
  cameras_.model.on_predictions(camera, std::move(windows), now);
}

void ConsoleState::on_preview(const std::string& camera, TimeNs stamp_ns, int width, int height,
                              std::string pixels) {
  std::lock_guard lock(cameras_.mutex);
  cameras_.model.on_preview(camera, stamp_ns, width, height, std::move(pixels));
}

std::optional<std::string> ConsoleState::preview_pgm(const std::string& camera) const {
  std::lock_guard lock(cameras_.mutex);
  return cameras_.model.preview_pgm(camera);
}

void ConsoleState::on_calibration(const std::map<std::string, CameraGeometry>& cameras) {
  std::lock_guard lock(cameras_.mutex);
  cameras_.model.on_calibration(cameras);
}

void ConsoleState::on_estimator(EstimatorRecord status, TimeNs now) {
  std::lock_guard lock(estimator_.mutex);
  estimator_.model.on_status(std::move(status), now);
}

void ConsoleState::on_tracks(std::vector<TrackPoint> tracks, TimeNs now) {
  std::lock_guard lock(scene_.mutex);
  scene_.model.on_tracks(std::move(tracks), now);
}

void ConsoleState::on_body(BodyRecord body, TimeNs now) {
  std::lock_guard lock(scene_.mutex);
  scene_.model.on_body(std::move(body), now);
}

void ConsoleState::on_labels(std::vector<SubjectLabelsRecord> subjects) {
  std::lock_guard lock(scene_.mutex);
  scene_.model.on_labels(std::move(subjects));
}

bool ConsoleState::on_chains(ChainFrameRecord frame, TimeNs now) {
  std::lock_guard lock(scene_.mutex);
  return scene_.model.on_chains(std::move(frame), now);
}

void ConsoleState::on_recorder_status(const std::string& recorder, RecorderRecord status, TimeNs now) {
  std::scoped_lock lock(recorders_.mutex, commands_.mutex);
  commands_.model.on_recorder_status(recorder, status);
  recorders_.model.on_status(recorder, std::move(status), now);
}

bool ConsoleState::knows_camera(const std::string& camera) const {
  std::lock_guard lock(cameras_.mutex);
  return cameras_.model.knows(camera);
}

std::optional<std::pair<int, int>> ConsoleState::image_size(const std::string& camera) const {
  std::lock_guard lock(cameras_.mutex);
  const auto size = cameras_.model.info_size(camera);
  if (!size || size->first <= 0 || size->second <= 0) return std::nullopt;
  return size;
}

void ConsoleState::on_command_sent(PendingCommand command) {
  std::scoped_lock lock(cameras_.mutex, commands_.mutex);
  const CameraStatusRecord* status = cameras_.model.status(command.camera);
  commands_.model.on_command_sent(std::move(command), status);
}

void ConsoleState::on_recorder_command_sent(PendingRecorderCommand command) {
  std::lock_guard lock(commands_.mutex);
  commands_.model.on_recorder_command_sent(std::move(command));
}

bool ConsoleState::knows_recorder(const std::string& recorder) const {
  std::lock_guard lock(recorders_.mutex);
  return recorders_.model.knows(recorder);
}

void ConsoleState::on_outcome(CommandOutcome outcome) {
  std::lock_guard lock(commands_.mutex);
  commands_.model.on_outcome(std::move(outcome));
}

std::vector<CommandOutcome> ConsoleState::take_outcomes(TimeNs now) {
  std::lock_guard lock(commands_.mutex);
  return commands_.model.take_outcomes(now);
}

void ConsoleState::start_coverage(TimeNs now) {
  std::lock_guard lock(calibration_.mutex);
  calibration_.model.start_coverage(now);
}

void ConsoleState::add_coverage_frame(const std::string& camera, const std::vector<BlobPoint>& blobs) {
  std::optional<std::pair<int, int>> size;
  {
    std::lock_guard lock(cameras_.mutex);
    size = cameras_.model.info_size(camera);
  }
  std::lock_guard lock(calibration_.mutex);
  calibration_.model.add_coverage_frame(camera, blobs, size);
}

void ConsoleState::stop_coverage() {
  std::lock_guard lock(calibration_.mutex);
  calibration_.model.stop_coverage(wall_now_ns());
}

void ConsoleState::set_calibration_job(std::string summary_json, std::string full_json) {
  std::lock_guard lock(calibration_.mutex);
  calibration_.model.set_job(std::move(summary_json), std::move(full_json));
}

std::string ConsoleState::calibration_job() const {
  std::lock_guard lock(calibration_.mutex);
  return calibration_.model.job();
}

json ConsoleState::details(const std::string& kind, const std::string& key, TimeNs now) const {
  std::lock_guard lock(scene_.mutex);
  return scene_.model.details(kind, key, now);
}

json ConsoleState::snapshot(TimeNs now, bool full) const {
  json estimator;
  std::map<std::string, CameraUsageRecord> usage;
  if (full) {
    std::lock_guard lock(estimator_.mutex);
    estimator = estimator_.model.to_json(now);
    usage = estimator_.model.usage();
  }
  json out = {{"type", "state"}, {"full", full}};
  {
    std::lock_guard lock(cameras_.mutex);
    out["cameras"] = cameras_.model.to_json(now, full, usage);
  }
  {
    std::lock_guard lock(scene_.mutex);
    out.update(scene_.model.to_json(now, full));
  }
  if (!full) return out;
  if (!estimator.is_null()) out["estimator"] = std::move(estimator);
  {
    std::lock_guard lock(recorders_.mutex);
    out.update(recorders_.model.to_json(now));
  }
  std::lock_guard lock(calibration_.mutex);
  out["calibration"] = calibration_.model.to_json(now);
  return out;
}

}  // namespace panoptes::console
