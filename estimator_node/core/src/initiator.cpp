// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/initiator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "panoptes/triangulation.h"

namespace panoptes::estimator {

namespace {

bool finite(const Eigen::Vector2d& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y());
}

}  // namespace

void Initiator::set_cameras(const std::vector<const CameraModel*>& cameras) {
  auto geometry = std::make_shared<Geometry>();
  geometry->cameras = cameras;
  const std::size_t n = cameras.size();
  geometry->essential.assign(n * n, Eigen::Matrix3d::Zero());
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = 0; b < n; ++b) {
      if (a == b) continue;
      // X_b = R X_a + t with R = R_b_w R_w_a, t = R_b_w (C_a - C_b): E = [t]x R (seed 000 §4.5).
      const Eigen::Matrix3d R_b_w = cameras[b]->T_cam_world().rotation();
      const Eigen::Matrix3d R = R_b_w * cameras[a]->T_world_cam().rotation();
      const Eigen::Vector3d t = R_b_w * (cameras[a]->center_world() - cameras[b]->center_world());
      geometry->essential[b * n + a] = skew(t) * R;
    }
  }
  geometry_ = std::move(geometry);
  per_camera_.resize(n);
}

std::size_t Initiator::pending() const {
  std::size_t count = 0;
  for (const auto& tracklets : per_camera_) count += tracklets.size();
  return count;
}

void Initiator::clear() {
  for (auto& tracklets : per_camera_) tracklets.clear();
}

Eigen::Vector2d Initiator::aligned(const Tracklet& t, TimeNs stamp_ns, double* allowance_px) const {
  const double dt = ns_to_seconds(stamp_ns - t.stamp_ns);
  if (t.links > 0) {
    // Constant pixel velocity; a 1-px allowance covers image-plane acceleration over the window.
    *allowance_px = 1.0;
    return t.pixel + dt * t.velocity;
  }
  // Without a pixel velocity the partner may only pair when it is nearly simultaneous: a blob that
  // never continues into a tracklet (a reflection, sensor noise) then pairs only by coincidence.
  *allowance_px = std::abs(stamp_ns - t.stamp_ns) <= options_.unaligned_max_dt_ns
                      ? options_.max_image_speed_px_s * std::abs(dt)
                      : std::numeric_limits<double>::infinity();
  return t.pixel;
}

double Initiator::epipolar_distance_px(int camera_a, const Eigen::Vector2d& pixel_a, int camera_b,
                                       const Eigen::Vector2d& pixel_b) const {
  const auto& cameras = geometry_->cameras;
  const std::size_t n = cameras.size();
  const Eigen::Vector2d xa = cameras[camera_a]->pixel_to_normalized(pixel_a);
  const Eigen::Vector2d xb = cameras[camera_b]->pixel_to_normalized(pixel_b);
  const Eigen::Vector3d line = geometry_->essential[static_cast<std::size_t>(camera_b) * n + camera_a] *
                               Eigen::Vector3d(xa.x(), xa.y(), 1.0);
  const double norm = std::hypot(line.x(), line.y());
  if (norm <= 0) return std::numeric_limits<double>::infinity();
  const auto& intrinsics = cameras[camera_b]->intrinsics();
  const double focal = 0.5 * (intrinsics.fx + intrinsics.fy);
  return std::abs(line.dot(Eigen::Vector3d(xb.x(), xb.y(), 1.0))) / norm * focal;
}

std::vector<Initiator::Tracklet> Initiator::continue_tracklets(
    int camera, TimeNs stamp_ns, const std::vector<Eigen::Vector2d>& blobs) const {
  // Nearest new blob within the link radius, closest pairs first. Tracklets that no blob continues
  // ended (their marker was taken by a track, or left).
  const auto& own = per_camera_[camera];
  struct Link {
    double d;
    std::size_t tracklet;
    std::size_t blob;
  };
  std::vector<Link> links;
  for (std::size_t i = 0; i < own.size(); ++i) {
    for (std::size_t j = 0; j < blobs.size(); ++j) {
      const double d = (blobs[j] - own[i].pixel).norm();
      if (d < options_.link_radius_px) links.push_back({d, i, j});
    }
  }
  std::sort(links.begin(), links.end(), [](const Link& a, const Link& b) { return a.d < b.d; });
  std::vector<Tracklet> next(blobs.size());
  std::vector<char> tracklet_taken(own.size(), 0), blob_linked(blobs.size(), 0);
  for (const auto& link : links) {
    if (tracklet_taken[link.tracklet] || blob_linked[link.blob]) continue;
    tracklet_taken[link.tracklet] = blob_linked[link.blob] = 1;
    const Tracklet& previous = own[link.tracklet];
    const double dt = ns_to_seconds(stamp_ns - previous.stamp_ns);
    Tracklet& t = next[link.blob];
    t.pixel = blobs[link.blob];
    t.stamp_ns = stamp_ns;
    if (dt > 0) {
      t.velocity = (t.pixel - previous.pixel) / dt;
      t.links = previous.links + 1;
    }
  }
  for (std::size_t j = 0; j < blobs.size(); ++j) {
    if (!blob_linked[j]) next[j] = Tracklet{blobs[j], Eigen::Vector2d::Zero(), stamp_ns, 0};
  }
  return next;
}

