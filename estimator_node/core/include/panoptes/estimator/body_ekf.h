// SPDX-License-Identifier: Apache-2.0
// Rigid-body EKF maths: an error-state filter with the orientation kept as an external quaternion
// (seed 003 Appendix A.3.1, eqs. A.25–A.30) and a constant-acceleration motion model whose
// prediction follows seed 000 Ch. 5 (the W, V, A kinematics, state eq. 5.35), for the rotation too.
// The filter state is
//   x = (p, v, a, δθ, ω, α)       18 elements, world frame for p, v, a; body frame for δθ, ω, α
// with the orientation R_world_body = q ⊗ exp(δθ); after each update δθ is folded into q and
// zeroed (seed 003 eq. A.41). Each update takes one marker's 2D projection in one camera.
#pragma once

#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "panoptes/camera_model.h"
#include "panoptes/estimator/ekf.h"
#include "panoptes/geometry.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

inline constexpr int kBodyStateSize = 18;
using BodyVector = Eigen::Matrix<double, kBodyStateSize, 1>;
using BodyMatrix = Eigen::Matrix<double, kBodyStateSize, kBodyStateSize>;

// Indices of the state blocks.
inline constexpr int kBodyP = 0, kBodyV = 3, kBodyA = 6, kBodyTheta = 9, kBodyW = 12, kBodyAlpha = 15;

// The rotation has two noise terms: white angular acceleration drives ω directly (a constant
// angular velocity model when alone) and white angular jerk drives α (constant angular
// acceleration). With angular_jerk = 0 and no prior on α, α stays zero: the constant angular
// velocity model.
// Defaults from sweeps on issue 5's acceptance scene and issue 16's small fast bodies
// (docs/bodies.md, "Measurements"); bodies accelerating at 10-20 m/s² want jerk ≈ 150.
struct BodyMotionNoise {
  double jerk = 50.0;           // σ² of white jerk, m²/s⁵ (drives a; with it v and p)
  double angular_accel = 0.1;   // σ² of white angular acceleration, rad²/s³ (drives ω)
  double angular_jerk = 100.0;  // σ² of white angular jerk, rad²/s⁵ (drives α; with it ω and δθ)
};

struct BodyState {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();            // body origin, world frame, m
  Eigen::Vector3d v = Eigen::Vector3d::Zero();            // m/s
  Eigen::Vector3d a = Eigen::Vector3d::Zero();            // m/s²
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // R_world_body
  Eigen::Vector3d w = Eigen::Vector3d::Zero();            // angular velocity, body frame, rad/s
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();        // angular acceleration, body frame, rad/s²
  FilterCovariance<kBodyStateSize> P;                     // covariance of (p, v, a, δθ, ω, α)
  TimeNs stamp_ns = 0;

  RigidTransform pose() const { return {q, p}; }
};

// 1-σ of each block of a prior whose blocks are independent and isotropic.
struct BodyPriorSigmas {
  double position_m = 0.0;
  double velocity_mps = 0.0;
  double acceleration_mps2 = 0.0;
  double angle_rad = 0.0;
  double angular_velocity_radps = 0.0;
  double angular_acceleration_radps2 = 0.0;
};
FilterCovariance<kBodyStateSize> body_prior(const BodyPriorSigmas& sigmas);

// The error state's transition matrix over `dt` seconds from `state` (linearised about its ω, α).
BodyMatrix body_transition(const BodyState& state, double dt);
// The process noise Q(Δt) of the error state (also the base of an articulated chain, chain.h).
BodyMatrix body_process_noise(double dt, const BodyMotionNoise& noise);

// Moves the state to `stamp_ns` (forward or, for look-ups only, backward).
void predict(BodyState& state, TimeNs stamp_ns, const BodyMotionNoise& noise);
BodyState predicted(const BodyState& state, TimeNs stamp_ns, const BodyMotionNoise& noise);

// The pose extrapolated `horizon_s` ahead with the W, V, A kinematics of seed 000 Ch. 5:
// p + v h + a h²/2 and q ⊗ exp(ω h + α h²/2). No covariance (cheap; for publishing predictions).
RigidTransform extrapolate_pose(const BodyState& state, double horizon_s);

// A marker's pixel in a camera and its 2×6 Jacobian with respect to the pose's position (columns
// 0-2) and its body-frame rotation error δθ (columns 3-5), with p_world = p + R exp(δθ) m (seed 003
// eq. A.29). Shared by the filter and the synchronous snapshot solve (body_snapshot.h). Nullopt
// when the marker is closer than `min_depth_m` to the camera or does not project.
struct MarkerPixel {
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  Eigen::Matrix<double, 2, 6> J = Eigen::Matrix<double, 2, 6>::Zero();
};
std::optional<MarkerPixel> marker_pixel(const RigidTransform& pose, const Eigen::Vector3d& marker,
                                        const CameraModel& camera, double min_depth_m = 0.05);

// Projection of one marker (body-frame position `marker`) into a camera.
using MarkerProjection = PixelMeasurement<kBodyStateSize>;

std::optional<MarkerProjection> project_marker(const BodyState& state, const Eigen::Vector3d& marker,
                                               const CameraModel& camera, double measurement_sigma_px,
                                               double min_depth_m = 0.05);
// The filter's measurement for a pixel whose Jacobian is taken with respect to the pose (position,
// body-frame δθ): a marker on the body (above) or a landmark seen by a camera on the body
// (inside_out.h).
MarkerProjection pose_measurement(const BodyState& state, const MarkerPixel& projected,
                                  double measurement_sigma_px);

// EKF update with one marker measurement through the filter layer (ekf.h), which returns the error
// state δx; it is injected into the nominal state and δθ reset into q (eq. A.41). `projection`
// must have been made from this state (its H P and S, with the noise σ, are reused).
void update(BodyState& state, const MarkerProjection& projection, const Eigen::Vector2d& measurement,
            double measurement_sigma_px);

// The error-state difference `to` ⊖ `from` (p, v, a, ω, α subtracted; δθ = log(q_from⁻¹ q_to), in
// the body frame as the filter's δθ), and its inverse `state` ⊕ δx (the update's injection).
BodyVector body_difference(const BodyState& to, const BodyState& from);
void inject(BodyState& state, const BodyVector& dx);

// Rotation vector -> quaternion (exp map) and back.
Eigen::Quaterniond rotation_vector_to_quaternion(const Eigen::Vector3d& r);
Eigen::Vector3d quaternion_to_rotation_vector(const Eigen::Quaterniond& q);

// The pose blocks of inject()'s correction for any state with the body's members and block indices: the
// body filter's and an articulated chain's base (chain.h).
template <class State, class Correction>
void inject_pose_blocks(State& state, const Correction& dx) {
  state.p += dx.template segment<3>(kBodyP);
  state.v += dx.template segment<3>(kBodyV);
  state.a += dx.template segment<3>(kBodyA);
  state.w += dx.template segment<3>(kBodyW);
  state.alpha += dx.template segment<3>(kBodyAlpha);
  // Reset (seed 003 eq. A.41): the incremental rotation is added onto the external quaternion.
  state.q = (state.q * rotation_vector_to_quaternion(dx.template segment<3>(kBodyTheta))).normalized();
}

}  // namespace panoptes::estimator
