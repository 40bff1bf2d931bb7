// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/inside_out.h"

#include <limits>
#include <stdexcept>
#include <utility>

#include "panoptes/estimator/assignment.h"
#include "panoptes/geometry.h"
#include "panoptes/p3p.h"

namespace panoptes::estimator {
namespace {

// The three landmarks spanning the largest triangle: the best-conditioned P3P of a constellation.
std::array<int, 3> widest_triangle(const Constellation& constellation) {
  const auto& L = constellation.landmarks;
  const int n = static_cast<int>(L.size());
  double best_area = 0;
  std::array<int, 3> best = {0, 1, 2};
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        const auto& a = L[static_cast<std::size_t>(i)];
        const double area =
            (L[static_cast<std::size_t>(j)] - a).cross(L[static_cast<std::size_t>(k)] - a).norm();
        if (area > best_area) best_area = area, best = {i, j, k};
      }
  if (best_area < 1e-6)
    throw std::invalid_argument("constellation '" + constellation.name + "': landmarks are collinear");
  return best;
}

}  // namespace

std::optional<MarkerPixel> landmark_pixel(const RigidTransform& T_world_rig,
                                          const Eigen::Vector3d& landmark_world,
                                          const CameraModel& camera_in_rig, double min_depth_m) {
  // p_rig = R_world_rigᵀ (L − p); with R = R̂ exp(δθ), p_rig ≈ p̂_rig + [p̂_rig]× δθ.
  const Eigen::Matrix3d R_rig_world = T_world_rig.rotation().transpose();
  const Eigen::Vector3d p_rig = R_rig_world * (landmark_world - T_world_rig.t);
  const RigidTransform& T_cam_rig = camera_in_rig.T_cam_world();  // the camera's pose is T_rig_cam
  const Eigen::Matrix3d R_cam_rig = T_cam_rig.rotation();
  const Eigen::Vector3d p_cam = R_cam_rig * p_rig + T_cam_rig.t;
  if (p_cam.z() < min_depth_m) return std::nullopt;
  Eigen::Matrix<double, 2, 3> J_cam;
  const auto pixel = camera_in_rig.project_camera_point(p_cam, &J_cam);
  if (!pixel) return std::nullopt;
  MarkerPixel result;
  result.pixel = *pixel;
  result.J.leftCols<3>() = -J_cam * R_cam_rig * R_rig_world;
  result.J.rightCols<3>() = J_cam * R_cam_rig * skew(p_rig);
  return result;
}

InsideOutTracker::InsideOutTracker(std::vector<Constellation> constellations, CameraModel camera_in_rig,
                                   InsideOutOptions options)
    : constellations_(std::move(constellations)),
      camera_in_rig_(std::move(camera_in_rig)),
      T_rig_cam_(camera_in_rig_.T_world_cam()),
      options_(options) {
  bool any_identifies = false;
  for (std::size_t c = 0; c < constellations_.size(); ++c) {
    const Constellation& constellation = constellations_[c];
    if (constellation.identifies && constellation.landmarks.size() < 3)
      throw std::invalid_argument("constellation '" + constellation.name +
                                  "': needs at least 3 landmarks, has " +
                                  std::to_string(constellation.landmarks.size()));
    widest_triangles_.push_back(constellation.identifies ? std::optional(widest_triangle(constellation))
                                                         : std::nullopt);
    any_identifies = any_identifies || constellation.identifies;
    for (const auto& landmark : constellation.landmarks)
      landmarks_.push_back({landmark, static_cast<int>(c)});
  }
  if (!any_identifies) throw std::invalid_argument("inside-out: no landmark constellation given");
}

int InsideOutTracker::count_inliers(const RigidTransform& T_world_rig,
                                    std::span<const Eigen::Vector2d> pixels) const {
  const double limit2 = options_.acquire_inlier_px * options_.acquire_inlier_px;
  // One blob explains one landmark: a pose from far away that projects many landmarks onto one
  // blob must not count them all.
  std::vector<bool> taken(pixels.size(), false);
  int inliers = 0;
  for (const Landmark& landmark : landmarks_) {
    const auto projected = landmark_pixel(T_world_rig, landmark.world, camera_in_rig_);
    if (!projected || !camera_in_rig_.in_image(projected->pixel)) continue;
    for (std::size_t b = 0; b < pixels.size(); ++b)
      if (!taken[b] && (pixels[b] - projected->pixel).squaredNorm() < limit2) {
        taken[b] = true;
        ++inliers;
        break;
      }
  }
  return inliers;
}

