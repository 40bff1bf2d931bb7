// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/world_frame.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <sstream>

#include <Eigen/Dense>

#include "panoptes/calib/solve_result.h"
#include "panoptes/calib/triangulate.h"

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

namespace {

// One instant of the wand on the floor: its markers triangulated, in wand order.
struct FloorInstant {
  TimeNs t_ns = 0;
  std::vector<Eigen::Vector3d> markers;
};

struct TrackView {
  CameraModel model;
  CameraWandTrack track;
};

// Largest reprojection error (px) of `points` (one per marker) in the given views.
double max_reprojection_px(const std::vector<const CameraModel*>& models,
                           const std::vector<std::vector<Eigen::Vector2d>>& pixels,
                           const std::vector<Eigen::Vector3d>& points) {
  double worst = 0;
  for (std::size_t v = 0; v < models.size(); ++v)
    for (std::size_t m = 0; m < points.size(); ++m) {
      const auto projected = models[v]->project(points[m]);
      if (!projected) return 1e9;
      worst = std::max(worst, (*projected - pixels[v][m]).norm());
    }
  return worst;
}

// Triangulates every marker from all views; nullopt if one fails.
std::optional<std::vector<Eigen::Vector3d>> triangulate_markers(
    const std::vector<const CameraModel*>& models, const std::vector<std::vector<Eigen::Vector2d>>& pixels) {
  std::vector<CameraModel> used;
  used.reserve(models.size());
  for (const auto* model : models) used.push_back(*model);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t m = 0; m < pixels.front().size(); ++m) {
    std::vector<Eigen::Vector2d> rays;
    rays.reserve(pixels.size());
    for (const auto& view : pixels) rays.push_back(view[m]);
    const auto X = triangulate(used, rays);
    if (!X) return std::nullopt;
    points.push_back(*X);
  }
  return points;
}

// The wand's instants seen by >= 2 cameras at the fastest camera's rate, interpolated in every
// track as the solver does (wand.h, TrackSegment), triangulated and checked by reprojection.
std::vector<FloorInstant> triangulate_wand_instants(const std::vector<TrackView>& views,
                                                    const WandDefinition& wand,
                                                    const WandFloorOptions& options) {
  TimeNs first = std::numeric_limits<TimeNs>::max(), last = std::numeric_limits<TimeNs>::min();
  double period = 1e9;
  for (const auto& view : views) {
    first = std::min(first, view.track.frames.front().stamp_ns);
    last = std::max(last, view.track.frames.back().stamp_ns);
    if (view.track.frame_period_s > 0) period = std::min(period, view.track.frame_period_s);
  }
  std::vector<FloorInstant> instants;
  if (first >= last) return instants;
  const double rate = options.sample_rate_hz > 0 ? options.sample_rate_hz : 1.0 / period;
  const auto step = static_cast<TimeNs>(std::llround(1e9 / rate));
  const std::size_t markers = wand.marker_count();
  for (TimeNs t = first + step / 2; t < last; t += step) {
    std::vector<const CameraModel*> models;
    std::vector<std::vector<Eigen::Vector2d>> pixels;
    for (const auto& view : views) {
      const auto segment = find_segment(view.track, t, options.max_gap_frames * view.track.frame_period_s);
      if (!segment) continue;
      std::vector<Eigen::Vector2d> observed;
      for (std::size_t m = 0; m < markers; ++m) observed.push_back(evaluate_segment(*segment, m, 0.0));
      models.push_back(&view.model);
      pixels.push_back(std::move(observed));
    }
    if (models.size() < 2) continue;
    if (wand.ends_indistinguishable()) {
      // Each camera's end order is its own guess (bar_labels.h); with calibrated cameras the
      // order that triangulates consistently with the first camera's is the right one.
      for (std::size_t v = 1; v < models.size(); ++v) {
        const auto error_of = [&](const std::vector<Eigen::Vector2d>& candidate) {
          const std::vector<const CameraModel*> pair{models[0], models[v]};
          const std::vector<std::vector<Eigen::Vector2d>> pair_pixels{pixels[0], candidate};
          const auto points = triangulate_markers(pair, pair_pixels);
          return points ? max_reprojection_px(pair, pair_pixels, *points) : 1e9;
        };
        std::vector<Eigen::Vector2d> reversed(pixels[v].rbegin(), pixels[v].rend());
        if (error_of(reversed) < error_of(pixels[v])) pixels[v] = std::move(reversed);
      }
    }
    auto points = triangulate_markers(models, pixels);
    if (!points || max_reprojection_px(models, pixels, *points) > options.max_reprojection_px) continue;
    instants.push_back({t, std::move(*points)});
  }
  return instants;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// RANSAC over planes through three of `points`: the unit normal and a point of the plane with the
// most points within `inlier_m`. Deterministic (fixed seed).
std::pair<Eigen::Vector3d, Eigen::Vector3d> ransac_plane(const std::vector<Eigen::Vector3d>& points,
                                                         double inlier_m, int iterations) {
  std::mt19937 random(20261121);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::size_t best_count = 0;
  std::pair<Eigen::Vector3d, Eigen::Vector3d> best{Eigen::Vector3d::UnitZ(), points.front()};
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const Eigen::Vector3d& a = points[pick(random)];
    const Eigen::Vector3d normal = (points[pick(random)] - a).cross(points[pick(random)] - a);
    if (normal.norm() < 1e-4) continue;  // the three (nearly) on one line: 1 cm^2 of area at least
    const Eigen::Vector3d n = normal.normalized();
    std::size_t count = 0;
    for (const auto& p : points) count += std::abs(n.dot(p - a)) < inlier_m ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best = {n, a};
    }
  }
  return best;
}

