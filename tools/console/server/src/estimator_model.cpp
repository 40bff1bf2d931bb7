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
  return {{"tracks_confirmed", status_->tracks_confirmed},
          {"tracks_tentative", status_->tracks_tentative},
          {"cpu_percent", round_to(status_->cpu_percent, 1)},
          {"update_p99_ms", round_to(status_->update_p99_ms, 3)},
          {"age_s", detail::seconds(now - status_ns_, 1)}};
}

}  // namespace panoptes::console
