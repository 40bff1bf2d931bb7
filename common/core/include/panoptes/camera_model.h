// SPDX-License-Identifier: Apache-2.0
// Pinhole camera with OpenCV's (k1, k2, p1, p2, k3) distortion. Pixel (0,0) is the centre of the
// top-left pixel; camera frame x right, y down, z forward (architecture.md, "Frames and units").
#pragma once

#include <array>
#include <optional>

#include <Eigen/Core>

#include "panoptes/geometry.h"

namespace panoptes {

struct CameraIntrinsics {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::array<double, 5> distortion{};  // k1, k2, p1, p2, k3
};

class CameraModel {
 public:
  CameraModel() = default;
  CameraModel(const CameraIntrinsics& intrinsics, const RigidTransform& T_world_cam);

  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const RigidTransform& T_world_cam() const { return T_world_cam_; }
  const RigidTransform& T_cam_world() const { return T_cam_world_; }
  Eigen::Vector3d center_world() const { return T_world_cam_.t; }

  // Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates, with the
  // 2x2 Jacobian if requested.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn, Eigen::Matrix2d* J = nullptr) const;
  // Inverse of distort() by Gauss-Newton iterations (converges where the model is monotonic).
  Eigen::Vector2d undistort(const Eigen::Vector2d& xd) const;

  // Camera-frame point -> pixel. nullopt if the point is not in front of the camera.
  // J_cam is d(pixel)/d(p_cam), 2x3.
  std::optional<Eigen::Vector2d> project_camera_point(const Eigen::Vector3d& p_cam,
                                                      Eigen::Matrix<double, 2, 3>* J_cam = nullptr) const;
  // World point -> pixel; J_world is d(pixel)/d(p_world), 2x3.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_world,
                                         Eigen::Matrix<double, 2, 3>* J_world = nullptr) const;

  // Pixel -> undistorted normalised coordinates (x/z, y/z) in the camera frame.
  Eigen::Vector2d pixel_to_normalized(const Eigen::Vector2d& pixel) const;
  // Pixel -> unit ray direction in the world frame.
  Eigen::Vector3d pixel_to_world_ray(const Eigen::Vector2d& pixel) const;

  bool in_image(const Eigen::Vector2d& pixel, double margin = 0.0) const;

 private:
  CameraIntrinsics intrinsics_;
  RigidTransform T_world_cam_;
  RigidTransform T_cam_world_;
  Eigen::Matrix3d R_cam_world_ = Eigen::Matrix3d::Identity();
};

}  // namespace panoptes
