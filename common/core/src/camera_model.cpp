// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera_model.h"

#include <cmath>

#include <Eigen/LU>

#include "panoptes/distortion.h"

namespace panoptes {

namespace {

// Points closer to the image plane than this are treated as behind the camera: their
// projection would be numerically meaningless.
constexpr double kMinDepth = 1e-9;
constexpr int kUndistortIterations = 20;
constexpr double kUndistortTolerance = 1e-12;

}  // namespace

CameraModel::CameraModel(const CameraIntrinsics& intrinsics, const RigidTransform& T_world_cam)
    : intrinsics_(intrinsics), T_world_cam_(T_world_cam) {
  // A quaternion that is already unit to rounding is kept bit for bit so a model rebuilt from a
  // saved calibration is identical; anything further off would silently scale the rotation.
  if (std::abs(T_world_cam_.q.squaredNorm() - 1.0) > 1e-12) T_world_cam_.q.normalize();
  T_cam_world_ = T_world_cam_.inverse();
  R_cam_world_ = T_cam_world_.rotation();
}

// The model (distortion.h, shared with the calibration's Ceres costs) and its exact Jacobian.
Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& xn, Eigen::Matrix2d* J) const {
  const auto& d = intrinsics_.distortion;
  Eigen::Vector2d xd = distort_normalized<double>(xn.x(), xn.y(), d.data());
  if (J != nullptr) {
    const double k1 = d[0], k2 = d[1], p1 = d[2], p2 = d[3], k3 = d[4];
    const double x = xn.x(), y = xn.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    // d(radial)/d(r2), then the chain rule through d(r2)/dx = 2x, d(r2)/dy = 2y.
    const double dradial_dr2 = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    const double dradial_dx = 2.0 * x * dradial_dr2;
    const double dradial_dy = 2.0 * y * dradial_dr2;
    (*J)(0, 0) = radial + x * dradial_dx + 2.0 * p1 * y + 6.0 * p2 * x;
    (*J)(0, 1) = x * dradial_dy + 2.0 * p1 * x + 2.0 * p2 * y;
    (*J)(1, 0) = y * dradial_dx + 2.0 * p1 * x + 2.0 * p2 * y;
    (*J)(1, 1) = radial + y * dradial_dy + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return xd;
}

Eigen::Vector2d CameraModel::undistort(const Eigen::Vector2d& xd) const {
  // Newton on distort(x) = xd, starting from the distorted point (exact when distortion is zero).
  // The step is halved while it does not reduce the residual so strong distortion near the edge
  // of the monotonic region does not make it jump to a far, wrong root.
  Eigen::Vector2d x = xd;
  Eigen::Matrix2d J;
  Eigen::Vector2d residual = distort(x, &J) - xd;
  double residual_norm = residual.norm();
  for (int iteration = 0; iteration < kUndistortIterations && residual_norm > kUndistortTolerance;
       ++iteration) {
    const double det = J.determinant();
    if (!std::isfinite(det) || std::abs(det) < 1e-15) break;
    const Eigen::Vector2d step = -J.inverse() * residual;
    double scale = 1.0;
    bool improved = false;
    for (int halving = 0; halving < 10; ++halving, scale *= 0.5) {
      const Eigen::Vector2d candidate = x + scale * step;
      Eigen::Matrix2d J_candidate;
      const Eigen::Vector2d candidate_residual = distort(candidate, &J_candidate) - xd;
      const double candidate_norm = candidate_residual.norm();
      if (candidate_norm < residual_norm) {
        x = candidate;
        J = J_candidate;
        residual = candidate_residual;
        residual_norm = candidate_norm;
        improved = true;
        break;
      }
    }
    if (!improved || (scale * step).norm() < kUndistortTolerance) break;
  }
  return x;
}

std::optional<Eigen::Vector2d> CameraModel::project_camera_point(const Eigen::Vector3d& p_cam,
                                                                 Eigen::Matrix<double, 2, 3>* J_cam) const {
  const double z = p_cam.z();
  if (!(z > kMinDepth)) return std::nullopt;
  const double inv_z = 1.0 / z;
  const Eigen::Vector2d xn(p_cam.x() * inv_z, p_cam.y() * inv_z);
  Eigen::Matrix2d J_distort;
  const Eigen::Vector2d xd = distort(xn, J_cam != nullptr ? &J_distort : nullptr);
  const Eigen::Vector2d pixel(intrinsics_.fx * xd.x() + intrinsics_.cx,
                              intrinsics_.fy * xd.y() + intrinsics_.cy);
  if (J_cam != nullptr) {
    Eigen::Matrix<double, 2, 3> J_normalized;
    J_normalized << inv_z, 0.0, -xn.x() * inv_z, 0.0, inv_z, -xn.y() * inv_z;
    const Eigen::Matrix2d J_focal = Eigen::Vector2d(intrinsics_.fx, intrinsics_.fy).asDiagonal();
    *J_cam = J_focal * J_distort * J_normalized;
  }
  return pixel;
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p_world,
                                                    Eigen::Matrix<double, 2, 3>* J_world) const {
  const Eigen::Vector3d p_cam = R_cam_world_ * p_world + T_cam_world_.t;
  Eigen::Matrix<double, 2, 3> J_cam;
  auto pixel = project_camera_point(p_cam, J_world != nullptr ? &J_cam : nullptr);
  if (pixel && J_world != nullptr) *J_world = J_cam * R_cam_world_;
  return pixel;
}

Eigen::Vector2d CameraModel::pixel_to_normalized(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d xd((pixel.x() - intrinsics_.cx) / intrinsics_.fx,
                           (pixel.y() - intrinsics_.cy) / intrinsics_.fy);
  return undistort(xd);
}

Eigen::Vector3d CameraModel::pixel_to_world_ray(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d xn = pixel_to_normalized(pixel);
  const Eigen::Vector3d ray_cam = Eigen::Vector3d(xn.x(), xn.y(), 1.0).normalized();
  return T_world_cam_.q * ray_cam;
}

// Pixel centres are integers, so the sensor covers [-0.5, width - 0.5); a positive margin widens it.
bool CameraModel::in_image(const Eigen::Vector2d& pixel, double margin) const {
  return pixel.x() >= -0.5 - margin && pixel.x() < intrinsics_.width - 0.5 + margin &&
         pixel.y() >= -0.5 - margin && pixel.y() < intrinsics_.height - 0.5 + margin;
}

}  // namespace panoptes
