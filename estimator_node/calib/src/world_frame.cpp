// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/world_frame.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Dense>

#include "panoptes/calib/wand_solver.h"

namespace panoptes::calib {

namespace {

RigidTransform frame_from_axes(const Eigen::Vector3d& origin, Eigen::Vector3d x, Eigen::Vector3d z) {
  z.normalize();
  x = (x - x.dot(z) * z);
  if (x.norm() < 1e-9) x = z.unitOrthogonal();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R_new_old;
  R_new_old.row(0) = x.transpose();
  R_new_old.row(1) = y.transpose();
  R_new_old.row(2) = z.transpose();
  RigidTransform T;
  T.q = Eigen::Quaterniond(R_new_old).normalized();
  T.t = -(R_new_old * origin);
  return T;
}

// Least-squares plane: centroid and unit normal; `flatness` = smallest / middle singular value.
void fit_plane(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d& centroid, Eigen::Vector3d& normal,
               double& flatness) {
  centroid.setZero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  normal = eigen.eigenvectors().col(0);
  flatness = eigen.eigenvalues()(1) > 0
                 ? std::sqrt(std::max(0.0, eigen.eigenvalues()(0)) / eigen.eigenvalues()(1))
                 : 1.0;
}

}  // namespace

RigidTransform provisional_world_frame(const std::vector<RigidTransform>& T_world_cam,
                                       const std::vector<Eigen::Vector3d>& points) {
  if (T_world_cam.empty()) return {};
  // Cameras are mounted upright: their image "up" (-y) averages to the world's up.
  Eigen::Vector3d image_up = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> centers;
  for (const auto& T : T_world_cam) {
    image_up -= T.rotation().col(1);
    centers.push_back(T.t);
  }
  Eigen::Vector3d up = image_up.normalized();
  if (centers.size() >= 3) {
    Eigen::Vector3d centroid, normal;
    double flatness = 1.0;
    fit_plane(centers, centroid, normal, flatness);
    // Cameras around a room or along a corridor are hung at about one height: the plane through
    // them is level. Trust it only when it is well defined and agrees with the image up.
    if (flatness < 0.3 && std::abs(normal.dot(up)) > 0.7)
      up = normal.dot(up) > 0 ? normal : Eigen::Vector3d(-normal);
  }
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (!points.empty()) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    std::vector<double> heights;
    for (const auto& p : points) {
      centroid += p;
      heights.push_back(p.dot(up));
    }
    centroid /= static_cast<double>(points.size());
    const std::size_t low = heights.size() / 50;
    std::nth_element(heights.begin(), heights.begin() + static_cast<std::ptrdiff_t>(low), heights.end());
    origin = centroid - (centroid.dot(up) - heights[low]) * up;
  }
  return frame_from_axes(origin, T_world_cam.front().t - origin, up);
}

void apply_world_transform(SolveResult& result, const RigidTransform& T_new_old) {
  for (auto& camera : result.cameras)
    if (camera.T_world_cam) camera.T_world_cam = T_new_old * *camera.T_world_cam;
  for (auto& sample : result.samples)
    for (auto& p : sample.markers) p = T_new_old.apply(p);
}

void apply_world_transform(SystemCalibration& calibration, const RigidTransform& T_new_old, double scale) {
  for (auto& camera : calibration.cameras)
    if (camera.T_world_cam) {
      camera.T_world_cam = T_new_old * *camera.T_world_cam;
      camera.T_world_cam->t *= scale;
    }
}

std::optional<RigidTransform> floor_frame(const std::vector<Eigen::Vector3d>& floor_points,
                                          const Eigen::Vector3d& up_hint, std::string* error) {
  if (floor_points.size() < 3) {
    if (error) *error = "need at least 3 floor points, found " + std::to_string(floor_points.size());
    return std::nullopt;
  }
  Eigen::Vector3d centroid, normal;
  double flatness = 1.0;
  fit_plane(floor_points, centroid, normal, flatness);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : floor_points) scatter += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  if (eigen.eigenvalues()(1) < 1e-4 * static_cast<double>(floor_points.size())) {
    if (error) *error = "floor points are (nearly) on one line: spread them over the floor";
    return std::nullopt;
  }
  if (normal.dot(up_hint - centroid) < 0) normal = -normal;
  return frame_from_axes(centroid, floor_points[1] - floor_points[0], normal);
}

