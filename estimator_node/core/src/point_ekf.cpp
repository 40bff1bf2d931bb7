// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/point_ekf.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

namespace panoptes::estimator {

Matrix6d transition_matrix(double dt_s) {
  Matrix6d A = Matrix6d::Identity();
  A.block<3, 3>(0, 3) = dt_s * Eigen::Matrix3d::Identity();
  return A;
}

Matrix6d process_noise(double dt_s, double sigma2) {
  // Seed 003 eq. A.48 per axis: σ² [[Δt³/3, Δt²/2], [Δt²/2, Δt]]. For Δt < 0 (a look-up into the
  // past) the magnitude is used so that uncertainty still grows away from the last update.
  const double dt = dt_s < 0 ? -dt_s : dt_s;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  Matrix6d Q;
  Q.block<3, 3>(0, 0) = (dt * dt * dt / 3.0) * sigma2 * I;
  Q.block<3, 3>(0, 3) = (dt * dt / 2.0) * sigma2 * I;
  Q.block<3, 3>(3, 0) = (dt * dt / 2.0) * sigma2 * I;
  Q.block<3, 3>(3, 3) = dt * sigma2 * I;
  if (dt_s < 0) {
    // Cross terms change sign when extrapolating backwards.
    Q.block<3, 3>(0, 3) *= -1.0;
    Q.block<3, 3>(3, 0) *= -1.0;
  }
  return Q;
}

namespace {
// How long of `dt_s` the acceleration input acts, signed like dt_s.
double accelerated_for(const PointState& state, double dt_s) {
  const double h = std::min(std::abs(dt_s), state.acceleration_horizon_s);
  return dt_s < 0 ? -h : h;
}
}  // namespace

Eigen::Vector3d position_after(const PointState& state, double dt_s) {
  const double h = accelerated_for(state, dt_s);
  return state.position() + dt_s * state.velocity() + (h * dt_s - 0.5 * h * h) * state.acceleration;
}

void predict(PointState& state, TimeNs stamp_ns, double sigma2) {
  const double dt = ns_to_seconds(stamp_ns - state.stamp_ns);
  if (dt != 0.0) {
    const double h = accelerated_for(state, dt);
    state.x.head<3>() = position_after(state, dt);  // eq. A.31, with the known input
    state.x.tail<3>() += h * state.acceleration;
    state.acceleration_horizon_s -= std::abs(h);
    state.P.propagate_constant_velocity(dt, process_noise(dt, sigma2));  // eq. A.32
  }
  state.stamp_ns = stamp_ns;
}

PointState predicted(const PointState& state, TimeNs stamp_ns, double sigma2) {
  PointState copy = state;
  predict(copy, stamp_ns, sigma2);
  return copy;
}

std::optional<PointProjection> project_point(const PointState& state, const CameraModel& camera,
                                             double measurement_sigma_px) {
  Eigen::Matrix<double, 2, 3> J;
  const auto pixel = camera.project(state.position(), &J);
  if (!pixel) return std::nullopt;
  Eigen::Matrix<double, 2, 6> H = Eigen::Matrix<double, 2, 6>::Zero();
  H.leftCols<3>() = J;
  return state.P.pixel_measurement(*pixel, H, measurement_sigma_px);
}

void update(PointState& state, const PointProjection& projection, const Eigen::Vector2d& measurement,
            double /*measurement_sigma_px: already in the projection's S*/) {
  state.x += state.P.update(projection, measurement);
}

void update_along(PointState& state, const Eigen::Vector3d& direction, double measured_m, double sigma_m) {
  Eigen::Matrix<double, 1, 6> H = Eigen::Matrix<double, 1, 6>::Zero();
  H.head<3>() = direction.transpose();
  const Eigen::Matrix<double, 1, 1> R(sigma_m * sigma_m);
  const Eigen::Matrix<double, 1, 1> residual(measured_m - direction.dot(state.position()));
  state.x += state.P.update<1>(H, R, residual);
}

}  // namespace panoptes::estimator
