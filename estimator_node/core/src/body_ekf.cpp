// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/body_ekf.h"

#include <cmath>

#include <Eigen/LU>

namespace panoptes::estimator {

// Transition matrix of the error state over Δt (linearised about the nominal ω, α).
BodyMatrix body_transition(const BodyState& state, double dt) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  BodyMatrix A = BodyMatrix::Identity();
  // Constant acceleration (seed 000 Ch. 5, W, V, A): p' = p + v Δt + a Δt²/2, v' = v + a Δt.
  A.block<3, 3>(kBodyP, kBodyV) = dt * I;
  A.block<3, 3>(kBodyP, kBodyA) = 0.5 * dt * dt * I;
  A.block<3, 3>(kBodyV, kBodyA) = dt * I;
  // Constant angular acceleration (seed 003 eq. A.27 for the (Δr, ṙ) pair, extended by α). The
  // error is expressed in the body frame, which itself turns by φ = ω Δt + α Δt²/2:
  // δθ' = exp(-[φ]×) δθ + Δt δω + Δt²/2 δα, δω' = δω + Δt δα.
  const Eigen::Vector3d phi = dt * state.w + 0.5 * dt * dt * state.alpha;
  A.block<3, 3>(kBodyTheta, kBodyTheta) = rotation_vector_to_quaternion(-phi).toRotationMatrix();
  A.block<3, 3>(kBodyTheta, kBodyW) = dt * I;
  A.block<3, 3>(kBodyTheta, kBodyAlpha) = 0.5 * dt * dt * I;
  A.block<3, 3>(kBodyW, kBodyAlpha) = dt * I;
  return A;
}

// Q(Δt) for white jerk (positions; p, v, a), white angular jerk (δθ, ω, α) and white angular
// acceleration (δθ, ω); seed 003 eq. A.28 generalised to three integrators. For Δt < 0 (look-ups
// into the past) the blocks take the signs of backward extrapolation, so uncertainty still grows
// away from the last update.
BodyMatrix body_process_noise(double dt, const BodyMotionNoise& noise) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt;
  BodyMatrix Q = BodyMatrix::Zero();
  const double c[3][3] = {{d5 / 20, d4 / 8, d3 / 6}, {d4 / 8, d3 / 3, d2 / 2}, {d3 / 6, d2 / 2, dt}};
  const int rotation[3] = {kBodyTheta, kBodyW, kBodyAlpha};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      Q.block<3, 3>(3 * Eigen::Index{r}, 3 * Eigen::Index{k}) = noise.jerk * c[r][k] * I;
      Q.block<3, 3>(rotation[r], rotation[k]) = noise.angular_jerk * c[r][k] * I;
    }
  }
  const double w = noise.angular_accel;
  Q.block<3, 3>(kBodyTheta, kBodyTheta) += w * d3 / 3 * I;
  Q.block<3, 3>(kBodyTheta, kBodyW) += w * d2 / 2 * I;
  Q.block<3, 3>(kBodyW, kBodyTheta) += w * d2 / 2 * I;
  Q.block<3, 3>(kBodyW, kBodyW) += w * dt * I;
  if (dt < 0) Q = -Q;
  return Q;
}

Eigen::Quaterniond rotation_vector_to_quaternion(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, r / angle));
}

Eigen::Vector3d quaternion_to_rotation_vector(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();
  return 2.0 * std::atan2(s, q.w()) * q.vec() / s;
}

FilterCovariance<kBodyStateSize> body_prior(const BodyPriorSigmas& sigmas) {
  BodyVector variances;
  const double blocks[6] = {
      sigmas.position_m, sigmas.velocity_mps,           sigmas.acceleration_mps2,
      sigmas.angle_rad,  sigmas.angular_velocity_radps, sigmas.angular_acceleration_radps2};
  for (int k = 0; k < 6; ++k) variances.segment<3>(3 * Eigen::Index{k}).setConstant(blocks[k] * blocks[k]);
  return FilterCovariance<kBodyStateSize>::diagonal(variances);
}