std::optional<RigidTransform> InsideOutTracker::acquire(std::span<const Eigen::Vector2d> pixels) {
  std::vector<Eigen::Vector3d> bearings;
  bearings.reserve(pixels.size());
  for (const auto& pixel : pixels)
    bearings.push_back(camera_in_rig_.pixel_to_normalized(pixel).homogeneous().normalized());
  const RigidTransform T_cam_rig = T_rig_cam_.inverse();
  int best_inliers = 0;
  std::optional<RigidTransform> best;
  std::size_t best_constellation = 0;
  const std::size_t n = pixels.size();
  for (std::size_t c = 0; c < constellations_.size(); ++c) {
    if (!widest_triangles_[c]) continue;
    const auto& triangle = *widest_triangles_[c];
    const auto& L = constellations_[c].landmarks;
    const std::array<Eigen::Vector3d, 3> points = {L[static_cast<std::size_t>(triangle[0])],
                                                   L[static_cast<std::size_t>(triangle[1])],
                                                   L[static_cast<std::size_t>(triangle[2])]};
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b)
        for (std::size_t d = 0; d < n; ++d) {
          if (a == b || a == d || b == d) continue;
          for (const RigidTransform& T_cam_world :
               solve_p3p({bearings[a], bearings[b], bearings[d]}, points)) {
            const RigidTransform T_world_rig = T_cam_world.inverse() * T_cam_rig;
            const int inliers = count_inliers(T_world_rig, pixels);
            if (inliers > best_inliers) best_inliers = inliers, best = T_world_rig, best_constellation = c;
          }
        }
  }
  if (!best || best_inliers < options_.acquire_min_landmarks) return std::nullopt;
  acquired_from_ = constellations_[best_constellation].name;
  return best;
}

namespace {

// Gates every point's predicted pixel in `camera` (project(state, i): the pixel and its pose
// Jacobian) against the blobs, assigns jointly, then updates one point at a time, each
// re-linearised at the state the previous one left. Returns the points assigned (0 and no update
// when fewer than `min_points`).
template <typename Project>
int gated_update(BodyState& state, std::size_t points, const Project& project, const CameraModel& camera,
                 std::span<const Eigen::Vector2d> pixels, const InsideOutOptions& options, int min_points) {
  std::vector<GatedPair> pairs;
  for (std::size_t i = 0; i < points; ++i) {
    const auto projected = project(state, i);
    if (!projected || !camera.in_image(projected->pixel, -20.0)) continue;
    const MarkerProjection measurement = pose_measurement(state, *projected, options.pixel_sigma);
    for (std::size_t b = 0; b < pixels.size(); ++b) {
      const double d2 = mahalanobis2(measurement, pixels[b]);
      if (inside_gate(d2, options.gate_chi2)) pairs.push_back({i, b, d2});
    }
  }
  const auto assigned = assign_gated(pairs, 0.5 * options.gate_chi2);
  if (static_cast<int>(assigned.size()) < min_points) return 0;
  for (const auto& [i, b] : assigned) {
    const auto projected = project(state, i);
    if (!projected) continue;
    estimator::update(state, pose_measurement(state, *projected, options.pixel_sigma), pixels[b],
                      options.pixel_sigma);
  }
  return static_cast<int>(assigned.size());
}

}  // namespace

int InsideOutTracker::update(BodyState& state, std::span<const Eigen::Vector2d> pixels) const {
  const auto project = [&](const BodyState& at, std::size_t l) {
    return landmark_pixel(at.pose(), landmarks_[l].world, camera_in_rig_);
  };
  return gated_update(state, landmarks_.size(), project, camera_in_rig_, pixels, options_,
                      options_.track_min_landmarks);
}

int InsideOutTracker::add_outside_in_frame(TimeNs stamp_ns, const CameraModel& fixed_camera,
                                           std::span<const Eigen::Vector3d> rig_markers,
                                           std::span<const Eigen::Vector2d> pixels) {
  if (!state_) return 0;
  if (stamp_ns < state_->stamp_ns) {
    ++counters_.late_frames;
    return 0;
  }
  predict(*state_, stamp_ns, options_.motion);
  const auto project = [&](const BodyState& at, std::size_t m) {
    return marker_pixel(at.pose(), rig_markers[m], fixed_camera);
  };
  // One marker is a measurement too: the filter already knows the pose.
  const int updated = gated_update(*state_, rig_markers.size(), project, fixed_camera, pixels, options_, 1);
  if (updated > 0) {
    counters_.outside_in_updates += static_cast<std::uint64_t>(updated);
    last_update_ns_ = stamp_ns;
  }
  return updated;
}

std::optional<InsideOutPose> InsideOutTracker::add_frame(TimeNs stamp_ns,
                                                         std::span<const Eigen::Vector2d> pixels) {
  ++counters_.frames;
  if (state_ && stamp_ns < state_->stamp_ns) {
    ++counters_.late_frames;
    return std::nullopt;
  }
  if (state_ && stamp_ns - last_update_ns_ > options_.lost_after_ns) {
    state_.reset();
    ++counters_.lost;
  }
  InsideOutPose pose;
  if (!state_) {
    const auto T_world_rig = acquire(pixels);
    if (!T_world_rig) {
      ++counters_.failed_acquisitions;
      return std::nullopt;
    }
    ++counters_.acquisitions;
    BodyState state;
    state.p = T_world_rig->t;
    state.q = T_world_rig->q;
    state.stamp_ns = stamp_ns;
    state.P = body_prior({0.02, 2.0, 10.0, 0.02, 4.0, 20.0});
    state_ = state;
    last_update_ns_ = stamp_ns;
    pose.acquired = true;
  } else {
    predict(*state_, stamp_ns, options_.motion);
  }
  pose.landmarks = update(*state_, pixels);
  if (pose.landmarks > 0) {
    counters_.updates += static_cast<std::uint64_t>(pose.landmarks);
    last_update_ns_ = stamp_ns;
  } else {
    ++counters_.frames_without_update;
  }
  pose.stamp_ns = stamp_ns;
  pose.T_world_rig = state_->pose();
  pose.velocity = state_->v;
  pose.angular_velocity = state_->w;
  return pose;
}

}  // namespace panoptes::estimator
