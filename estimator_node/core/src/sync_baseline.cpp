// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/sync_baseline.h"

#include <limits>
#include <vector>

#include "panoptes/triangulation.h"

namespace panoptes::estimator {

SyncBaseline::SyncBaseline(SyncBaselineOptions options) : options_(options) {}

void SyncBaseline::set_calibration(const SystemCalibration& calibration) {
  for (const auto& camera : calibration.cameras) {
    if (camera.T_world_cam) cameras_.insert_or_assign(camera.id, camera.model());
  }
}

std::optional<SyncEstimate> SyncBaseline::process(const FeatureFrame& frame) {
  const auto camera = cameras_.find(frame.camera_id);
  if (camera == cameras_.end()) return std::nullopt;

  // The blob of this camera that is the marker: nearest to where the last estimate projects.
  Latest& latest = latest_[frame.camera_id];
  latest.stamp_ns = frame.stamp_ns;
  latest.pixel.reset();
  std::optional<Eigen::Vector2d> predicted;
  if (last_) predicted = camera->second.project(last_->p);
  double best = std::numeric_limits<double>::infinity();
  for (const Blob& blob : frame.blobs) {
    const Eigen::Vector2d pixel(blob.x, blob.y);
    const double distance = predicted ? (pixel - *predicted).squaredNorm() : 0.0;
    if (distance < best) {
      best = distance;
      latest.pixel = pixel;
    }
    if (!predicted) break;
  }

  // Every camera's latest frame, treated as simultaneous with this one.
  std::vector<PixelObservation> observations;
  for (const auto& [id, entry] : latest_) {
    if (!entry.pixel || frame.stamp_ns - entry.stamp_ns > options_.max_frame_age_ns) continue;
    observations.push_back({&cameras_.at(id), *entry.pixel});
  }
  if (observations.size() < 2) return std::nullopt;
  const auto point = triangulate(observations);
  if (!point || !(point->max_reprojection_px <= options_.max_reprojection_px)) return std::nullopt;

  SyncEstimate estimate;
  estimate.stamp_ns = frame.stamp_ns;
  estimate.p = point->point;
  estimate.cameras = static_cast<int>(observations.size());
  estimate.max_reprojection_px = point->max_reprojection_px;
  last_ = estimate;
  ++estimates_;
  return estimate;
}

}  // namespace panoptes::estimator
