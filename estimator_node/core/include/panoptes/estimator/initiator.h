// SPDX-License-Identifier: Apache-2.0
// Track initiation from blobs that no track explained (seed 003 §2.2.3.2: "an unmatched dot is a
// potential new point"; seed 000 §4.5: correspondences from the epipolar constraint).
//
// Unmatched blobs are linked frame to frame into short 2D tracklets per camera, so that each has
// a pixel velocity. A new blob is paired with the tracklets of other cameras: each partner is
// first moved to the new blob's stamp along its pixel velocity (the cameras are asynchronous),
// then must lie on the epipolar line, triangulate in front of both cameras and reproject well.
// Further cameras whose tracklets reproject near the point support it; the best-supported pair
// wins and is refined from every supporting view (linear, then Gauss–Newton). The 3D velocity
// comes from triangulating the same views a short time earlier along their pixel velocities.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

struct InitiatorOptions {
  TimeNs window_ns = 30'000'000;      // other cameras' tracklets this recent may pair
  double link_radius_px = 120.0;      // a blob continues its camera's tracklet within this (25 m/s at 3 m,
                                      // 110 Hz: 80 px; docs/estimator.md "Adaptive process noise")
  double epipolar_px = 2.0;           // distance to the epipolar line, beyond time alignment
  double reprojection_px = 3.0;       // every supporting view must reproject this well
  double max_image_speed_px_s = 800;  // allowance for a partner without a pixel velocity yet ...
  TimeNs unaligned_max_dt_ns = 3'000'000;  // ... which pairs only this close in time
  double min_depth_m = 0.05;               // points closer to a camera are rejected
  bool partial_velocity = true;            // one view's pixel velocity: the velocity across its line of sight
};

struct InitiationCandidate {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  bool has_velocity = false;
  // Only one view saw the marker a frame before (it has just come into the others): `velocity` is
  // its part across that camera's line of sight, `unknown_direction` (unit) the line of sight,
  // along which the velocity is unknown. has_velocity is false then.
  bool has_partial_velocity = false;
  Eigen::Vector3d unknown_direction = Eigen::Vector3d::Zero();
  std::vector<int> cameras;           // indices of the cameras whose blobs made it (first: newest)
  std::vector<TimeNs> camera_stamps;  // stamp of each of those blobs
  double max_reprojection_px = 0;
};

class Initiator {
 public:
  explicit Initiator(InitiatorOptions options = {}) : options_(options) {}

  const InitiatorOptions& options() const { return options_; }

  // Camera models by index; must stay valid and in the same order while the initiator is used.
  // Call again whenever the set changes (tracklets of removed indices are dropped).
  void set_cameras(const std::vector<const CameraModel*>& cameras);

  // Takes the blobs of camera `camera`'s frame at `stamp_ns` that no track took. Returns the new
  // points found; `occupied(point)` tells whether an existing track already explains a point (its
  // blobs are then consumed without a candidate). Blobs used by a candidate leave the pool.
  std::vector<InitiationCandidate> add_frame(int camera, TimeNs stamp_ns,
                                             const std::vector<Eigen::Vector2d>& blobs,
                                             const std::function<bool(const Eigen::Vector3d&)>& occupied);

  // Blobs of `camera`'s frame at `stamp_ns` that tracks took but may not explain (a track that one
  // camera alone updates: its depth along that camera's ray is its prediction's). Each is paired
  // with the other cameras' tracklets as a new blob would be, but never enters the pool, and the
  // pool is left as it was unless `take(candidate, index of the blob)` accepts the candidate: then
  // its partners are consumed. Call before add_frame for the same frame. Returns how many were taken.
  std::size_t probe(int camera, TimeNs stamp_ns, const std::vector<Eigen::Vector2d>& blobs,
                    const std::function<bool(const InitiationCandidate&, std::size_t)>& take);

  std::size_t pending() const;
  void clear();

 private:
  struct Tracklet {
    Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // px/s
    TimeNs stamp_ns = 0;
    int links = 0;  // frames linked so far (velocity valid when > 0)
  };
  struct View {
    int camera;
    Eigen::Vector2d pixel;  // at the candidate's stamp
    Eigen::Vector2d velocity;
    bool has_velocity;
    TimeNs stamp_ns;
    std::size_t index;  // into per_camera_[camera]
  };

  // Partner tracklet `t` moved to `stamp_ns`, with the pixel allowance its extrapolation needs.
  Eigen::Vector2d aligned(const Tracklet& t, TimeNs stamp_ns, double* allowance_px) const;
  double epipolar_distance_px(int camera_a, const Eigen::Vector2d& pixel_a, int camera_b,
                              const Eigen::Vector2d& pixel_b) const;

  // The best-supported pairing of a new blob with another camera's tracklet (support < 0: none).
  struct Pairing {
    int support = -1;  // further cameras that agree
    double error = std::numeric_limits<double>::infinity();
    std::vector<View> views;  // the new blob's first, its partner's second
    Eigen::Vector3d point;
  };

  // The new blobs of `camera` as tracklets, each continuing the nearest of its old tracklets.
  std::vector<Tracklet> continue_tracklets(int camera, TimeNs stamp_ns,
                                           const std::vector<Eigen::Vector2d>& blobs) const;
  // Pairs the new tracklet `mine` (blob `blob` of `camera`) with the other cameras' tracklets.
  Pairing best_pairing(int camera, TimeNs stamp_ns, const Tracklet& mine, std::size_t blob) const;
  // The candidate a pairing makes: refined from every view, with the velocity its views give.
  InitiationCandidate candidate_of(TimeNs stamp_ns, const Pairing& best) const;
  // Removes a pairing's partners (its views but the first) from their cameras' pools.
  void consume_partners(const Pairing& best);

  // Shared and immutable, so that copying an initiator (tracker checkpoints) copies only the pool.
  struct Geometry {
    std::vector<const CameraModel*> cameras;
    std::vector<Eigen::Matrix3d> essential;  // [b * n + a]: x_bᵀ E x_a = 0 (normalised coords)
  };

  InitiatorOptions options_;
  std::shared_ptr<const Geometry> geometry_ = std::make_shared<Geometry>();
  std::vector<std::vector<Tracklet>> per_camera_;
};

}  // namespace panoptes::estimator
