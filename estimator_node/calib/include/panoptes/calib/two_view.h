// SPDX-License-Identifier: Apache-2.0
// Stage 1 of the wand solver: the relative pose of every pair of cameras that saw the wand at
// enough common instants (seed 003 §3.3.1; seed 000 §4.5): five-point essential matrix with
// RANSAC, two-view triangulation, the residual that ranks the pair, and the metric scale from the
// wand's length (seed 000 §4.5.8). docs/calibration.md, "Stages".
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calib/solve_stats.h"
#include "panoptes/calib/wand_samples.h"
#include "panoptes/calibration.h"

namespace panoptes::calib {

// Camera b relative to camera a: x_a = R_ab x_b + c_b (c_b: b's centre in a's frame; metres with
// a metric wand, else the unit baseline).
struct RelativePose {
  Eigen::Matrix3d R_ab = Eigen::Matrix3d::Identity();
  Eigen::Vector3d c_b = Eigen::Vector3d::Zero();
};

struct TwoViewOptions {
  int min_pair_samples = 25;   // common instants needed
  int max_pair_samples = 400;  // subsampled (evenly) for the RANSAC and the residual
  double ransac_threshold_px = 1.0;
};

// The wand as two cameras saw it at one instant: measured pixels in wand order.
struct WandPixelPair {
  std::vector<Eigen::Vector2d> a, b;
};

struct TwoViewResult {
  int samples = 0;         // common instants given
  int inliers = 0;         // of the essential matrix (marker correspondences)
  double residual_px = 0;  // RMS reprojection of the two-view reconstruction
  double scale = 0;        // metres per unit baseline (0 without a metric wand)
  double score = 0;        // rank of the pair: lower is better (residual, penalised under 100 inliers)
  std::optional<RelativePose> pose;  // absent: too few instants, no essential matrix, too few inliers
};

// The relative pose of two cameras from the wand seen by both (intrinsics as given).
TwoViewResult solve_two_view(const CameraIntrinsics& intrinsics_a, const CameraIntrinsics& intrinsics_b,
                             const std::vector<WandPixelPair>& common, const WandDefinition& wand,
                             const TwoViewOptions& options);

// A solved pair, by camera index (a < b).
struct PairPose {
  int a = 0, b = 0;
  RelativePose pose;
  double score = 0;
  std::size_t edge_index = 0;  // into PairwiseResult::edges
};

struct PairwiseResult {
  std::vector<PairEdge> edges;  // every pair with common instants, ascending (a, b)
  std::vector<PairPose> pairs;  // the pairs that gave a relative pose
  std::size_t pairs_with_common = 0;
};

// solve_two_view for every pair of cameras with common instants (observations at offset 0).
PairwiseResult pairwise_relative_poses(const std::vector<CameraCalibration>& cameras,
                                       const std::vector<WandInstant>& instants, const WandDefinition& wand,
                                       const TwoViewOptions& options,
                                       const std::function<void(const std::string&)>& progress = {});

}  // namespace panoptes::calib
