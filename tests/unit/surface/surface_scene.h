// SPDX-License-Identifier: Apache-2.0
// Test support: a wall seen by cameras in front of it (pinhole, f in pixels), for the surface
// tracker's tests. The wall is the plane y = 0, surface u along world x, v along world z.
#pragma once

#include <Eigen/Geometry>

#include "panoptes/camera_model.h"
#include "panoptes/surface/image_to_surface.h"

namespace panoptes::surface::testing {

inline SurfacePlane wall(double width_m, double height_m) {
  SurfacePlane plane;
  plane.origin = Eigen::Vector3d::Zero();
  plane.u_axis = Eigen::Vector3d::UnitX();
  plane.v_axis = Eigen::Vector3d::UnitZ();
  plane.size = Eigen::Vector2d(width_m, height_m);
  return plane;
}

// A 1280 × 1024 camera at `eye` (in front of the wall, y < 0) looking at `target` on the wall.
inline CameraModel camera_facing(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double f_px,
                                 double k1 = 0.0) {
  CameraIntrinsics K;
  K.width = 1280;
  K.height = 1024;
  K.fx = K.fy = f_px;
  K.cx = 639.5;
  K.cy = 511.5;
  K.distortion[0] = k1;
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();  // image right (horizontal)
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R_world_cam;
  R_world_cam << x, y, z;
  RigidTransform T_world_cam;
  T_world_cam.q = Eigen::Quaterniond(R_world_cam);
  T_world_cam.t = eye;
  return CameraModel(K, T_world_cam);
}

}  // namespace panoptes::surface::testing
