// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/camera_resection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "points_by_x.h"

namespace panoptes::estimator {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

struct Pair {
  Eigen::Vector3d point;
  Eigen::Vector2d pixel;
  double weight = 1.0;
};

// The image shift most (blob - prediction) pairs agree on: votes in cells, the best 3 x 3
// neighbourhood, then the mean of the pairs in it.
Eigen::Vector2d vote_shift(const CameraModel& model, const std::vector<ResectionSample>& samples,
                           const ResectionOptions& o, std::size_t& candidates) {
  std::map<std::pair<long, long>, int> votes;
  std::vector<Eigen::Vector2d> shifts;
  const auto cell_of = [&](const Eigen::Vector2d& d) {
    return std::make_pair(static_cast<long>(std::floor(d.x() / o.vote_cell_px)),
                          static_cast<long>(std::floor(d.y() / o.vote_cell_px)));
  };
  candidates = 0;
  for (const ResectionSample& sample : samples) {
    for (const Eigen::Vector3d& point : sample.points_world) {
      const auto predicted = model.project(point);
      if (!predicted) continue;
      candidates += model.in_image(*predicted) ? 1 : 0;
      for (const Eigen::Vector2d& blob : sample.blobs) {
        const Eigen::Vector2d d = blob - *predicted;
        if (!d.allFinite() || d.norm() > o.vote_radius_px) continue;
        ++votes[cell_of(d)];
        shifts.push_back(d);
      }
    }
  }
  if (votes.empty()) return Eigen::Vector2d::Zero();
  std::pair<long, long> best{0, 0};
  int best_score = -1;
  for (const auto& [cell, count] : votes) {
    int score = 0;
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy) {
        const auto found = votes.find({cell.first + dx, cell.second + dy});
        if (found != votes.end()) score += found->second;
      }
    if (score > best_score) {
      best_score = score;
      best = cell;
    }
  }
  const Eigen::Vector2d centre((static_cast<double>(best.first) + 0.5) * o.vote_cell_px,
                               (static_cast<double>(best.second) + 0.5) * o.vote_cell_px);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double n = 0.0;
  for (const Eigen::Vector2d& d : shifts) {
    if ((d - centre).cwiseAbs().maxCoeff() > 1.5 * o.vote_cell_px) continue;
    sum += d;
    n += 1.0;
  }
  return n > 0.0 ? Eigen::Vector2d(sum / n) : centre;
}

// Each sample's blobs sorted by x, made once per resection for all its associations: comparing
// every prediction with every blob was most of a refinement's time (60 samples of 40 tracks).
std::vector<PointsByX> index_blobs(const std::vector<ResectionSample>& samples) {
  std::vector<PointsByX> indexes;
  indexes.reserve(samples.size());
  for (const ResectionSample& sample : samples) indexes.emplace_back(sample.blobs);
  return indexes;
}

// Each prediction (shifted) with its nearest blob within `radius`, when the next is unique_ratio
// times farther and no other prediction of the sample took the same blob. `in_image`, when given,
// counts the predictions inside the image.
std::vector<Pair> associate(const CameraModel& model, const std::vector<ResectionSample>& samples,
                            const std::vector<PointsByX>& indexes, const Eigen::Vector2d& shift,
                            double radius, double unique_ratio, std::size_t* in_image = nullptr) {
  std::vector<Pair> pairs;
  // A next blob beyond unique_ratio x radius passes whatever its distance: the search stops there.
  const double reach = std::max(1.0, unique_ratio) * radius;
  std::vector<std::pair<std::size_t, std::size_t>> found;  // (point, blob) of one sample
  std::vector<int> takers;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const ResectionSample& sample = samples[s];
    found.clear();
    takers.assign(sample.blobs.size(), 0);
    for (std::size_t i = 0; i < sample.points_world.size(); ++i) {
      const auto predicted = model.project(sample.points_world[i]);
      if (!predicted) continue;
      if (in_image != nullptr && model.in_image(*predicted)) ++*in_image;
      const NearestTwo nearest = indexes[s].nearest_two(*predicted + shift, reach);
      if (nearest.d1 > radius || nearest.d2 < unique_ratio * nearest.d1) continue;
      found.emplace_back(i, nearest.index);
      ++takers[nearest.index];
    }
    for (const auto& [i, j] : found)
      if (takers[j] == 1)
        pairs.push_back(
            {sample.points_world[i], sample.blobs[j], i < sample.weights.size() ? sample.weights[i] : 1.0});
  }
  return pairs;
}

Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle < 1e-15) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle));
}

struct Normal {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
  double squared = 0.0;  // sum of squared residuals of the pairs within `within`
  std::size_t inliers = 0;
};

