// SPDX-License-Identifier: Apache-2.0
#include "panoptes/surface/image_to_surface.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

namespace panoptes::surface {
namespace {

// |det| below this (of a homography scaled to unit Frobenius norm) is singular.
constexpr double kSingularDeterminant = 1e-12;

void require_regular(const Eigen::Matrix3d& H, const char* what) {
  if (!H.allFinite()) throw std::invalid_argument(std::string(what) + ": the homography is not finite");
  const double norm = H.norm();
  if (norm == 0.0 || std::abs((H / norm).determinant()) < kSingularDeterminant)
    throw std::invalid_argument(
        std::string(what) + ": the homography is singular (points collinear, or the surface seen edge-on)");
}

// A similarity that moves `points` to their centroid and scales their mean distance to √2
// (Hartley), so that the DLT's equations are well conditioned.
Eigen::Matrix3d normalising_transform(std::span<const Eigen::Vector2d> points) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  double mean_distance = 0;
  for (const auto& p : points) mean_distance += (p - centroid).norm();
  mean_distance /= static_cast<double>(points.size());
  const double scale = mean_distance > 0.0 ? std::sqrt(2.0) / mean_distance : 1.0;
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity();
  T(0, 0) = T(1, 1) = scale;
  T.block<2, 1>(0, 2) = -scale * centroid;
  return T;
}

}  // namespace

ImageToSurface ImageToSurface::from_homography(const Eigen::Matrix3d& H_surface_pixel) {
  require_regular(H_surface_pixel, "image-to-surface homography");
  ImageToSurface mapping;
  mapping.H_ = H_surface_pixel;
  return mapping;
}

ImageToSurface ImageToSurface::from_plane(const CameraModel& camera, const SurfacePlane& plane) {
  // A surface point (s, t) is at camera-frame X_c = R (o + s u + t v) + t_cw, so its normalised
  // image point is G (s, t, 1) with G = [R u | R v | R o + t_cw]; the mapping is G⁻¹.
  const RigidTransform& T_cam_world = camera.T_cam_world();
  const Eigen::Matrix3d R = T_cam_world.rotation();
  Eigen::Matrix3d G;
  G.col(0) = R * plane.u_axis;
  G.col(1) = R * plane.v_axis;
  G.col(2) = T_cam_world.apply(plane.origin);
  require_regular(G, "surface plane");
  bool any_in_front = false;
  for (const double s : {0.0, plane.size.x()})
    for (const double t : {0.0, plane.size.y()})
      any_in_front = any_in_front || T_cam_world.apply(plane.at({s, t})).z() > 0.0;
  if (!any_in_front) throw std::invalid_argument("surface plane: the surface lies behind the camera");
  ImageToSurface mapping;
  mapping.H_ = G.inverse();
  mapping.camera_ = camera;
  return mapping;
}

std::optional<Eigen::Vector2d> ImageToSurface::map(const Eigen::Vector2d& pixel, Eigen::Matrix2d* J) const {
  Eigen::Vector2d image = pixel;
  Eigen::Matrix2d J_image_pixel = Eigen::Matrix2d::Identity();
  if (camera_) {
    image = camera_->pixel_to_normalized(pixel);
    // d(pixel)/d(normalised) = diag(fx, fy) · d(distorted)/d(undistorted); the mapping inverts it.
    Eigen::Matrix2d J_distort;
    camera_->distort(image, &J_distort);
    const auto& K = camera_->intrinsics();
    J_image_pixel = (Eigen::Vector2d(K.fx, K.fy).asDiagonal() * J_distort).inverse();
  }
  const Eigen::Vector3d h = H_ * image.homogeneous();
  // w ≤ 0: the point is on or beyond the horizon of the plane (behind the camera for a plane).
  if (!(h.z() > 1e-12 * h.head<2>().norm()) || !h.allFinite()) return std::nullopt;
  const Eigen::Vector2d st = h.head<2>() / h.z();
  if (J) {
    Eigen::Matrix<double, 2, 3> J_project;
    J_project << 1.0 / h.z(), 0.0, -h.x() / (h.z() * h.z()), 0.0, 1.0 / h.z(), -h.y() / (h.z() * h.z());
    *J = J_project * H_.leftCols<2>() * J_image_pixel;
  }
  return st;
}

Eigen::Matrix3d fit_homography(std::span<const Eigen::Vector2d> pixels,
                               std::span<const Eigen::Vector2d> surface) {
  if (pixels.size() != surface.size())
    throw std::invalid_argument("homography: " + std::to_string(pixels.size()) + " pixels but " +
                                std::to_string(surface.size()) + " surface points");
  if (pixels.size() < 4)
    throw std::invalid_argument("homography: needs at least 4 point pairs, got " +
                                std::to_string(pixels.size()));
  const Eigen::Matrix3d Tp = normalising_transform(pixels), Ts = normalising_transform(surface);
  const auto n = static_cast<Eigen::Index>(pixels.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n, 9);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = Tp * pixels[static_cast<std::size_t>(i)].homogeneous();
    const Eigen::Vector3d q = Ts * surface[static_cast<std::size_t>(i)].homogeneous();
    // q × (H p) = 0: two independent rows per pair.
    A.block<1, 3>(2 * i, 3) = -q.z() * p.transpose();
    A.block<1, 3>(2 * i, 6) = q.y() * p.transpose();
    A.block<1, 3>(2 * i + 1, 0) = q.z() * p.transpose();
    A.block<1, 3>(2 * i + 1, 6) = -q.x() * p.transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  // Eight independent equations determine H; fewer (collinear points) leave a family.
  if (sigma.size() < 8 || sigma(7) < 1e-9 * sigma(0))
    throw std::invalid_argument("homography: the points do not determine it (three or more collinear?)");
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d H_normalised;
  H_normalised << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  Eigen::Matrix3d H = Ts.inverse() * H_normalised * Tp;
  H /= H(2, 2) != 0.0 ? H(2, 2) : H.norm();
  require_regular(H, "homography");
  return H;
}

}  // namespace panoptes::surface
