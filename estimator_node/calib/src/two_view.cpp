// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/two_view.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "panoptes/calib/triangulate.h"

namespace panoptes::calib {

namespace {

struct EssentialPose {
  int inliers = 0;
  std::optional<Eigen::Matrix3d> R_ba;
  Eigen::Vector3d t_ba = Eigen::Vector3d::Zero();
};

// Five-point RANSAC on the subsampled normalised correspondences, then the pose in front of both.
EssentialPose essential_pose(const CameraIntrinsics& intrinsics_a, const CameraIntrinsics& intrinsics_b,
                             const std::vector<WandPixelPair>& common, std::size_t stride,
                             std::size_t markers, double ransac_threshold_px) {
  EssentialPose out;
  const CameraModel model_a(intrinsics_a, RigidTransform{});
  const CameraModel model_b(intrinsics_b, RigidTransform{});
  std::vector<cv::Point2d> points_a, points_b;
  for (std::size_t s = 0; s < common.size(); s += stride)
    for (std::size_t m = 0; m < markers; ++m) {
      const Eigen::Vector2d xa = model_a.pixel_to_normalized(common[s].a[m]);
      const Eigen::Vector2d xb = model_b.pixel_to_normalized(common[s].b[m]);
      points_a.emplace_back(xa.x(), xa.y());
      points_b.emplace_back(xb.x(), xb.y());
    }
  const double focal = 0.25 * (intrinsics_a.fx + intrinsics_a.fy + intrinsics_b.fx + intrinsics_b.fy);
  cv::Mat mask;
  const cv::Mat E = cv::findEssentialMat(points_a, points_b, 1.0, cv::Point2d(0, 0), cv::RANSAC, 0.999,
                                         ransac_threshold_px / focal, mask);
  if (E.rows != 3 || E.cols != 3) return out;
  cv::Mat R, t;
  out.inliers = cv::recoverPose(E, points_a, points_b, R, t, 1.0, cv::Point2d(0, 0), mask);
  if (out.inliers < std::max<int>(8, static_cast<int>(0.5 * static_cast<double>(points_a.size()))))
    return out;
  Eigen::Matrix3d R_ba;
  for (int r = 0; r < 3; ++r) {
    out.t_ba[r] = t.at<double>(r);
    for (int c = 0; c < 3; ++c) R_ba(r, c) = R.at<double>(r, c);
  }
  out.R_ba = R_ba;
  return out;
}

}  // namespace

TwoViewResult solve_two_view(const CameraIntrinsics& intrinsics_a, const CameraIntrinsics& intrinsics_b,
                             const std::vector<WandPixelPair>& common, const WandDefinition& wand,
                             const TwoViewOptions& options) {
  TwoViewResult result;
  result.samples = static_cast<int>(common.size());
  if (result.samples < options.min_pair_samples || common.empty()) return result;
  const std::size_t markers = wand.marker_count();
  const std::size_t stride =
      std::max<std::size_t>(1, common.size() / static_cast<std::size_t>(options.max_pair_samples));
  const EssentialPose essential =
      essential_pose(intrinsics_a, intrinsics_b, common, stride, markers, options.ransac_threshold_px);
  result.inliers = essential.inliers;
  if (!essential.R_ba) return result;
  const Eigen::Matrix3d& R_ba = *essential.R_ba;
  const Eigen::Vector3d& t_ba = essential.t_ba;
  // Two-view reconstruction in a's frame with unit baseline: residual and wand scale.
  RigidTransform T_world_a;  // a at the origin
  RigidTransform T_world_b;
  T_world_b.q = Eigen::Quaterniond(R_ba.transpose());
  T_world_b.t = -R_ba.transpose() * t_ba;
  const CameraModel ma(intrinsics_a, T_world_a), mb(intrinsics_b, T_world_b);
  const double max_squared = 25.0 * options.ransac_threshold_px * options.ransac_threshold_px;
  double squared = 0;
  int count = 0;
  std::vector<double> lengths;
  for (std::size_t s = 0; s < common.size(); s += stride) {
    std::vector<Eigen::Vector3d> X;
    bool all = true;
    for (std::size_t m = 0; m < markers; ++m) {
      const Eigen::Vector2d& pa = common[s].a[m];
      const Eigen::Vector2d& pb = common[s].b[m];
      const auto x = triangulate({ma, mb}, {pa, pb});
      if (!x) {
        all = false;
        continue;
      }
      const double ea = (*ma.project(*x) - pa).squaredNorm(), eb = (*mb.project(*x) - pb).squaredNorm();
      if (ea + eb > max_squared) {
        all = false;
        continue;
      }
      squared += ea + eb;
      count += 2;
      X.push_back(*x);
    }
    if (all && markers >= 2) lengths.push_back((X.back() - X.front()).norm());
  }
  if (count == 0) return result;
  result.residual_px = std::sqrt(squared / count);
  if (!lengths.empty()) {
    std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
    result.scale = wand.length() / lengths[lengths.size() / 2];
  }
  RelativePose pose;
  pose.R_ab = R_ba.transpose();
  pose.c_b = -R_ba.transpose() * t_ba * (result.scale > 0 ? result.scale : 1.0);
  result.pose = pose;
  // Seed 003 §3.3.1 ranks pairs by their structure-from-motion residual; few correspondences
  // make a residual look better than it is, so pairs under 100 inliers are penalised.
  result.score = (result.residual_px + 0.01) * std::sqrt(100.0 / std::min(100, result.inliers));
  return result;
}

PairwiseResult pairwise_relative_poses(const std::vector<CameraCalibration>& cameras,
                                       const std::vector<WandInstant>& instants, const WandDefinition& wand,
                                       const TwoViewOptions& options,
                                       const std::function<void(const std::string&)>& progress) {
  const std::size_t markers = wand.marker_count();
  // Common instants per pair (a < b), the wand's pixels at offset 0.
  std::map<std::pair<int, int>, std::vector<WandPixelPair>> common;
  const auto pixels = [&](const InstantObservation& observation) {
    std::vector<Eigen::Vector2d> out;
    out.reserve(markers);
    for (std::size_t m = 0; m < markers; ++m) out.push_back(observed_pixel(observation, m, 0.0));
    return out;
  };
  for (const auto& instant : instants)
    for (std::size_t i = 0; i < instant.observations.size(); ++i)
      for (std::size_t j = i + 1; j < instant.observations.size(); ++j) {
        const auto* first = &instant.observations[i];
        const auto* second = &instant.observations[j];
        if (second->camera < first->camera) std::swap(first, second);
        common[{first->camera, second->camera}].push_back({pixels(*first), pixels(*second)});
      }
  PairwiseResult result;
  result.pairs_with_common = common.size();
  for (const auto& [key, list] : common) {
    const auto [a, b] = key;
    const TwoViewResult two_view =
        solve_two_view(cameras[a].intrinsics, cameras[b].intrinsics, list, wand, options);
    PairEdge edge;
    edge.camera_a = cameras[a].id;
    edge.camera_b = cameras[b].id;
    edge.samples = two_view.samples;
    edge.inliers = two_view.inliers;
    edge.residual_px = two_view.residual_px;
    edge.scale = two_view.scale;
    if (two_view.pose) {
      result.pairs.push_back({a, b, *two_view.pose, two_view.score, result.edges.size()});
      if (progress && result.pairs.size() % 10 == 0)
        progress("pairwise relative poses: " + std::to_string(result.pairs.size()) + " pairs");
    }
    result.edges.push_back(edge);
  }
  return result;
}

}  // namespace panoptes::calib
