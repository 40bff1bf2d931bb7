// SPDX-License-Identifier: Apache-2.0
// In-memory records shared by the nodes (their JSON Lines files: panoptes/jsonl.h).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "panoptes/time.h"

namespace panoptes {

struct Blob {
  double x = 0, y = 0;                 // sub-pixel centroid, pixels
  double area = 0;                     // pixels above threshold
  double sum = 0;                      // intensity sum over the blob
  int peak = 0;                        // brightest pixel value
  double m20 = 0, m11 = 0, m02 = 0;    // central second moments (pixels^2), intensity weighted
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // bounding box of the pixels above threshold, [x0, x1) x [y0, y1)
};

struct FeatureFrame {
  std::string camera_id;
  std::int64_t frame = 0;
  TimeNs stamp_ns = 0;       // mid-exposure, common time base
  TimeNs arrival_ns = 0;     // when the image reached the node (0 if unknown)
  TimeNs processing_ns = 0;  // detection time
  TimeNs publish_ns = 0;     // when camera_node wrote the frame to DDS (0 if unknown)
  TimeNs received_ns = 0;    // when the frame reached the estimator, on the estimator's clock; 0 if unknown
  std::vector<Blob> blobs;
};

enum class TrackStatus { kTentative, kConfirmed, kCoasting };
std::string_view to_string(TrackStatus status);

struct TrackRecord {
  TimeNs stamp_ns = 0;
  std::int64_t id = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  std::array<double, 6> position_covariance{};  // xx xy xz yy yz zz
  TrackStatus status = TrackStatus::kConfirmed;
  int cameras = 0;  // cameras that updated the track recently
};

struct PoseRecord {
  TimeNs stamp_ns = 0;
  std::string body;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector4d q = Eigen::Vector4d(0, 0, 0, 1);  // x, y, z, w
  // Optional (extra JSON keys "v", "w", "horizon_ns", "quality", "cameras", "cov"):
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  // linear velocity, world, m/s
  Eigen::Vector3d w = Eigen::Vector3d::Zero();  // angular velocity, world, rad/s
  TimeNs horizon_ns = 0;                        // the pose is predicted this far past stamp_ns
  double quality = 0.0;                         // fraction of the markers seen recently, 0..1
  int cameras = 0;                              // cameras that updated the body recently
  std::array<double, 6> sigma{};                // 1-σ: x, y, z (m), rotation about x, y, z (rad)
};

}  // namespace panoptes