// The normal equations of the reprojection residuals at T_cam_world, perturbed on the left in the
// camera frame (p_cam -> exp(dθ) p_cam + dt). `huber` > 0: IRLS weights; pairs beyond `within`
// are left out.
Normal normal_equations(const CameraIntrinsics& intrinsics, const RigidTransform& T_cam_world,
                        const std::vector<Pair>& pairs, double huber, double within) {
  const CameraModel model(intrinsics, T_cam_world.inverse());
  Normal n;
  for (const Pair& pair : pairs) {
    const Eigen::Vector3d p_cam = T_cam_world.apply(pair.point);
    Eigen::Matrix<double, 2, 3> J_cam;
    const auto pixel = model.project_camera_point(p_cam, &J_cam);
    if (!pixel) continue;
    const Eigen::Vector2d r = *pixel - pair.pixel;
    const double e = r.norm();
    if (e > within) continue;
    const double w = pair.weight * (huber > 0.0 && e > huber ? huber / e : 1.0);
    Eigen::Matrix<double, 3, 6> d_cam;
    d_cam.leftCols<3>() = -skew(p_cam);
    d_cam.rightCols<3>() = Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 2, 6> J = J_cam * d_cam;
    n.H += w * J.transpose() * J;
    n.g += w * J.transpose() * r;
    n.squared += e * e;
    ++n.inliers;
  }
  return n;
}

// The centre prior (ResectionOptions::centre_prior_mm) added to `n`: the residual (C - C_old)/σ
// with C = -Rᵀt; under the perturbation dC = -Rᵀ dt, so it adds I/σ² to the translation block
// (scaled to pixel units) and R (C - C_old)/σ² to its gradient with the sign of dC's Jacobian.
void add_centre_prior(Normal& n, const RigidTransform& T_cam_world, const Eigen::Vector3d& old_centre,
                      const ResectionOptions& o) {
  if (!(o.centre_prior_mm > 0.0)) return;
  const double sigma_m = 1e-3 * o.centre_prior_mm;
  const double w = o.prior_pixel_sigma_px * o.prior_pixel_sigma_px / (sigma_m * sigma_m);
  const Eigen::Matrix3d R = T_cam_world.q.toRotationMatrix();
  const Eigen::Vector3d centre = -(R.transpose() * T_cam_world.t);
  n.H.bottomRightCorner<3, 3>() += w * Eigen::Matrix3d::Identity();
  n.g.tail<3>() += -w * (R * (centre - old_centre));
}

RigidTransform adjust(const CameraIntrinsics& intrinsics, RigidTransform T_cam_world,
                      const std::vector<Pair>& pairs, const ResectionOptions& o, double within,
                      const Eigen::Vector3d& old_centre) {
  for (int iteration = 0; iteration < o.iterations; ++iteration) {
    Normal n = normal_equations(intrinsics, T_cam_world, pairs, o.huber_px, within);
    if (n.inliers < 6) break;
    add_centre_prior(n, T_cam_world, old_centre, o);
    const Eigen::Matrix<double, 6, 1> delta = -n.H.ldlt().solve(n.g);
    if (!delta.allFinite()) break;
    const Eigen::Quaterniond dq = exp_rotation(delta.head<3>());
    T_cam_world.q = (dq * T_cam_world.q).normalized();
    T_cam_world.t = dq * T_cam_world.t + delta.tail<3>();
    if (delta.norm() < o.converged) break;
  }
  return T_cam_world;
}

// Uncertainty of the pose from the inliers' normal equations scaled by their residual.
void judge(const CameraIntrinsics& intrinsics, const RigidTransform& T_cam_world,
           const std::vector<Pair>& pairs, const ResectionOptions& o, const Eigen::Vector3d& old_centre,
           ResectionResult& result) {
  Normal n = normal_equations(intrinsics, T_cam_world, pairs, 0.0, o.inlier_px);
  result.inliers = n.inliers;
  const double squared = n.squared;
  add_centre_prior(n, T_cam_world, old_centre, o);
  n.squared = squared;
  result.rms_px = n.inliers == 0 ? 0.0 : std::sqrt(n.squared / static_cast<double>(n.inliers));
  if (n.inliers < 6) return;
  // σ² per pixel coordinate from the residuals (2 per pair, 6 parameters), floored at 0.1 px.
  const double dof = std::max(1.0, 2.0 * static_cast<double>(n.inliers) - 6.0);
  const double sigma2 = std::max(n.squared / dof, 0.01);
  const Eigen::Matrix<double, 6, 6> covariance = sigma2 * n.H.inverse();
  if (!covariance.allFinite()) {
    result.rotation_sigma_deg = result.translation_sigma_mm = std::numeric_limits<double>::infinity();
    return;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rotation(covariance.topLeftCorner<3, 3>());
  result.rotation_sigma_deg = std::sqrt(std::max(0.0, rotation.eigenvalues().maxCoeff())) / kDegree;
  // The camera centre's uncertainty: C = -Rᵀ t, so its covariance is that of t seen from the world
  // plus the rotation's lever; the translation block bounds it well enough for a gate.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> translation(covariance.bottomRightCorner<3, 3>());
  result.translation_sigma_mm = 1e3 * std::sqrt(std::max(0.0, translation.eigenvalues().maxCoeff()));
}

}  // namespace

