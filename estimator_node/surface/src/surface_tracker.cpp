// SPDX-License-Identifier: Apache-2.0
#include "panoptes/surface/surface_tracker.h"

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

#include "panoptes/estimator/assignment.h"
#include "panoptes/estimator/ekf.h"

namespace panoptes::surface {
namespace {

using State = Eigen::Matrix<double, 6, 1>;  // position, velocity, acceleration (x, y each)
using Covariance = estimator::FilterCovariance<6>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// The position rows: H = [I 0 0].
Eigen::Matrix<double, 2, 6> position_rows() {
  Eigen::Matrix<double, 2, 6> H = Eigen::Matrix<double, 2, 6>::Zero();
  H.leftCols<2>().setIdentity();
  return H;
}

// Constant-acceleration transition over dt and its white-jerk process noise with spectral density
// q (per axis: q·[dt⁵/20 dt⁴/8 dt³/6; dt⁴/8 dt³/3 dt²/2; dt³/6 dt²/2 dt]).
std::pair<Matrix6, Matrix6> transition(double dt, double q) {
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  Matrix6 F = Matrix6::Identity();
  F.block<2, 2>(0, 2) = dt * I;
  F.block<2, 2>(0, 4) = 0.5 * dt * dt * I;
  F.block<2, 2>(2, 4) = dt * I;
  const double dt2 = dt * dt, dt3 = dt2 * dt;
  Eigen::Matrix3d c;
  c << dt3 * dt2 / 20, dt2 * dt2 / 8, dt3 / 6, dt2 * dt2 / 8, dt3 / 3, dt2 / 2, dt3 / 6, dt2 / 2, dt;
  Matrix6 Q;
  for (Eigen::Index i = 0; i < 3; ++i)
    for (Eigen::Index j = 0; j < 3; ++j) Q.block<2, 2>(2 * i, 2 * j) = q * c(i, j) * I;
  return {F, Q};
}

struct Measurement {
  Eigen::Vector2d position;
  Eigen::Matrix2d R;
};

}  // namespace

struct SurfaceTracker::Spot {
  State x = State::Zero();
  Covariance P;
  TimeNs stamp_ns = 0;
  TimeNs first_stamp_ns = 0;
  Eigen::Vector2d first_position = Eigen::Vector2d::Zero();
  int updates = 0;
  std::uint32_t stroke_id = 0;  // 0 until confirmed
  int camera = -1;
  std::vector<std::pair<int, TimeNs>> last_seen;  // per camera that updated it: its newest stamp

  void seen_by(int camera_index, TimeNs stamp) {
    camera = camera_index;
    for (auto& [seen_camera, seen_stamp] : last_seen) {
      if (seen_camera == camera_index) {
        seen_stamp = stamp;
        return;
      }
    }
    last_seen.emplace_back(camera_index, stamp);
  }

  StrokeEvent event(StrokePhase phase, TimeNs window_ns) const {
    StrokeEvent e;
    e.phase = phase;
    e.stroke_id = stroke_id;
    e.stamp_ns = stamp_ns;
    e.position = x.head<2>();
    e.velocity = x.segment<2>(2);
    e.acceleration = x.tail<2>();
    e.camera = camera;
    e.cameras = static_cast<int>(std::count_if(last_seen.begin(), last_seen.end(), [&](const auto& seen) {
      return stamp_ns - seen.second <= window_ns;
    }));
    return e;
  }

