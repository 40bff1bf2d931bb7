// SPDX-License-Identifier: Apache-2.0
// Pose of a 7-LED marker from known correspondences (seed 004 §2.2.3): homography from the six
// coplanar LEDs, Levenberg-Marquardt on eq. 3, the second planar minimum, the pointer LED (eq. 4-5)
// and a final refinement with all seven LEDs. Everything runs in the model's plane frame (origin
// M3, M0..M5 at z ~ 0) and is converted to the model frame at the end.
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "panoptes/estimator/led_marker.h"
#include "panoptes/rigid_fit.h"

namespace panoptes::estimator {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Pose {  // T_cam_plane
  Matrix3d R = Matrix3d::Identity();
  Vector3d t = Vector3d::Zero();
};

// e_proj (eq. 3) over the first n LEDs; +inf if an LED is not in front of the camera.
double cost(const Pose& pose, const std::array<Vector3d, 7>& P, const LedPoints& m, int n) {
  double e = 0;
  for (int i = 0; i < n; ++i) {
    const Vector3d q = pose.R * P[i] + pose.t;
    if (!(q.z() > 1e-9)) return kInf;
    e += (q.head<2>() / q.z() - m[i]).squaredNorm();
  }
  return e;
}

// Levenberg-Marquardt on eq. 3 over the first n LEDs, 6 parameters (rotation increment w on the
// left, R <- exp(w) R, and t), analytic Jacobian: d(pi)/dq * [-[q]x | I], q = R P + t.
Pose refine(Pose pose, const std::array<Vector3d, 7>& P, const LedPoints& m, int n, double* final_cost) {
  double e = cost(pose, P, m, n);
  if (!std::isfinite(e)) {
    if (final_cost) *final_cost = e;
    return pose;
  }
  double lambda = 1e-4;
  Matrix6d JtJ;
  Vector6d Jtr;
  auto linearise = [&]() {
    JtJ.setZero();
    Jtr.setZero();
    for (int i = 0; i < n; ++i) {
      const Vector3d Rp = pose.R * P[i];
      const Vector3d q = Rp + pose.t;
      const double iz = 1.0 / q.z();
      const double u = q.x() * iz, v = q.y() * iz;
      const Vector2d r(u - m[i].x(), v - m[i].y());
      Eigen::Matrix<double, 2, 3> Jq;
      Jq << iz, 0, -u * iz, 0, iz, -v * iz;
      Eigen::Matrix3d skew;
      skew << 0, -Rp.z(), Rp.y(), Rp.z(), 0, -Rp.x(), -Rp.y(), Rp.x(), 0;
      Eigen::Matrix<double, 2, 6> J;
      J.leftCols<3>() = -Jq * skew;
      J.rightCols<3>() = Jq;
      JtJ.noalias() += J.transpose() * J;
      Jtr.noalias() += J.transpose() * r;
    }
  };
  linearise();
  for (int iteration = 0; iteration < 50; ++iteration) {
    Matrix6d A = JtJ;
    A.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
    const Vector6d delta = -A.llt().solve(Jtr);
    if (!delta.allFinite()) break;
    Pose candidate;
    const double angle = delta.head<3>().norm();
    candidate.R = (angle > 0 ? Eigen::AngleAxisd(angle, delta.head<3>() / angle).toRotationMatrix()
                             : Matrix3d::Identity()) *
                  pose.R;
    candidate.t = pose.t + delta.tail<3>();
    const double e_new = cost(candidate, P, m, n);
    if (e_new < e) {
      const double gain = e - e_new;
      pose = candidate;
      e = e_new;
      lambda = std::max(lambda * 0.2, 1e-9);
      // Converged: the cost no longer moves (noise-level residuals) or the step is negligible.
      if (gain < 1e-7 * (e + gain) || delta.norm() < 1e-10) break;
      linearise();
    } else {
      lambda *= 8;
      if (lambda > 1e8) break;
    }
  }
  pose.R = nearest_rotation(pose.R);
  if (final_cost) *final_cost = e;
  return pose;
}

// Plane-to-image homography from the six coplanar LEDs (six_point_homography), then the planar
// pose (Xu et al. 2009; Zhang): H ~ [r1 r2 t].
std::optional<Pose> homography_pose(const std::array<Vector3d, 7>& P, const LedPoints& m) {
  LedPoints plane;
  for (int i = 0; i < kLedCount; ++i)
    plane[static_cast<std::size_t>(i)] = P[static_cast<std::size_t>(i)].head<2>();
  const auto homography = six_point_homography(plane, m);
  if (!homography) return std::nullopt;
  const Matrix3d& H = *homography;
  double scale = 0.5 * (H.col(0).norm() + H.col(1).norm());
  if (!(scale > 0)) return std::nullopt;
  if (H(2, 2) < 0) scale = -scale;  // the marker is in front of the camera: t_z > 0
  Matrix3d M;
  M.col(0) = H.col(0) / scale;
  M.col(1) = H.col(1) / scale;
  M.col(2) = M.col(0).cross(M.col(1));
  Pose pose;
  pose.R = nearest_rotation(M);
  pose.t = H.col(2) / scale;
  if (!pose.R.allFinite() || !pose.t.allFinite() || pose.t.z() <= 0) return std::nullopt;
  return pose;
}

// Start of the second planar minimum (Schweighofer & Pinz 2006): the ambiguity is, to first order,
// the reflection of the target plane about the plane through its centre perpendicular to the line
// of sight s. R2 = (I - 2 s s^T) R1 diag(1, 1, -1) maps every coplanar LED (z = 0) to its mirror
// image and keeps the marker facing the camera; LM then settles in the second minimum.
Pose mirrored(const Pose& pose, const std::array<Vector3d, 7>& P) {
  Vector3d centre = Vector3d::Zero();
  for (int i = 0; i < 6; ++i) centre += Vector3d(P[i].x(), P[i].y(), 0);
  centre /= 6;
  const Vector3d c = pose.R * centre + pose.t;
  const Vector3d s = c.normalized();
  const Matrix3d reflect = Matrix3d::Identity() - 2 * s * s.transpose();
  Pose out;
  out.R = reflect * pose.R * Eigen::Vector3d(1, 1, -1).asDiagonal();
  out.t = c - out.R * centre;
  return out;
}

RigidTransform to_model(const Pose& pose, const LedMarkerModel& model) {
  RigidTransform T_cam_plane;
  T_cam_plane.q = Eigen::Quaterniond(pose.R).normalized();
  T_cam_plane.t = pose.t;
  return T_cam_plane * model.T_model_plane().inverse();
}

Pose from_model(const RigidTransform& T_cam_marker, const LedMarkerModel& model) {
  const RigidTransform T = T_cam_marker * model.T_model_plane();
  return {T.rotation(), T.t};
}

bool finite(const LedPoints& m) {
  for (const auto& p : m)
    if (!p.allFinite()) return false;
  return true;
}

}  // namespace