// The posed cameras' wand tracks (those of two or more frames) and the posed cameras' mean position.
struct FloorViews {
  std::vector<TrackView> views;
  Eigen::Vector3d camera_mean = Eigen::Vector3d::Zero();
  int posed = 0;
};

// Also records every posed camera's count of identified wand frames in `camera_frames`.
FloorViews wand_track_views(const SystemCalibration& calibration, const std::vector<FeatureFrame>& frames,
                            const WandDefinition& wand, const WandFloorOptions& options,
                            std::vector<std::pair<std::string, int>>& camera_frames) {
  std::map<std::string, std::vector<FeatureFrame>> by_camera;
  for (const auto& frame : frames) by_camera[frame.camera_id].push_back(frame);
  FloorViews result;
  for (const auto& camera : calibration.cameras) {
    if (!camera.T_world_cam) continue;
    result.camera_mean += camera.T_world_cam->t;
    ++result.posed;
    const auto found = by_camera.find(camera.id);
    if (found == by_camera.end()) continue;
    TrackView view{camera.model(),
                   extract_wand_track(camera.id, found->second, camera.intrinsics, wand, options.identify)};
    camera_frames.emplace_back(camera.id, static_cast<int>(view.track.frames.size()));
    if (view.track.frames.size() >= 2) result.views.push_back(std::move(view));
  }
  return result;
}

// A wand whose ends look alike has no end order of its own: keep it continuous in time.
void keep_end_order_continuous(std::vector<FloorInstant>& instants) {
  for (std::size_t i = 1; i < instants.size(); ++i) {
    auto& now = instants[i].markers;
    const auto& before = instants[i - 1].markers;
    if ((now.front() - before.back()).norm() + (now.back() - before.front()).norm() <
        (now.front() - before.front()).norm() + (now.back() - before.back()).norm())
      std::reverse(now.begin(), now.end());
  }
}

double seconds_after_first(const std::vector<FloorInstant>& instants, std::size_t i) {
  return static_cast<double>(instants[i].t_ns - instants[0].t_ns) * 1e-9;
}

using Rest = std::pair<std::size_t, std::size_t>;  // [first, last] instants

// Rests: every marker slower than rest_speed over +-0.1 s, for at least min_rest_s.
std::vector<Rest> find_rests(const std::vector<FloorInstant>& instants, std::size_t markers,
                             const WandFloorOptions& options) {
  const double window_s = 0.1;
  const auto seconds = [&](std::size_t i) { return seconds_after_first(instants, i); };
  std::vector<bool> resting(instants.size(), false);
  for (std::size_t i = 0, lo = 0, hi = 0; i < instants.size(); ++i) {
    while (seconds(lo) < seconds(i) - window_s) ++lo;
    while (hi + 1 < instants.size() && seconds(hi) < seconds(i) + window_s) ++hi;
    const double dt = seconds(hi) - seconds(lo);
    if (dt < window_s || dt > 4 * window_s) continue;  // too short to tell, or across a gap
    double speed = 0;
    for (std::size_t m = 0; m < markers; ++m)
      speed = std::max(speed, (instants[hi].markers[m] - instants[lo].markers[m]).norm() / dt);
    resting[i] = speed < options.rest_speed_m_s;
  }
  std::vector<Rest> rests;
  for (std::size_t i = 0; i < instants.size();) {
    if (!resting[i]) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j + 1 < instants.size() && resting[j + 1] && seconds(j + 1) - seconds(j) < 2 * window_s) ++j;
    if (seconds(j) - seconds(i) >= options.min_rest_s) rests.emplace_back(i, j);
    i = j + 1;
  }
  return rests;
}