Initiator::Pairing Initiator::best_pairing(int camera, TimeNs stamp_ns, const Tracklet& mine,
                                           std::size_t blob) const {
  const auto& cameras = geometry_->cameras;
  Pairing best;
  for (std::size_t other = 0; other < per_camera_.size(); ++other) {
    if (static_cast<int>(other) == camera) continue;
    const auto& partners = per_camera_[other];
    for (std::size_t k = 0; k < partners.size(); ++k) {
      if (stamp_ns - partners[k].stamp_ns > options_.window_ns) continue;  // probe() runs before the pruning
      double allowance = 0;
      const Eigen::Vector2d partner_pixel = aligned(partners[k], stamp_ns, &allowance);
      if (!std::isfinite(allowance)) continue;
      if (epipolar_distance_px(camera, mine.pixel, static_cast<int>(other), partner_pixel) >
          options_.epipolar_px + allowance) {
        continue;
      }
      const auto pair = triangulate({{cameras[camera], mine.pixel}, {cameras[other], partner_pixel}}, 3);
      if (!pair || pair->max_reprojection_px > options_.reprojection_px + allowance) continue;
      const Eigen::Vector3d point = pair->point;
      if (cameras[camera]->T_cam_world().apply(point).z() < options_.min_depth_m ||
          cameras[other]->T_cam_world().apply(point).z() < options_.min_depth_m) {
        continue;
      }
      std::vector<View> views = {{camera, mine.pixel, mine.velocity, mine.links > 0, stamp_ns, blob},
                                 {static_cast<int>(other), partner_pixel, partners[k].velocity,
                                  partners[k].links > 0, partners[k].stamp_ns, k}};
      // Support: in every further camera, the tracklet that reprojects best, if well enough.
      for (std::size_t third = 0; third < per_camera_.size(); ++third) {
        if (static_cast<int>(third) == camera || third == other) continue;
        double best_error = std::numeric_limits<double>::infinity();
        std::size_t best_index = 0;
        Eigen::Vector2d best_pixel = Eigen::Vector2d::Zero();  // set whenever best_error is finite
        for (std::size_t m = 0; m < per_camera_[third].size(); ++m) {
          if (stamp_ns - per_camera_[third][m].stamp_ns > options_.window_ns) continue;
          double third_allowance = 0;
          const Eigen::Vector2d pixel = aligned(per_camera_[third][m], stamp_ns, &third_allowance);
          if (!std::isfinite(third_allowance)) continue;
          const double e = reprojection_error(*cameras[third], point, pixel) - third_allowance;
          if (e < best_error) {
            best_error = e;
            best_index = m;
            best_pixel = pixel;
          }
        }
        if (best_error <= options_.reprojection_px) {
          const Tracklet& t = per_camera_[third][best_index];
          views.push_back(
              {static_cast<int>(third), best_pixel, t.velocity, t.links > 0, t.stamp_ns, best_index});
        }
      }
      const int support = static_cast<int>(views.size()) - 2;
      if (support > best.support || (support == best.support && pair->max_reprojection_px < best.error)) {
        best = {support, pair->max_reprojection_px, std::move(views), point};
      }
    }
  }
  return best;
}