std::optional<RigidTransform> led_marker_homography_pose(const LedMarkerModel& model,
                                                         const LedPoints& points) {
  if (!finite(points)) return std::nullopt;
  const auto pose = homography_pose(model.plane_leds(), points);
  if (!pose) return std::nullopt;
  return to_model(*pose, model);
}

double led_reprojection_error(const LedMarkerModel& model, const RigidTransform& T_cam_marker,
                              const LedPoints& points) {
  return cost(from_model(T_cam_marker, model), model.plane_leds(), points, kLedCount) / kLedCount;
}

std::optional<LedPose> estimate_led_marker_pose(const LedMarkerModel& model, const LedPoints& points,
                                                LedPoseMethod method) {
  if (!finite(points)) return std::nullopt;
  const auto& P = model.plane_leds();
  const auto PH = homography_pose(P, points);
  if (!PH) return std::nullopt;
  Pose chosen;
  double e = kInf;
  if (method == LedPoseMethod::kAllSeven) {
    chosen = refine(*PH, P, points, kLedCount, &e);  // eq. 11
  } else {
    double e1 = kInf;
    const Pose P1 = refine(*PH, P, points, 6, &e1);  // P1 = argmin e_proj(P, 5), eq. 3
    if (!std::isfinite(e1)) return std::nullopt;
    if (method == LedPoseMethod::kCoplanar) {
      chosen = P1;  // eq. 9
    } else {
      double e2 = kInf;
      const Pose P2 = refine(mirrored(P1, P), P, points, 6, &e2);
      if (method == LedPoseMethod::kCoplanarBestOfTwo) {
        chosen = e2 < e1 ? P2 : P1;  // eq. 10
      } else {
        // eq. 4-5: the pointer LED M6 decides between the two minima.
        auto e_pointer = [&](const Pose& pose) {
          const Vector3d q = pose.R * P[6] + pose.t;
          return q.z() > 0 ? (q.head<2>() / q.z() - points[6]).squaredNorm() : kInf;
        };
        const Pose& best = std::isfinite(e2) && e_pointer(P2) < e_pointer(P1) ? P2 : P1;
        chosen = refine(best, P, points, kLedCount, &e);  // final pose: argmin e_proj(P, 6)
      }
    }
  }
  const double e7 = cost(chosen, P, points, kLedCount);
  if (!std::isfinite(e7)) return std::nullopt;
  LedPose out;
  out.T_cam_marker = to_model(chosen, model);
  out.rms = std::sqrt(e7 / kLedCount);
  return out;
}