// The floor plane, its normal towards the cameras, and the marker positions on it.
struct FloorPlane {
  Eigen::Vector3d normal, centroid;
  std::vector<Eigen::Vector3d> inliers;

  [[nodiscard]] double distance(const Eigen::Vector3d& p) const { return normal.dot(p - centroid); }
};

// RANSAC over every marker position (lifted or carried wands are outliers), then least squares over
// the inliers, twice.
FloorPlane fit_floor_plane(const std::vector<FloorInstant>& instants, const Eigen::Vector3d& camera_mean,
                           const WandFloorOptions& options) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& instant : instants)
    points.insert(points.end(), instant.markers.begin(), instant.markers.end());
  const auto ransac = ransac_plane(points, options.inlier_m, options.ransac_iterations);
  FloorPlane plane{ransac.first, ransac.second, {}};
  for (int pass = 0; pass < 2; ++pass) {
    plane.inliers.clear();
    for (const auto& p : points)
      if (std::abs(plane.normal.dot(p - plane.centroid)) < options.inlier_m) plane.inliers.push_back(p);
    if (plane.inliers.size() < 3) break;
    double flatness = 0;
    fit_plane(plane.inliers, plane.centroid, plane.normal, flatness);
  }
  if (plane.normal.dot(camera_mean - plane.centroid) < 0) plane.normal = -plane.normal;
  return plane;
}

// How well the plane fits: instants wholly on it, the positions' spread on it, its tilt, and the RMS
// over the floor points and every resting marker (a rest off the floor counts too).
void measure_floor_fit(const FloorPlane& plane, const std::vector<FloorInstant>& instants,
                       const std::vector<Rest>& rests, const WandFloorOptions& options,
                       WandFloorResult& result) {
  for (const auto& instant : instants) {
    bool all = true;
    for (const auto& p : instant.markers) all = all && std::abs(plane.distance(p)) < options.inlier_m;
    result.floor_instants += all ? 1 : 0;
  }
  const auto& inliers = plane.inliers;
  const Eigen::Vector3d& centroid = plane.centroid;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : inliers) scatter += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter / std::max<double>(1, inliers.size()));
  result.spread_m[0] = std::sqrt(std::max(0.0, eigen.eigenvalues()(2)));
  result.spread_m[1] = std::sqrt(std::max(0.0, eigen.eigenvalues()(1)));
  result.tilt_deg = std::acos(std::clamp(plane.normal.z(), -1.0, 1.0)) * 180 / M_PI;

  double squared = 0;
  std::size_t count = 0;
  const auto add = [&](const Eigen::Vector3d& p) {
    const double d = plane.distance(p);
    squared += d * d;
    ++count;
    result.max_distance_mm = std::max(result.max_distance_mm, std::abs(d) * 1e3);
  };
  for (const auto& p : inliers) add(p);
  for (const auto& [first, last] : rests)
    for (std::size_t i = first; i <= last; ++i)
      for (const auto& p : instants[i].markers)
        if (std::abs(plane.distance(p)) >= options.inlier_m) add(p);
  result.plane_rms_mm = std::sqrt(squared / static_cast<double>(std::max<std::size_t>(1, count))) * 1e3;
}

