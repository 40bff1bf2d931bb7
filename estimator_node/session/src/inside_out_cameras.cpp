// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/inside_out_cameras.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "panoptes/errors.h"
#include "panoptes/session/log.h"

namespace panoptes::session {

namespace est = panoptes::estimator;

void InsideOutCameras::configure(const std::vector<LandmarkGroup>& landmarks,
                                 const std::vector<CameraCalibration>& moving,
                                 const std::string& landmarks_file, const InsideOutSettings& settings) {
  settings_ = settings;
  std::vector<est::Constellation> constellations;
  constellations.reserve(landmarks.size());
  for (const LandmarkGroup& group : landmarks)
    constellations.push_back({group.name, group.points, group.constellation});
  std::map<std::string, Rig> rigs;
  for (const CameraCalibration& camera : moving) {
    // The mount on the rig; CameraModel reads T_world_cam, which landmark_pixel takes as T_rig_cam.
    const CameraModel camera_in_rig(camera.intrinsics, camera.T_world_cam.value_or(RigidTransform{}));
    try {
      rigs.emplace(camera.id, Rig{camera.rig.empty() ? camera.id : camera.rig,
                                  est::InsideOutTracker(constellations, camera_in_rig, settings.tracker),
                                  {}});
    } catch (const std::invalid_argument& error) {
      throw ConfigError(landmarks_file, "landmarks", error.what());
    }
  }
  rigs_ = std::move(rigs);
}

void InsideOutCameras::set_outside_in(const SystemCalibration& fixed, const RigMarkers& rig_markers,
                                      const std::string& landmarks_file) {
  for (const auto& entry : rig_markers) {
    const std::string& name = entry.first;
    const auto rig = std::find_if(rigs_.begin(), rigs_.end(),
                                  [&](const auto& camera_rig) { return camera_rig.second.name == name; });
    if (rig == rigs_.end())
      throw ConfigError(landmarks_file, "rig_markers." + name,
                        "no camera marked moving: true is carried by rig '" + name + "'");
    rig->second.markers = entry.second;
  }
  fixed_cameras_.clear();
  if (rig_markers.empty()) return;
  for (const CameraCalibration& camera : fixed.cameras)
    if (camera.T_world_cam) fixed_cameras_.emplace(camera.id, camera.model());
}

void InsideOutCameras::observe_fixed(const FeatureFrame& frame) {
  const auto camera = fixed_cameras_.find(frame.camera_id);
  if (camera == fixed_cameras_.end()) return;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(frame.blobs.size());
  for (const Blob& blob : frame.blobs)
    if (std::isfinite(blob.x) && std::isfinite(blob.y)) pixels.emplace_back(blob.x, blob.y);
  for (auto& [camera_id, rig] : rigs_)
    if (!rig.markers.empty())
      rig.tracker.add_outside_in_frame(frame.stamp_ns, camera->second, rig.markers, pixels);
}

est::FrameOutcome InsideOutCameras::process(const FeatureFrame& frame) {
  Rig& rig = rigs_.at(frame.camera_id);
  // A bad blob is dropped, never given to the filter; a cold start sees the brightest blobs.
  std::vector<const Blob*> blobs;
  for (const Blob& blob : frame.blobs)
    if (std::isfinite(blob.x) && std::isfinite(blob.y)) blobs.push_back(&blob);
  if (!rig.tracker.tracking() && blobs.size() > settings_.acquire_max_blobs) {
    std::stable_sort(blobs.begin(), blobs.end(),
                     [](const Blob* a, const Blob* b) { return a->sum > b->sum; });
    blobs.resize(settings_.acquire_max_blobs);
  }
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(blobs.size());
  for (const Blob* blob : blobs) pixels.emplace_back(blob->x, blob->y);
  const std::uint64_t late_before = rig.tracker.counters().late_frames;
  const auto pose = rig.tracker.add_frame(frame.stamp_ns, pixels);
  est::CameraCounters& counters = counters_[frame.camera_id];
  ++counters.frames;
  counters.blobs += frame.blobs.size();
  if (rig.tracker.counters().late_frames != late_before) {
    ++counters.too_late;
    return est::FrameOutcome::kTooLate;
  }
  ++counters.used;
  if (pose) counters.associated += static_cast<std::uint64_t>(pose->landmarks);
  counters.last_stamp_ns = std::max(counters.last_stamp_ns, frame.stamp_ns);
  last_stamp_ns_ = std::max(last_stamp_ns_, frame.stamp_ns);
  return est::FrameOutcome::kProcessed;
}

std::vector<BodyDefinition> InsideOutCameras::rig_descriptions() const {
  std::map<std::string, BodyDefinition> by_name;
  for (const auto& [camera_id, rig] : rigs_) {
    BodyDefinition& description = by_name[rig.name];
    description.name = rig.name;
    if (description.markers.empty()) description.markers = rig.markers;
  }
  std::vector<BodyDefinition> descriptions;
  descriptions.reserve(by_name.size());
  for (auto& [name, description] : by_name) descriptions.push_back(std::move(description));
  return descriptions;
}

std::vector<PoseRecord> InsideOutCameras::poses_at(TimeNs stamp_ns, TimeNs horizon_ns) const {
  std::vector<PoseRecord> poses;
  for (const auto& [camera_id, rig] : rigs_) {
    const auto& state = rig.tracker.state();
    const est::InsideOutOptions& options = rig.tracker.options();
    // Reported only while its newest frame (of its camera, or of a fixed camera seeing its markers)
    // updated the filter: a prediction across dropped or unmatched frames of a head turning at
    // 3 rad/s can be degrees off, and is never published as a pose.
    if (!state || state->stamp_ns != rig.tracker.last_update_ns()) continue;
    const est::BodyState at = est::predicted(*state, std::max(stamp_ns, state->stamp_ns), options.motion);
    const double horizon_s = ns_to_seconds(horizon_ns);
    const RigidTransform pose = est::extrapolate_pose(at, horizon_s);
    PoseRecord record;
    record.stamp_ns = at.stamp_ns;
    record.body = rig.name;
    record.p = pose.t;
    record.q = Eigen::Vector4d(pose.q.x(), pose.q.y(), pose.q.z(), pose.q.w());
    record.v = at.v + horizon_s * at.a;
    record.w = pose.q * (at.w + horizon_s * at.alpha);
    record.horizon_ns = horizon_ns;
    record.quality = 1.0;
    record.cameras = 1;
    for (int k = 0; k < 3; ++k) {
      record.sigma[static_cast<std::size_t>(k)] =
          std::sqrt(std::max(0.0, at.P(est::kBodyP + k, est::kBodyP + k)));
      record.sigma[3 + static_cast<std::size_t>(k)] =
          std::sqrt(std::max(0.0, at.P(est::kBodyTheta + k, est::kBodyTheta + k)));
    }
    poses.push_back(std::move(record));
  }
  return poses;
}

std::vector<std::string> InsideOutCameras::summary_lines() const {
  std::vector<std::string> lines;
  for (const auto& [camera_id, rig] : rigs_) {
    const est::InsideOutCounters& c = rig.tracker.counters();
    lines.push_back(
        "inside-out '" + rig.name + "' (camera '" + camera_id + "'): frames " + std::to_string(c.frames) +
        ", acquisitions " + std::to_string(c.acquisitions) +
        (rig.tracker.acquired_from().empty() ? "" : " (last from '" + rig.tracker.acquired_from() + "')") +
        ", failed " + std::to_string(c.failed_acquisitions) + ", landmark updates " +
        std::to_string(c.updates) + ", frames without update " + std::to_string(c.frames_without_update) +
        ", lost " + std::to_string(c.lost) + ", late " + std::to_string(c.late_frames) +
        (rig.markers.empty() ? "" : ", outside-in marker updates " + std::to_string(c.outside_in_updates)));
  }
  return lines;
}

std::vector<CameraCalibration> take_moving_cameras(SystemCalibration& calibration) {
  std::vector<CameraCalibration> moving;
  auto& cameras = calibration.cameras;
  for (auto it = cameras.begin(); it != cameras.end();) {
    if (it->moving) {
      moving.push_back(std::move(*it));
      it = cameras.erase(it);
    } else {
      ++it;
    }
  }
  return moving;
}

void set_up_inside_out(InsideOutCameras& cameras, SystemCalibration& calibration,
                       const std::string& calibration_file, const std::string& landmarks_file) {
  const std::vector<CameraCalibration> moving = take_moving_cameras(calibration);
  if (landmarks_file.empty()) {
    if (!moving.empty())
      throw ConfigError(calibration_file, "cameras",
                        "camera '" + moving.front().id +
                            "' is moving: true, but no landmarks are given (inside-out tracking needs "
                            "--landmarks <file>, docs/inside_out.md)");
    return;
  }
  const std::vector<LandmarkGroup> landmarks = load_landmarks(landmarks_file);
  if (moving.empty()) {
    log("landmarks in " + landmarks_file + " unused: no camera in " + calibration_file + " is moving: true");
    return;
  }
  cameras.configure(landmarks, moving, landmarks_file);
  const RigMarkers rig_markers = load_rig_markers(landmarks_file);
  cameras.set_outside_in(calibration, rig_markers, landmarks_file);
  for (const auto& [rig, markers] : rig_markers)
    log("inside-out: rig '" + rig + "' fused with the fixed cameras' view of its " +
        std::to_string(markers.size()) + " markers");
  std::size_t points = 0;
  for (const auto& group : landmarks) points += group.points.size();
  for (const auto& camera : moving)
    log("inside-out: camera '" + camera.id + "' carries rig '" +
        (camera.rig.empty() ? camera.id : camera.rig) + "', tracked from " + std::to_string(points) +
        " landmarks in " + std::to_string(landmarks.size()) + " groups (" + landmarks_file + ")");
}

}  // namespace panoptes::session