std::optional<Eigen::Matrix3d> six_point_homography(const LedPoints& from, const LedPoints& to) {
  Vector2d c_from = Vector2d::Zero(), c_to = Vector2d::Zero();
  for (int i = 0; i < 6; ++i) c_from += from[i], c_to += to[i];
  c_from /= 6, c_to /= 6;
  double s_from = 0, s_to = 0;
  for (int i = 0; i < 6; ++i) s_from += (from[i] - c_from).norm(), s_to += (to[i] - c_to).norm();
  if (!(s_from > 0) || !(s_to > 0)) return std::nullopt;
  s_from = 6 * std::sqrt(2.0) / s_from, s_to = 6 * std::sqrt(2.0) / s_to;
  Eigen::Matrix<double, 8, 8> AtA = Eigen::Matrix<double, 8, 8>::Zero();
  Eigen::Matrix<double, 8, 1> Atb = Eigen::Matrix<double, 8, 1>::Zero();
  for (int i = 0; i < 6; ++i) {
    const Vector2d x = (from[i] - c_from) * s_from, u = (to[i] - c_to) * s_to;
    Eigen::Matrix<double, 8, 1> a, b;
    a << x.x(), x.y(), 1, 0, 0, 0, -u.x() * x.x(), -u.x() * x.y();
    b << 0, 0, 0, x.x(), x.y(), 1, -u.y() * x.x(), -u.y() * x.y();
    AtA.noalias() += a * a.transpose() + b * b.transpose();
    Atb += a * u.x() + b * u.y();
  }
  const Eigen::Matrix<double, 8, 1> h = AtA.ldlt().solve(Atb);
  if (!h.allFinite()) return std::nullopt;
  Matrix3d Hn, T_from, T_to_inverse;
  Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), 1;
  T_from << s_from, 0, -s_from * c_from.x(), 0, s_from, -s_from * c_from.y(), 0, 0, 1;
  T_to_inverse << 1 / s_to, 0, c_to.x(), 0, 1 / s_to, c_to.y(), 0, 0, 1;
  return T_to_inverse * Hn * T_from;
}

}  // namespace panoptes::estimator
