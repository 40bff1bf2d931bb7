// SPDX-License-Identifier: Apache-2.0
// The console's view of the estimator: its latest status (rt/panoptes/estimator_status) and when it
// arrived. Not thread-safe: ConsoleState guards it.
#pragma once

#include <map>
#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/console_records.h"

namespace panoptes::console {

class EstimatorModel {
 public:
  void on_status(EstimatorRecord status, TimeNs now);

  bool has_status() const { return status_.has_value(); }
  // Each camera's use by the estimator, from its latest status (empty before the first).
  std::map<std::string, CameraUsageRecord> usage() const;

  // The full snapshot's "estimator": the track counts, its CPU and update p99, and the status's age.
  // Null before the first status (the snapshot then has no "estimator").
  nlohmann::json to_json(TimeNs now) const;

 private:
  std::optional<EstimatorRecord> status_;
  TimeNs status_ns_ = 0;
};

}  // namespace panoptes::console
