// SPDX-License-Identifier: Apache-2.0
// The console's cameras: each camera's latest info, calibrated geometry, status, features,
// predicted windows and preview, the figures the console derives from them (received rate,
// latency, drops between statuses) and the health light. Not thread-safe: ConsoleState guards it.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/console_records.h"

namespace panoptes::console {

// A light per camera, with the reason a person can act on.
struct Health {
  Light light = Light::kRed;
  std::string reason;
};

// The health light of one camera from what the console knows (pure, tested).
struct HealthInputs {
  bool has_status = false;
  TimeNs since_status_ns = 0;
  bool has_frames = false;
  TimeNs since_frame_ns = 0;
  double camera_fps = 0;       // from the camera's status
  double nominal_rate_hz = 0;  // from camera_info; 0 unknown
  std::uint64_t drops_last_period = 0;
  double detect_p99_ms = 0;
  std::string last_error;
};
Health camera_health(const HealthInputs& inputs, const StateOptions& options);

class CameraModel {
 public:
  explicit CameraModel(const StateOptions& options) : options_(options) {}

  void on_info(const std::string& camera, CameraInfoRecord info);
  void on_status(const std::string& camera, CameraStatusRecord status, TimeNs now);
  void on_features(const std::string& camera, FeatureRecord features, TimeNs now);
  void on_predictions(const std::string& camera, std::vector<PredictedWindowRecord> windows, TimeNs now);
  // False (and nothing kept) when the size does not match the pixels: a bad message, never a bad image.
  bool on_preview(const std::string& camera, TimeNs stamp_ns, int width, int height, std::string pixels);
  void on_calibration(const std::map<std::string, CameraGeometry>& cameras);

  bool knows(const std::string& camera) const;
  // The camera's latest status; nullptr before the first.
  const CameraStatusRecord* status(const std::string& camera) const;
  // Image size from camera_info as sent (possibly 0); nullopt before camera_info.
  std::optional<std::pair<int, int>> info_size(const std::string& camera) const;
  std::optional<std::string> preview_pgm(const std::string& camera) const;
  Health health(const std::string& camera, TimeNs now) const;

  // The snapshot's "cameras" (docs/console.md, "Protocol"): blobs, windows and health, and when
  // `full` the info, geometry, status and, from the estimator's status, the camera's usage.
  nlohmann::json to_json(TimeNs now, bool full, const std::map<std::string, CameraUsageRecord>& usage) const;

 private:
  struct Camera {
    std::optional<CameraInfoRecord> info;
    std::optional<CameraGeometry> calibrated;
    std::optional<CameraStatusRecord> status;
    TimeNs status_ns = 0;
    std::uint64_t drops_last_period = 0;  // drops between the last two statuses
    FeatureRecord features;
    TimeNs features_ns = 0;
    std::vector<PredictedWindowRecord> windows;
    TimeNs windows_ns = 0;
    TimeNs preview_stamp_ns = 0;  // 0: no preview yet
    int preview_width = 0;
    int preview_height = 0;
    std::string preview_pixels;
    std::uint64_t frames_received = 0;
    double latency_ms = 0;  // receive time minus stamp, smoothed
    // Frames received per second, over the last whole second.
    TimeNs rate_window_start_ns = 0;
    std::uint64_t rate_window_frames = 0;
    double received_fps = 0;
  };

  Health health_of(const Camera& camera, TimeNs now) const;
  // Frames per second received as of `now`: 0 once frames stopped for a second.
  static double received_fps_at(const Camera& camera, TimeNs now);
  nlohmann::json camera_json(const std::string& id, const Camera& camera, TimeNs now, bool full,
                             const std::map<std::string, CameraUsageRecord>& usage) const;

  StateOptions options_;
  std::map<std::string, Camera> cameras_;
};

}  // namespace panoptes::console