// The new frame from the first rest (origin under its first marker, x along the wand, z up the
// floor's normal), and every rest's placement in it.
void place_world_frame(const std::vector<FloorInstant>& instants, const std::vector<Rest>& rests,
                       const FloorPlane& plane, const Eigen::Vector3d& camera_mean,
                       const WandDefinition& wand, double scale, const WandFloorOptions& options,
                       WandFloorResult& result) {
  const std::size_t markers = wand.marker_count();
  std::vector<std::vector<Eigen::Vector3d>> rest_means;
  for (const auto& [first, last] : rests) {
    std::vector<Eigen::Vector3d> mean(markers, Eigen::Vector3d::Zero());
    for (std::size_t i = first; i <= last; ++i)
      for (std::size_t m = 0; m < markers; ++m)
        mean[m] += instants[i].markers[m] / static_cast<double>(last - first + 1);
    rest_means.push_back(std::move(mean));
  }
  auto& origin_rest = rest_means.front();
  if (wand.ends_indistinguishable()) {
    // No image tells the ends apart: the end nearer the middle of the room is the first.
    const Eigen::Vector3d middle = camera_mean - plane.distance(camera_mean) * plane.normal;
    if ((origin_rest.back() - middle).norm() < (origin_rest.front() - middle).norm())
      std::reverse(origin_rest.begin(), origin_rest.end());
  }
  const Eigen::Vector3d origin =
      origin_rest.front() - (plane.distance(origin_rest.front()) + options.floor_offset_m) * plane.normal;
  const RigidTransform T_metric =
      frame_from_axes(origin, origin_rest.back() - origin_rest.front(), plane.normal);
  RigidTransform T_new_old = T_metric;
  T_new_old.t /= scale;  // p_new = scale * T_new_old(p_old)
  result.T_new_old = T_new_old;
  for (std::size_t r = 0; r < rests.size(); ++r) {
    WandPlacement placement;
    placement.start_s = seconds_after_first(instants, rests[r].first);
    placement.end_s = seconds_after_first(instants, rests[r].second);
    placement.instants = static_cast<int>(rests[r].second - rests[r].first + 1);
    for (const auto& p : rest_means[r]) {
      placement.markers.push_back(T_metric.apply(p));
      placement.height_mm += plane.distance(p) * 1e3 / static_cast<double>(markers);
    }
    result.placements.push_back(std::move(placement));
  }
}

// Refuses a frame from positions on one line or a placement far off the plane (an error, the frame
// reset); warns of a placement left out, a poorly defined tilt, a high RMS or a wand length that
// disagrees with --wand.
void check_floor_fit(const WandDefinition& wand, bool unscaled, const WandFloorOptions& options,
                     WandFloorResult& result) {
  std::ostringstream why;
  why.precision(3);
  if (result.spread_m[1] < options.spread_error_m) {
    why << "the wand's positions on the floor are (nearly) on one line: they spread " << result.spread_m[0]
        << " m along it but " << result.spread_m[1] << " m across (SD; need " << options.spread_error_m
        << " m, better " << options.spread_warning_m << " m): lay the wand at places around the room";
    result.error = why.str();
    result.T_new_old.reset();
    return;
  }
  for (std::size_t r = 0; r < result.placements.size(); ++r) {
    const double height_mm = result.placements[r].height_mm;
    if (std::abs(height_mm) <= options.inlier_m * 1e3) continue;
    const bool refused = std::abs(height_mm) > options.off_plane_error_m * 1e3;
    why << "wand placement " << r + 1 << " (at " << result.placements[r].start_s << " s) is " << height_mm
        << " mm off the floor plane through the other positions";
    if (refused) {
      why << " (limit " << options.off_plane_error_m * 1e3 << " mm): was the wand on the floor?";
      result.error = why.str();
      result.T_new_old.reset();
      return;
    }
    why << ": left out of the fit";
    result.warnings.push_back(why.str());
    why.str("");
  }
  if (result.spread_m[1] < options.spread_warning_m) {
    why << "the positions are nearly on one line (spread " << result.spread_m[0] << " m x "
        << result.spread_m[1] << " m, SD): the floor's tilt is poorly defined; lay the wand further apart";
    result.warnings.push_back(why.str());
    why.str("");
  }
  if (result.plane_rms_mm > options.rms_warning_m * 1e3) {
    why << "plane RMS " << result.plane_rms_mm << " mm (max " << result.max_distance_mm << " mm) exceeds "
        << options.rms_warning_m * 1e3
        << " mm: the wand was not flat on the floor everywhere, or the floor is uneven";
    result.warnings.push_back(why.str());
    why.str("");
  }
  if (!unscaled && std::abs(result.median_length_m / wand.length() - 1) > 0.01) {
    why << "the wand measures " << result.median_length_m << " m end to end, --wand says " << wand.length()
        << " m: check --wand";
    result.warnings.push_back(why.str());
  }
}

}  // namespace

