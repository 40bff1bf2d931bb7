// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/calibration_model.h"

#include <nlohmann/json.hpp>

#include "json_helpers.h"

namespace panoptes::console {

using nlohmann::json;

void CalibrationModel::start_coverage(TimeNs now) {
  coverage_.clear();
  active_ = true;
  start_ns_ = now;
}

void CalibrationModel::add_coverage_frame(const std::string& camera, const std::vector<BlobPoint>& blobs,
                                          std::optional<std::pair<int, int>> image_size) {
  Coverage& coverage = coverage_[camera];
  ++coverage.frames;
  if (!blobs.empty()) ++coverage.frames_with_blobs;
  if (image_size) coverage.grid.set_size(image_size->first, image_size->second);
  for (const BlobPoint& blob : blobs) coverage.grid.add(blob.x, blob.y);
}

void CalibrationModel::stop_coverage(TimeNs now) {
  if (active_) stop_ns_ = now;
  active_ = false;
}

void CalibrationModel::set_job(std::string summary_json, std::string full_json) {
  job_ = std::move(summary_json);
  job_full_ = std::move(full_json);
}

json CalibrationModel::to_json(TimeNs now) const {
  json cameras = json::array();
  for (const auto& [id, coverage] : coverage_) {
    cameras.push_back({{"id", id},
                       {"frames", coverage.frames},
                       {"frames_with_blobs", coverage.frames_with_blobs},
                       {"coverage_percent", coverage.grid.percent()},
                       {"cells", coverage.grid.cells()}});
  }
  const TimeNs end = active_ ? now : stop_ns_;
  return {{"capturing", active_},
          {"seconds", start_ns_ == 0 ? 0.0 : detail::seconds(end - start_ns_, 1)},
          {"cameras", std::move(cameras)},
          {"job", json::parse(job_, nullptr, false)}};
}

}  // namespace panoptes::console