InitiationCandidate Initiator::candidate_of(TimeNs stamp_ns, const Pairing& best) const {
  const auto& cameras = geometry_->cameras;
  std::vector<PixelObservation> observations;
  for (const auto& view : best.views) observations.push_back({cameras[view.camera], view.pixel});
  InitiationCandidate candidate;
  candidate.stamp_ns = stamp_ns;
  candidate.position = best.point;
  candidate.max_reprojection_px = best.error;
  if (const auto all = triangulate(observations, 5);
      all && all->max_reprojection_px <= options_.reprojection_px + 1.0) {
    candidate.position = all->point;
    candidate.max_reprojection_px = all->max_reprojection_px;
  }
  // Velocity: the views with a pixel velocity, 10 ms earlier.
  std::vector<PixelObservation> earlier;
  constexpr double kBack = 0.01;
  for (const auto& view : best.views) {
    if (view.has_velocity) earlier.push_back({cameras[view.camera], view.pixel - kBack * view.velocity});
  }
  if (earlier.size() >= 2) {
    if (const auto before = triangulate(earlier, 3); before) {
      candidate.velocity = (candidate.position - before->point) / kBack;
      candidate.has_velocity = true;
    }
  } else if (earlier.size() == 1 && options_.partial_velocity) {
    // One view only: its earlier ray met on the plane through the marker square to the line of
    // sight gives the velocity across the line of sight; along it nothing is known.
    const CameraModel& view = *earlier.front().camera;
    const Eigen::Vector3d centre = view.center_world();
    const Eigen::Vector3d sight = (candidate.position - centre).normalized();
    const Eigen::Vector3d ray = view.pixel_to_world_ray(earlier.front().pixel);
    if (const double along = ray.dot(sight); along > 0.5) {
      const Eigen::Vector3d before = centre + ray * ((candidate.position - centre).dot(sight) / along);
      candidate.velocity = (candidate.position - before) / kBack;
      candidate.has_partial_velocity = true;
      candidate.unknown_direction = sight;
    }
  }
  for (const auto& view : best.views) {
    candidate.cameras.push_back(view.camera);
    candidate.camera_stamps.push_back(view.stamp_ns);
  }
  return candidate;
}

void Initiator::consume_partners(const Pairing& best) {
  std::vector<std::pair<int, std::size_t>> remove;
  for (std::size_t v = 1; v < best.views.size(); ++v)
    remove.emplace_back(best.views[v].camera, best.views[v].index);
  std::sort(remove.begin(), remove.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  for (const auto& [cam, index] : remove)
    per_camera_[cam].erase(per_camera_[cam].begin() + static_cast<std::ptrdiff_t>(index));
}

std::size_t Initiator::probe(int camera, TimeNs stamp_ns, const std::vector<Eigen::Vector2d>& blobs,
                             const std::function<bool(const InitiationCandidate&, std::size_t)>& take) {
  if (camera < 0 || static_cast<std::size_t>(camera) >= geometry_->cameras.size() || blobs.empty()) return 0;
  // Linked to this camera's tracklets for a pixel velocity (the pool is only read).
  const std::vector<Tracklet> mine = continue_tracklets(camera, stamp_ns, blobs);
  std::size_t taken = 0;
  for (std::size_t j = 0; j < blobs.size(); ++j) {
    if (!finite(blobs[j])) continue;
    const Pairing best = best_pairing(camera, stamp_ns, mine[j], j);
    if (best.support < 0 || !take(candidate_of(stamp_ns, best), j)) continue;
    consume_partners(best);
    ++taken;
  }
  return taken;
}

std::vector<InitiationCandidate> Initiator::add_frame(
    int camera, TimeNs stamp_ns, const std::vector<Eigen::Vector2d>& blobs,
    const std::function<bool(const Eigen::Vector3d&)>& occupied) {
  std::vector<InitiationCandidate> found;
  const auto& cameras = geometry_->cameras;
  if (camera < 0 || static_cast<std::size_t>(camera) >= cameras.size()) return found;

  // Forget tracklets too old to pair with anything from now on.
  for (auto& tracklets : per_camera_) {
    std::erase_if(tracklets, [&](const Tracklet& t) { return stamp_ns - t.stamp_ns > options_.window_ns; });
  }

  // Continue this camera's tracklets.
  const std::vector<Tracklet> next = continue_tracklets(camera, stamp_ns, blobs);
  auto& own = per_camera_[camera];
  own.clear();

  std::vector<char> consumed_new(blobs.size(), 0);
  for (std::size_t j = 0; j < blobs.size(); ++j) {
    if (!finite(blobs[j])) {
      consumed_new[j] = 1;
      continue;
    }
    const Pairing best = best_pairing(camera, stamp_ns, next[j], j);
    if (best.support < 0) continue;

    InitiationCandidate candidate = candidate_of(stamp_ns, best);
    consumed_new[j] = 1;
    consume_partners(best);
    if (!occupied || !occupied(candidate.position)) found.push_back(std::move(candidate));
  }
  for (std::size_t j = 0; j < blobs.size(); ++j) {
    if (!consumed_new[j]) own.push_back(next[j]);
  }
  return found;
}

}  // namespace panoptes::estimator