std::optional<RigidTransform> lframe_frame(const std::vector<Eigen::Vector3d>& points,
                                           const Eigen::Vector3d& up_hint, double x_arm_m, double y_arm_m,
                                           std::string* error, double* scale) {
  if (scale != nullptr && !(x_arm_m > 0 && y_arm_m > 0)) {
    if (error) *error = "an unscaled calibration needs the L-frame's arm lengths to set its scale";
    return std::nullopt;
  }
  double best = 1e9;
  std::optional<RigidTransform> frame;
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < n; ++k) {
        if (i == j || j == k || i == k) continue;
        const Eigen::Vector3d x = points[j] - points[i], y = points[k] - points[i];
        if (x.norm() < 1e-9 || y.norm() < 1e-9) continue;
        const double cosine = std::abs(x.normalized().dot(y.normalized()));
        if (cosine > 0.1) continue;
        double cost = cosine;
        // Metres per unit: 1 for a metric calibration; for an unscaled one the least-squares fit of
        // the two arms, after which they are judged like metric ones.
        double s = 1.0;
        if (scale != nullptr)
          s = (x.norm() * x_arm_m + y.norm() * y_arm_m) / (x.squaredNorm() + y.squaredNorm());
        if (x_arm_m > 0 && y_arm_m > 0) {
          const double dx = std::abs(s * x.norm() - x_arm_m), dy = std::abs(s * y.norm() - y_arm_m);
          if (dx > 0.02 || dy > 0.02) continue;
          cost += (dx + dy) * 10;
        } else if (x.norm() <= y.norm()) {
          continue;  // the longer arm is x
        }
        if (cost < best) {
          best = cost;
          Eigen::Vector3d z = x.cross(y);
          if (z.dot(up_hint - points[i]) < 0) z = -z;
          frame = frame_from_axes(points[i], x, z);
          if (scale != nullptr) *scale = s;
        }
      }
  if (!frame && error)
    *error = "no three of the " + std::to_string(n) + " triangulated markers form an L (right angle" +
             (x_arm_m > 0 ? std::string(", arm lengths as given") : std::string()) + ")";
  return frame;
}

std::vector<Eigen::Vector3d> triangulate_static_markers(const SystemCalibration& calibration,
                                                        const std::vector<FeatureFrame>& frames,
                                                        double cluster_px, double match_px) {
  struct Cluster {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int count = 0;
    Eigen::Vector2d mean() const { return sum / count; }
  };
  std::map<std::string, std::vector<Cluster>> clusters;
  std::map<std::string, int> frame_count;
  for (const auto& frame : frames) {
    if (!calibration.find(frame.camera_id)) continue;
    ++frame_count[frame.camera_id];
    auto& list = clusters[frame.camera_id];
    for (const auto& blob : frame.blobs) {
      const Eigen::Vector2d p(blob.x, blob.y);
      Cluster* hit = nullptr;
      for (auto& cluster : list)
        if ((cluster.mean() - p).norm() < cluster_px) hit = &cluster;
      if (hit == nullptr) {
        list.emplace_back();
        hit = &list.back();
      }
      hit->sum += p;
      hit->count += 1;
    }
  }
  struct View {
    CameraModel model;
    std::vector<Eigen::Vector2d> points;
    std::vector<bool> used;
  };
  std::vector<View> views;
  for (const auto& [id, list] : clusters) {
    const auto* camera = calibration.find(id);
    if (!camera || !camera->T_world_cam) continue;
    View view{camera->model(), {}, {}};
    for (const auto& cluster : list)
      if (cluster.count * 2 >= frame_count[id]) view.points.push_back(cluster.mean());
    view.used.assign(view.points.size(), false);
    views.push_back(std::move(view));
  }
  struct Candidate {
    Eigen::Vector3d X;
    std::vector<std::pair<std::size_t, std::size_t>> support;  // (view, point)
    double error = 0;
  };
  std::vector<Candidate> candidates;
  for (std::size_t a = 0; a < views.size(); ++a)
    for (std::size_t b = a + 1; b < views.size(); ++b)
      for (std::size_t i = 0; i < views[a].points.size(); ++i)
        for (std::size_t j = 0; j < views[b].points.size(); ++j) {
          const auto X =
              triangulate({views[a].model, views[b].model}, {views[a].points[i], views[b].points[j]});
          if (!X) continue;
          Candidate candidate{*X, {}, 0};
          for (std::size_t v = 0; v < views.size(); ++v) {
            const auto projected = views[v].model.project(*X);
            if (!projected) continue;
            double best = match_px;
            std::size_t hit = views[v].points.size();
            for (std::size_t k = 0; k < views[v].points.size(); ++k) {
              const double d = (views[v].points[k] - *projected).norm();
              if (d < best) {
                best = d;
                hit = k;
              }
            }
            if (hit < views[v].points.size()) {
              candidate.support.emplace_back(v, hit);
              candidate.error += best;
            }
          }
          if (candidate.support.size() >= 2) candidates.push_back(std::move(candidate));
        }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    if (x.support.size() != y.support.size()) return x.support.size() > y.support.size();
    return x.error < y.error;
  });
  std::vector<Eigen::Vector3d> result;
  for (const auto& candidate : candidates) {
    std::vector<CameraModel> models;
    std::vector<Eigen::Vector2d> pixels;
    for (const auto& [v, k] : candidate.support) {
      if (views[v].used[k]) continue;
      models.push_back(views[v].model);
      pixels.push_back(views[v].points[k]);
    }
    if (models.size() < 2 || models.size() < candidate.support.size()) continue;
    for (const auto& [v, k] : candidate.support) views[v].used[k] = true;
    if (auto X = triangulate(models, pixels)) result.push_back(*X);
  }
  return result;
}

}  // namespace panoptes::calib
