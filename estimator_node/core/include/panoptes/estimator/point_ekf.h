// SPDX-License-Identifier: Apache-2.0
// Point-track EKF maths (seed 003 Appendix A.3): state apart from maths. The covariance is a
// FilterCovariance (ekf.h), changed only by the filter layer's propagate and update.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "panoptes/camera_model.h"
#include "panoptes/estimator/ekf.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct PointState {
  Vector6d x = Vector6d::Zero();  // p (m), v (m/s), world frame
  FilterCovariance<6> P;
  TimeNs stamp_ns = 0;
  // A known acceleration input (m/s², world frame; zero unless the owner sets it), acting for the
  // first `acceleration_horizon_s` after stamp_ns, constant velocity after: prediction moves the mean
  // by it, the covariance stays the constant-velocity model's, whose white acceleration covers the
  // input's error (the tracker's fast tracks, docs/estimator.md "Acceleration input"). A coasting
  // track is not extrapolated on a parabola.
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();
  double acceleration_horizon_s = 0;

  Eigen::Vector3d position() const { return x.head<3>(); }
  Eigen::Vector3d velocity() const { return x.tail<3>(); }
};

// A(Δt), seed 003 eq. A.27 (the position/velocity block).
Matrix6d transition_matrix(double dt_s);
// Q(Δt) for white acceleration noise of spectral density `sigma2` (m²/s³), eq. A.28 / A.48.
Matrix6d process_noise(double dt_s, double sigma2);

// The mean of `state` `dt_s` from its stamp: p + v Δt + a (h Δt - h²/2), h = min(|Δt|,
// acceleration_horizon_s) (Δt ≥ 0; a Δt < 0 look-up mirrors it).
Eigen::Vector3d position_after(const PointState& state, double dt_s);

// Predicts `state` to `stamp_ns` (which may be earlier: Δt < 0 is used only for look-ups, see
// predicted()). Eq. A.31–A.32.
void predict(PointState& state, TimeNs stamp_ns, double sigma2);
PointState predicted(const PointState& state, TimeNs stamp_ns, double sigma2);

// The projection of a track into one camera with what gating and the update need.
using PointProjection = PixelMeasurement<6>;

// nullopt if the point is behind the camera.
std::optional<PointProjection> project_point(const PointState& state, const CameraModel& camera,
                                             double measurement_sigma_px);

// EKF update with one 2D measurement through the filter layer (ekf.h: P − K S Kᵀ, symmetrised).
// `projection` must have been made from this state (its H P and S, with the noise σ, are reused);
// `measurement_sigma_px` is that σ, kept for the callers' readability.
void update(PointState& state, const PointProjection& projection, const Eigen::Vector2d& measurement,
            double measurement_sigma_px);

// EKF update with a measurement of the position's component along the unit vector `direction`
// (z = directionᵀ p with noise σ = `sigma_m`): a depth along a camera's ray that its pixels cannot tell.
void update_along(PointState& state, const Eigen::Vector3d& direction, double measured_m, double sigma_m);

}  // namespace panoptes::estimator
