// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/solve_finish.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "panoptes/calib/triangulate.h"
#include "panoptes/calib/world_frame.h"

namespace panoptes::calib {

namespace {

// Reprojection sums per camera, and the wand triangulated freely (without the length terms).
struct Reprojection {
  std::vector<double> squared;
  std::vector<int> count;
  double total = 0;
  int total_count = 0;
  std::vector<double> length_errors;                // end to end, mm
  std::vector<std::vector<double>> spacing_errors;  // per consecutive marker pair, m
};

// Every active instant: its markers into result.samples, each observation's residual into
// result.residuals, and the free triangulation's lengths.
Reprojection reproject(const BundleState& state, const std::vector<CameraModel>& models,
                       const WandDefinition& wand, SolveResult& result) {
  const std::size_t markers = wand.marker_count();
  const std::size_t n = state.cameras.size();
  Reprojection out;
  out.squared.assign(n, 0.0);
  out.count.assign(n, 0);
  for (std::size_t s = 0; s < state.instants.size(); ++s) {
    const auto& instant = state.instants[s];
    std::vector<const InstantObservation*> active;
    for (const auto& observation : instant.observations)
      if (observation.active) active.push_back(&observation);
    if (active.size() < 2) continue;
    WandSample sample;
    sample.t_ns = instant.t_ns;
    sample.cameras = static_cast<int>(active.size());
    std::vector<Eigen::Vector3d> free_points;
    for (std::size_t m = 0; m < markers; ++m) {
      const Eigen::Vector3d X(&state.points[(s * markers + m) * 3]);
      sample.markers.push_back(X);
      std::vector<CameraModel> used;
      std::vector<Eigen::Vector2d> pixels;
      for (const auto* observation : active) {
        const int c = observation->camera;
        const Eigen::Vector2d pixel = observed_pixel(*observation, m, state.cameras[c].offset_s);
        const auto projected = models[c].project(X);
        if (!projected) continue;
        const Eigen::Vector2d error = *projected - pixel;
        out.squared[c] += error.squaredNorm();
        out.count[c] += 1;
        auto& camera = result.cameras[c];
        camera.max_px = std::max(camera.max_px, error.norm());
        out.total += error.squaredNorm();
        ++out.total_count;
        result.residuals.push_back({c, static_cast<int>(m), instant.t_ns, pixel, error});
        used.push_back(models[c]);
        pixels.push_back(pixel);
      }
      if (auto x = triangulate(used, pixels)) free_points.push_back(*x);
    }
    // The wand length as the calibrated cameras measure it, without the length constraint.
    if (markers >= 2 && free_points.size() == markers) {
      out.length_errors.push_back(((free_points.back() - free_points.front()).norm() - wand.length()) * 1e3);
      out.spacing_errors.resize(markers - 1);
      for (std::size_t m = 0; m + 1 < markers; ++m)
        out.spacing_errors[m].push_back((free_points[m + 1] - free_points[m]).norm() -
                                        (wand.positions[m + 1] - wand.positions[m]));
    }
    result.samples.push_back(std::move(sample));
  }
  return out;
}

LengthStats length_stats(const std::vector<double>& length_errors) {
  LengthStats stats;
  if (length_errors.empty()) return stats;
  stats.count = static_cast<int>(length_errors.size());
  stats.mean_error_mm = std::accumulate(length_errors.begin(), length_errors.end(), 0.0) / stats.count;
  double variance = 0;
  for (double e : length_errors) {
    variance += (e - stats.mean_error_mm) * (e - stats.mean_error_mm);
    stats.max_abs_error_mm = std::max(stats.max_abs_error_mm, std::abs(e));
  }
  stats.sigma_mm = std::sqrt(variance / std::max(1, stats.count - 1));
  double squared = 0;
  for (double e : length_errors) squared += e * e;
  stats.rms_error_mm = std::sqrt(squared / stats.count);
  std::vector<double> sorted = length_errors;
  const auto half = static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), sorted.begin() + half, sorted.end());
  stats.median_error_mm = sorted[static_cast<std::size_t>(half)];
  if (sorted.size() % 2 == 0)
    stats.median_error_mm =
        0.5 * (stats.median_error_mm + *std::max_element(sorted.begin(), sorted.begin() + half));
  return stats;
}

