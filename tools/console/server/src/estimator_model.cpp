// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/estimator_model.h"

#include <nlohmann/json.hpp>

#include "json_helpers.h"

namespace panoptes::console {

using detail::round_to;

void EstimatorModel::on_status(EstimatorRecord status, TimeNs now) {
  status_ = std::move(status);
  status_ns_ = now;
}

std::map<std::string, CameraUsageRecord> EstimatorModel::usage() const {
  return status_ ? status_->cameras : std::map<std::string, CameraUsageRecord>{};
}

nlohmann::json EstimatorModel::to_json(TimeNs now) const {
  if (!status_) return nullptr;
  // The cameras the estimator has lost, with their silence, and those a second writer claimed.
  nlohmann::json lost = nlohmann::json::array();
  nlohmann::json refused = nlohmann::json::array();
  for (const auto& [id, camera] : status_->cameras) {
    if (camera.state == "lost")
      lost.push_back({{"id", id}, {"since_s", round_to(camera.since_last_frame_s, 1)}});
    if (camera.refused_frames > 0) refused.push_back({{"id", id}, {"frames", camera.refused_frames}});
  }
  return {{"tracks_confirmed", status_->tracks_confirmed},
          {"tracks_tentative", status_->tracks_tentative},
          {"tracks_coasting", status_->tracks_coasting},
          {"tracks_unobserved", status_->tracks_unobserved},
          {"cameras_live", status_->cameras_live},
          {"cameras_lost", status_->cameras_lost},
          {"lost", std::move(lost)},
          {"refused", std::move(refused)},
          {"cpu_percent", round_to(status_->cpu_percent, 1)},
          {"update_p99_ms", round_to(status_->update_p99_ms, 3)},
          {"age_s", detail::seconds(now - status_ns_, 1)}};
}

}  // namespace panoptes::console