  // This spot's state and covariance predicted to `stamp_ns` (not stored).
  std::pair<State, Covariance> predicted(TimeNs stamp_ns_to, double jerk_noise) const {
    const double dt = static_cast<double>(stamp_ns_to - stamp_ns) / static_cast<double>(kNsPerSecond);
    const auto [F, Q] = transition(dt, jerk_noise);
    Covariance P_pred = P;
    P_pred.propagate(F, Q);
    return {F * x, P_pred};
  }
};

SurfaceTracker::SurfaceTracker(SurfacePlane surface, std::vector<ImageToSurface> cameras,
                               SurfaceTrackerOptions options)
    : surface_(std::move(surface)),
      cameras_(std::move(cameras)),
      options_(options),
      camera_stamp_ns_(cameras_.size(), std::numeric_limits<TimeNs>::min() / 2) {}
SurfaceTracker::~SurfaceTracker() = default;
SurfaceTracker::SurfaceTracker(SurfaceTracker&&) noexcept = default;
SurfaceTracker& SurfaceTracker::operator=(SurfaceTracker&&) noexcept = default;

std::size_t SurfaceTracker::active_strokes() const {
  return static_cast<std::size_t>(
      std::count_if(spots_.begin(), spots_.end(), [](const Spot& spot) { return spot.stroke_id != 0; }));
}

void SurfaceTracker::end_stale(TimeNs now_ns, bool by_cameras, std::vector<StrokeEvent>& events) {
  auto stale = [&](const Spot& spot) {
    const TimeNs unseen = now_ns - spot.stamp_ns;
    if (unseen <= options_.end_after_ns) return false;
    if (!by_cameras || unseen > options_.camera_wait_ns) return true;
    return std::all_of(spot.last_seen.begin(), spot.last_seen.end(), [&](const auto& seen) {
      return camera_stamp_ns_[static_cast<std::size_t>(seen.first)] - spot.stamp_ns > options_.end_after_ns;
    });
  };
  for (const Spot& spot : spots_) {
    if (!stale(spot)) continue;
    if (spot.stroke_id != 0) {
      events.push_back(spot.event(StrokePhase::kEnd, options_.end_after_ns));
      ++counters_.strokes_ended;
    } else {
      ++counters_.unconfirmed_dropped;
    }
  }
  std::erase_if(spots_, stale);
}

// A confirmed spot becomes a stroke: its begin event carries its first sighting.
void SurfaceTracker::begin_stroke(Spot& spot, std::vector<StrokeEvent>& events) {
  spot.stroke_id = next_id_++;
  ++counters_.strokes_begun;
  StrokeEvent begin = spot.event(StrokePhase::kBegin, options_.end_after_ns);
  begin.stamp_ns = spot.first_stamp_ns;
  begin.position = spot.first_position;
  events.push_back(begin);
}

std::vector<StrokeEvent> SurfaceTracker::end_silent(TimeNs now_ns) {
  std::vector<StrokeEvent> events;
  end_stale(now_ns, false, events);
  return events;
}

std::vector<StrokeEvent> SurfaceTracker::add_frame(int camera, TimeNs stamp_ns,
                                                   std::span<const Eigen::Vector2d> pixels) {
  std::vector<StrokeEvent> events;
  if (camera < 0 || static_cast<std::size_t>(camera) >= cameras_.size()) {
    ++counters_.unknown_camera;
    return events;
  }
  if (started_ && stamp_ns < last_stamp_ns_) {
    ++counters_.late_frames;
    return events;
  }
  started_ = true;
  last_stamp_ns_ = stamp_ns;
  ++counters_.frames;
  // Before the association (so that a new spot cannot join a stroke that has ended), this camera
  // counts with its previous frame; after it, with this one.
  end_stale(stamp_ns, true, events);

  std::vector<Measurement> measurements;
  const double variance = options_.pixel_sigma * options_.pixel_sigma;
  for (const auto& pixel : pixels) {
    ++counters_.spots;
    Eigen::Matrix2d J;
    const auto st = cameras_[static_cast<std::size_t>(camera)].map(pixel, &J);
    if (!st || !J.allFinite()) {
      ++counters_.unmappable;
    } else if (!surface_.contains(*st)) {
      ++counters_.off_surface;
    } else {
      measurements.push_back({*st, variance * J * J.transpose()});
    }
  }

  // Gate every spot's prediction against every measurement; assign jointly.
  std::vector<std::pair<State, Covariance>> predictions;
  predictions.reserve(spots_.size());
  for (const Spot& spot : spots_) predictions.push_back(spot.predicted(stamp_ns, options_.jerk_noise));
  std::vector<estimator::GatedPair> pairs;
  for (std::size_t s = 0; s < spots_.size(); ++s) {
    const Eigen::Matrix2d P_position = predictions[s].second.matrix().topLeftCorner<2, 2>();
    for (std::size_t m = 0; m < measurements.size(); ++m) {
      const Eigen::Matrix2d S = P_position + measurements[m].R;
      const Eigen::Vector2d r = measurements[m].position - predictions[s].first.head<2>();
      const double d2 = r.dot(S.inverse() * r);
      if (estimator::inside_gate(d2, options_.gate_chi2)) pairs.push_back({s, m, d2});
    }
  }
  std::vector<bool> used(measurements.size(), false);
  for (const auto& [s, m] : estimator::assign_gated(pairs, 0.5 * options_.gate_chi2)) {
    Spot& spot = spots_[s];
    auto& [x, P] = predictions[s];
    x += P.update<2>(position_rows(), measurements[m].R, measurements[m].position - x.head<2>());
    spot.x = x;
    spot.P = P;
    spot.stamp_ns = stamp_ns;
    spot.seen_by(camera, stamp_ns);
    used[m] = true;
    if (++spot.updates >= options_.confirm_updates && spot.stroke_id == 0) begin_stroke(spot, events);
    if (spot.stroke_id != 0) events.push_back(spot.event(StrokePhase::kContinue, options_.end_after_ns));
  }

  // Spots no stroke explained start new ones, unless they sit on a stroke (a second blob of one
  // spot, e.g. a reflection's halo).
  for (std::size_t m = 0; m < measurements.size(); ++m) {
    if (used[m]) continue;
    const bool duplicate = std::any_of(predictions.begin(), predictions.end(), [&](const auto& prediction) {
      return (prediction.first.template head<2>() - measurements[m].position).norm() <
             options_.duplicate_distance_m;
    });
    if (duplicate) {
      ++counters_.duplicate_spots;
      continue;
    }
    Spot spot;
    spot.x.head<2>() = measurements[m].position;
    State variances;
    const double v2 = options_.initial_speed_sigma * options_.initial_speed_sigma,
                 a2 = options_.initial_accel_sigma * options_.initial_accel_sigma;
    variances << 0, 0, v2, v2, a2, a2;
    Matrix6 prior = Matrix6(variances.asDiagonal());
    prior.topLeftCorner<2, 2>() = measurements[m].R;
    spot.P = Covariance(prior);
    spot.stamp_ns = spot.first_stamp_ns = stamp_ns;
    spot.first_position = measurements[m].position;
    spot.updates = 1;
    spot.seen_by(camera, stamp_ns);
    if (spot.updates >= options_.confirm_updates) begin_stroke(spot, events);
    spots_.push_back(spot);
  }
  camera_stamp_ns_[static_cast<std::size_t>(camera)] = stamp_ns;
  end_stale(stamp_ns, true, events);
  return events;
}

}  // namespace panoptes::surface