// Raw-frame statistics per camera and overall: every frame, and the inliers (kRawInlierPx).
void raw_residuals(const BundleState& state, const std::vector<CameraModel>& models,
                   const std::vector<CameraWandTrack>& tracks, std::size_t markers, SolveResult& result) {
  const auto errors = raw_frame_errors(state, models, tracks, markers);
  std::vector<double> all, inliers;
  for (std::size_t c = 0; c < errors.size(); ++c) {
    if (!state.cameras[c].registered) continue;
    std::vector<double> camera_inliers;
    for (double e : errors[c])
      if (e <= kRawInlierPx) camera_inliers.push_back(e);
    auto& camera = result.cameras[c];
    camera.raw_all = error_stats(errors[c]);
    camera.raw_inliers = error_stats(camera_inliers);
    camera.raw_observations = camera.raw_inliers.count;
    camera.raw_rms_axis_px = camera.raw_inliers.rms_axis_px;
    all.insert(all.end(), errors[c].begin(), errors[c].end());
    inliers.insert(inliers.end(), camera_inliers.begin(), camera_inliers.end());
  }
  result.raw_all = error_stats(std::move(all));
  result.raw_inliers = error_stats(std::move(inliers));
  result.raw_rms_axis_px = result.raw_inliers.rms_axis_px;
}

// Spacing check: the distances between neighbouring markers, as the calibrated cameras measure
// them without the length constraint, against --wand. A wrong --wand cannot be fitted: the
// adjustment splits the difference and the free measurements show it.
void check_spacing(const std::vector<std::vector<double>>& spacing_errors, const BundleState& state,
                   const std::vector<CameraCalibration>& cameras, const WandDefinition& wand,
                   SolveResult& result) {
  for (std::size_t m = 0; m < spacing_errors.size(); ++m) {
    const auto& errors = spacing_errors[m];
    if (errors.size() < 10) continue;
    const double mean =
        std::accumulate(errors.begin(), errors.end(), 0.0) / static_cast<double>(errors.size());
    const double given = wand.positions[m + 1] - wand.positions[m];
    if (std::abs(mean) <= std::max(0.002, 0.005 * given)) continue;
    std::string ids;
    for (std::size_t c = 0; c < state.cameras.size(); ++c)
      if (state.cameras[c].registered) ids += (ids.empty() ? "" : ", ") + cameras[c].id;
    std::ostringstream why;
    why.precision(4);
    why << "wand lengths never match: markers " << m << "-" << m + 1 << " measure " << given + mean
        << " m, --wand says " << given << " m; cameras " << ids
        << " are not calibrated (check --wand and the wand itself)";
    result.errors.push_back(why.str());
    for (std::size_t c = 0; c < state.cameras.size(); ++c)
      if (state.cameras[c].registered) {
        result.cameras[c].failure = "lengths never match --wand";
        result.cameras[c].T_world_cam.reset();
      }
    break;
  }
}

// Provisional world frame: z up from the cameras' layout (docs/calibration.md); `calibrate
// world` replaces it with the floor or an L-frame.
void provisional_world(SolveResult& result) {
  std::vector<RigidTransform> poses;
  std::vector<Eigen::Vector3d> points;
  for (const auto& camera : result.cameras)
    if (camera.T_world_cam) poses.push_back(*camera.T_world_cam);
  for (const auto& sample : result.samples)
    for (const auto& p : sample.markers) points.push_back(p);
  const RigidTransform T_new_old = provisional_world_frame(poses, points);
  apply_world_transform(result, T_new_old);
}

}  // namespace

SolveResult finish_solution(SolveResult partial, const BundleState& adjusted,
                            const std::vector<CameraCalibration>& cameras,
                            const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand) {
  SolveResult result = std::move(partial);
  std::vector<CameraIntrinsics> given;
  given.reserve(cameras.size());
  for (const auto& camera : cameras) given.push_back(camera.intrinsics);
  const std::vector<CameraModel> models = registered_models(adjusted, given);
  const Reprojection reprojection = reproject(adjusted, models, wand, result);
  for (std::size_t c = 0; c < adjusted.cameras.size(); ++c) {
    auto& camera = result.cameras[c];
    const CameraParameters& parameters = adjusted.cameras[c];
    camera.observations = reprojection.count[c];
    camera.rms_px =
        reprojection.count[c] > 0 ? std::sqrt(reprojection.squared[c] / reprojection.count[c]) : 0.0;
    if (parameters.registered) {
      camera.T_world_cam = T_world_cam_of(parameters);
      camera.intrinsics = intrinsics_of(parameters, given[c]);
      camera.time_offset_s = parameters.offset_s;
    }
  }
  result.rms_px =
      reprojection.total_count > 0 ? std::sqrt(reprojection.total / reprojection.total_count) : 0.0;
  raw_residuals(adjusted, models, tracks, wand.marker_count(), result);
  if (!reprojection.length_errors.empty()) result.lengths = length_stats(reprojection.length_errors);
  check_spacing(reprojection.spacing_errors, adjusted, cameras, wand, result);
  provisional_world(result);
  return result;
}

}  // namespace panoptes::calib
