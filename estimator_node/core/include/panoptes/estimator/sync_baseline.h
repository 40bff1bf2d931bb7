// SPDX-License-Identifier: Apache-2.0
// SyncBaseline: the naive synchronous estimator the one-camera-at-a-time EKF is measured against
// (seed 003 §2.2.3.1 and Fig. 2.5). On every camera frame it takes each camera's latest frame,
// triangulates one marker from them as if they had all been taken at the same instant, and stamps
// the result with the newest frame's stamp. It tracks a single marker and has no motion model:
// it exists for comparisons (tests, benchmarks), not for production.
#pragma once

#include <map>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/camera_model.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

struct SyncBaselineOptions {
  // A camera whose latest frame is older than this (relative to the newest) is left out, as a
  // synchronous system would leave out a camera that missed the trigger.
  TimeNs max_frame_age_ns = 100 * kNsPerMillisecond;
  // A triangulation whose worst reprojection error exceeds this is not reported. Generous: the
  // point of the baseline is to show the error of treating asynchronous frames as simultaneous.
  double max_reprojection_px = 50.0;
};

struct SyncEstimate {
  TimeNs stamp_ns = 0;  // the newest frame used
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  int cameras = 0;  // frames used
  double max_reprojection_px = 0;
};

class SyncBaseline {
 public:
  explicit SyncBaseline(SyncBaselineOptions options = {});

  // Cameras without T_world_cam are ignored.
  void set_calibration(const SystemCalibration& calibration);

  // Takes one camera frame (in stamp order) and returns the estimate stamped at this frame if at
  // least two cameras have a recent blob and the triangulation succeeds. The blob used from each
  // camera is the one nearest to the projection of the previous estimate (the first blob before
  // there is one). Frames from unknown cameras are ignored (nullopt).
  std::optional<SyncEstimate> process(const FeatureFrame& frame);

  const std::optional<SyncEstimate>& last_estimate() const { return last_; }
  std::uint64_t estimates() const { return estimates_; }

 private:
  struct Latest {
    TimeNs stamp_ns = 0;
    std::optional<Eigen::Vector2d> pixel;
  };

  SyncBaselineOptions options_;
  std::map<std::string, CameraModel> cameras_;
  std::map<std::string, Latest> latest_;
  std::optional<SyncEstimate> last_;
  std::uint64_t estimates_ = 0;
};

}  // namespace panoptes::estimator