WandFloorResult wand_floor_frame(const SystemCalibration& calibration,
                                 const std::vector<FeatureFrame>& frames, const WandDefinition& wand,
                                 bool unscaled, const WandFloorOptions& options) {
  WandFloorResult result;
  const std::size_t markers = wand.marker_count();
  if (markers < 2) {
    result.error = "the wand on the floor needs two or more markers (its direction sets x" +
                   std::string(unscaled ? ", its length the scale" : "") + "); --wand gives " +
                   std::to_string(markers);
    return result;
  }
  auto [views, camera_mean, posed] =
      wand_track_views(calibration, frames, wand, options, result.camera_frames);
  std::string per_camera;
  for (const auto& [id, count] : result.camera_frames)
    per_camera += (per_camera.empty() ? "" : ", ") + id + " " + std::to_string(count);
  if (per_camera.empty()) per_camera = "no calibrated camera has frames";
  std::vector<FloorInstant> instants;
  if (views.size() >= 2) instants = triangulate_wand_instants(views, wand, options);

  // Scale: the wand's known length against its measured one (an unscaled calibration); metric
  // calibrations only check it. Instants whose length is off are mismatches: dropped.
  std::vector<double> lengths;
  lengths.reserve(instants.size());
  for (const auto& instant : instants)
    lengths.push_back((instant.markers.back() - instant.markers.front()).norm());
  const double measured = median(lengths);
  const double scale = unscaled && measured > 0 ? wand.length() / measured : 1.0;
  std::erase_if(instants, [&](const FloorInstant& instant) {
    const double length = (instant.markers.back() - instant.markers.front()).norm();
    return std::abs(length / measured - 1) > options.length_tolerance;
  });
  result.instants = static_cast<int>(instants.size());
  if (result.instants < options.min_instants) {
    result.error = "too few wand instants on the floor: " + std::to_string(result.instants) +
                   " triangulated from >= 2 cameras (need " + std::to_string(options.min_instants) +
                   "); identified wand frames per camera: " + per_camera;
    return result;
  }
  result.scale = scale;
  result.scaled_by_wand = unscaled;
  result.median_length_m = measured * scale;
  for (auto& instant : instants)
    for (auto& p : instant.markers) p *= scale;
  camera_mean *= scale / std::max(1, posed);
  if (wand.ends_indistinguishable()) keep_end_order_continuous(instants);

  const std::vector<Rest> rests = find_rests(instants, markers, options);
  if (rests.empty()) {
    result.error = "the wand never rested on the floor for " + std::to_string(options.min_rest_s) + " s (" +
                   std::to_string(result.instants) +
                   " instants): lay it still where the origin should be, then at other places";
    return result;
  }
  const FloorPlane plane = fit_floor_plane(instants, camera_mean, options);
  measure_floor_fit(plane, instants, rests, options, result);
  place_world_frame(instants, rests, plane, camera_mean, wand, scale, options, result);
  check_floor_fit(wand, unscaled, options, result);
  return result;
}

std::string wand_floor_summary(const WandFloorResult& result) {
  std::ostringstream out;
  char line[512];
  std::string per_camera;
  for (const auto& [id, count] : result.camera_frames)
    per_camera += (per_camera.empty() ? "" : ", ") + id + " " + std::to_string(count);
  std::snprintf(line, sizeof(line),
                "world frame from the wand on the floor: %zu placements, %d of %d wand instants on the plane "
                "(wand frames per camera: %s)\n",
                result.placements.size(), result.floor_instants, result.instants, per_camera.c_str());
  out << line;
  std::snprintf(
      line, sizeof(line),
      "plane RMS %.3f mm, max distance %.3f mm; spread %.2f m x %.2f m (SD); old z tilted by %.3f deg\n",
      result.plane_rms_mm, result.max_distance_mm, result.spread_m[0], result.spread_m[1], result.tilt_deg);
  out << line;
  if (result.scaled_by_wand)
    std::snprintf(line, sizeof(line), "metric scale set from the wand's length: %.6f m per unit\n",
                  result.scale);
  else
    std::snprintf(line, sizeof(line), "wand length measured %.5f m (median)\n", result.median_length_m);
  out << line;
  for (std::size_t r = 0; r < result.placements.size(); ++r) {
    const auto& p = result.placements[r];
    std::snprintf(
        line, sizeof(line),
        "  placement %zu: %.2f-%.2f s, %d instants, %.3f mm off the plane, first marker at [%.4f, %.4f, "
        "%.4f] m, last at [%.4f, %.4f, %.4f] m\n",
        r + 1, p.start_s, p.end_s, p.instants, p.height_mm, p.markers.front().x(), p.markers.front().y(),
        p.markers.front().z(), p.markers.back().x(), p.markers.back().y(), p.markers.back().z());
    out << line;
  }
  for (const auto& warning : result.warnings) out << "warning: " << warning << "\n";
  if (!result.error.empty()) out << "error: " << result.error << "\n";
  return out.str();
}

}  // namespace panoptes::calib