ResectionResult resect_camera(const CameraModel& old_model, const std::vector<ResectionSample>& samples,
                              const ResectionOptions& o) {
  ResectionResult result;
  result.T_world_cam = old_model.T_world_cam();
  const CameraIntrinsics& intrinsics = old_model.intrinsics();
  // Without a vote (a camera near right) the predictions in the image are counted by the first
  // association, which projects them with the same pose.
  const bool vote = o.vote_radius_px > 0.0;
  if (vote) result.shift_px = vote_shift(old_model, samples, o, result.candidates);
  RigidTransform T_cam_world = old_model.T_cam_world();
  const std::vector<PointsByX> indexes = index_blobs(samples);
  for (int round = 0; round < std::max(1, o.rounds); ++round) {
    const CameraModel model(intrinsics, T_cam_world.inverse());
    const Eigen::Vector2d shift = round == 0 ? result.shift_px : Eigen::Vector2d::Zero();
    const double radius = round == 0 ? o.associate_px : std::max(o.inlier_px, o.associate_px / (round + 1));
    const std::vector<Pair> pairs = associate(model, samples, indexes, shift, radius, o.unique_ratio,
                                              round == 0 && !vote ? &result.candidates : nullptr);
    if (pairs.size() < 6) {
      result.reason = "only " + std::to_string(pairs.size()) + " blobs could be paired with tracks (of " +
                      std::to_string(result.candidates) + " predictions in the image)";
      return result;
    }
    // The first round's pairs sit a whole bump from the old pose's projections.
    const double within = round == 0 ? result.shift_px.norm() + 2.0 * radius : 2.0 * radius;
    T_cam_world = adjust(intrinsics, T_cam_world, pairs, o, within, old_model.T_world_cam().t);
  }
  const CameraModel model(intrinsics, T_cam_world.inverse());
  const std::vector<Pair> pairs =
      associate(model, samples, indexes, Eigen::Vector2d::Zero(), o.inlier_px, o.unique_ratio);
  judge(intrinsics, T_cam_world, pairs, o, old_model.T_world_cam().t, result);
  const RigidTransform T_world_cam = T_cam_world.inverse();
  result.rotation_change_deg =
      Eigen::AngleAxisd(T_world_cam.q * old_model.T_world_cam().q.conjugate()).angle() / kDegree;
  result.translation_change_mm = 1e3 * (T_world_cam.t - old_model.T_world_cam().t).norm();
  char text[200];
  if (result.inliers < o.min_inliers) {
    std::snprintf(text, sizeof text, "%zu pairs within %.1f px of the new pose, fewer than %zu",
                  result.inliers, o.inlier_px, o.min_inliers);
  } else if (result.rms_px > o.max_rms_px) {
    std::snprintf(text, sizeof text, "residual %.2f px RMS over %zu pairs, above %.2f px", result.rms_px,
                  result.inliers, o.max_rms_px);
  } else if (result.rotation_sigma_deg > o.max_rotation_sigma_deg ||
             result.translation_sigma_mm > o.max_translation_sigma_mm) {
    std::snprintf(text, sizeof text, "not determined: rotation 1-sigma %.3f deg, translation %.1f mm",
                  result.rotation_sigma_deg, result.translation_sigma_mm);
  } else if (result.rotation_change_deg > o.max_rotation_change_deg ||
             result.translation_change_mm > o.max_translation_change_mm) {
    std::snprintf(
        text, sizeof text,
        "implausible: it would turn the camera by %.2f deg and move it by %.1f mm (bounds %.2f deg, "
        "%.1f mm)",
        result.rotation_change_deg, result.translation_change_mm, o.max_rotation_change_deg,
        o.max_translation_change_mm);
  } else {
    result.ok = true;
    result.T_world_cam = T_world_cam;
    return result;
  }
  result.reason = text;
  return result;
}

}  // namespace panoptes::estimator