void predict(BodyState& state, TimeNs stamp_ns, const BodyMotionNoise& noise) {
  const double dt = ns_to_seconds(stamp_ns - state.stamp_ns);
  if (dt != 0.0) {
    const BodyMatrix A = body_transition(state, dt);
    state.p += dt * state.v + 0.5 * dt * dt * state.a;
    state.v += dt * state.a;
    state.q =
        (state.q * rotation_vector_to_quaternion(dt * state.w + 0.5 * dt * dt * state.alpha)).normalized();
    state.w += dt * state.alpha;
    state.P.propagate(A, body_process_noise(dt, noise));
  }
  state.stamp_ns = stamp_ns;
}

BodyState predicted(const BodyState& state, TimeNs stamp_ns, const BodyMotionNoise& noise) {
  BodyState copy = state;
  predict(copy, stamp_ns, noise);
  return copy;
}

RigidTransform extrapolate_pose(const BodyState& state, double h) {
  RigidTransform pose;
  pose.t = state.p + h * state.v + 0.5 * h * h * state.a;
  pose.q = (state.q * rotation_vector_to_quaternion(h * state.w + 0.5 * h * h * state.alpha)).normalized();
  return pose;
}

std::optional<MarkerPixel> marker_pixel(const RigidTransform& pose, const Eigen::Vector3d& marker,
                                        const CameraModel& camera, double min_depth_m) {
  const Eigen::Matrix3d R = pose.q.toRotationMatrix();
  const Eigen::Vector3d p_world = pose.t + R * marker;
  const Eigen::Vector3d p_cam = camera.T_cam_world().apply(p_world);
  if (p_cam.z() < min_depth_m) return std::nullopt;
  Eigen::Matrix<double, 2, 3> J;
  const auto pixel = camera.project(p_world, &J);
  if (!pixel) return std::nullopt;
  MarkerPixel out;
  out.pixel = *pixel;
  out.J.leftCols<3>() = J;
  // p_world = p + R exp(δθ) m ≈ p + R m − R [m]× δθ  (seed 003 eq. A.29 linearised about δθ = 0).
  out.J.rightCols<3>() = -J * R * skew(marker);
  return out;
}

std::optional<MarkerProjection> project_marker(const BodyState& state, const Eigen::Vector3d& marker,
                                               const CameraModel& camera, double measurement_sigma_px,
                                               double min_depth_m) {
  const auto projected = marker_pixel(state.pose(), marker, camera, min_depth_m);
  if (!projected) return std::nullopt;
  return pose_measurement(state, *projected, measurement_sigma_px);
}

MarkerProjection pose_measurement(const BodyState& state, const MarkerPixel& projected,
                                  double measurement_sigma_px) {
  Eigen::Matrix<double, 2, kBodyStateSize> H = Eigen::Matrix<double, 2, kBodyStateSize>::Zero();
  H.block<2, 3>(0, kBodyP) = projected.J.leftCols<3>();
  H.block<2, 3>(0, kBodyTheta) = projected.J.rightCols<3>();
  return state.P.pixel_measurement(projected.pixel, H, measurement_sigma_px);
}

void update(BodyState& state, const MarkerProjection& projection, const Eigen::Vector2d& measurement,
            double /*measurement_sigma_px: already in the projection's S*/) {
  inject(state, state.P.update(projection, measurement));
}

void inject(BodyState& state, const BodyVector& dx) {
  inject_pose_blocks(state, dx);
}

BodyVector body_difference(const BodyState& to, const BodyState& from) {
  BodyVector dx;
  dx.segment<3>(kBodyP) = to.p - from.p;
  dx.segment<3>(kBodyV) = to.v - from.v;
  dx.segment<3>(kBodyA) = to.a - from.a;
  dx.segment<3>(kBodyTheta) = quaternion_to_rotation_vector(from.q.conjugate() * to.q);
  dx.segment<3>(kBodyW) = to.w - from.w;
  dx.segment<3>(kBodyAlpha) = to.alpha - from.alpha;
  return dx;
}

}  // namespace panoptes::estimator
