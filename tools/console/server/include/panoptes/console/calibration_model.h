// SPDX-License-Identifier: Apache-2.0
// The calibration page's state: the wand capture's live coverage per camera (frames, frames with
// blobs, the 8x8 grid of where blobs were seen, as `estimator_node calibrate capture` prints) and
// the calibration workflow's job (JSON text the workflow writes). Not thread-safe: ConsoleState
// guards it.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/console_records.h"
#include "panoptes/image_coverage.h"

namespace panoptes::console {

class CalibrationModel {
 public:
  // From start on, every camera's frames count (the counts of an earlier capture are cleared).
  void start_coverage(TimeNs now);
  // One frame of `camera`; `image_size` (from its camera_info) sets the grid's extent.
  void add_coverage_frame(const std::string& camera, const std::vector<BlobPoint>& blobs,
                          std::optional<std::pair<int, int>> image_size);
  void stop_coverage(TimeNs now);
  bool capturing() const { return active_; }

  // The job's step and log (in every full snapshot) and the same with the last report and the
  // world-frame summary (served once per step by /api/calibration).
  void set_job(std::string summary_json, std::string full_json);
  const std::string& job() const { return job_full_; }

  // The full snapshot's "calibration": capturing, seconds, each camera's coverage, and the job.
  nlohmann::json to_json(TimeNs now) const;

 private:
  struct Coverage {
    std::uint64_t frames = 0;
    std::uint64_t frames_with_blobs = 0;
    ImageCoverage grid;
  };

  bool active_ = false;
  TimeNs start_ns_ = 0;
  TimeNs stop_ns_ = 0;
  std::map<std::string, Coverage> coverage_;
  std::string job_ = "{}";
  std::string job_full_ = "{}";
};

}  // namespace panoptes::console
