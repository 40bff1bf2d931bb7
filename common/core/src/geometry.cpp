// SPDX-License-Identifier: Apache-2.0
#include "panoptes/geometry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace panoptes {

RigidTransform look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward_unnormalised = target - eye;
  if (forward_unnormalised.norm() < 1e-12) {
    throw std::invalid_argument("look_at: eye and target coincide, the viewing direction is undefined");
  }
  const Eigen::Vector3d z_axis = forward_unnormalised.normalized();

  // OpenCV cameras have y pointing down, so x = z × up points to the image right.
  Eigen::Vector3d x_axis = z_axis.cross(up);
  if (x_axis.norm() < 1e-9 * std::max(1.0, up.norm())) {
    // Looking along `up` leaves the roll undefined; borrow the world axis least aligned with the
    // view so the result is still a valid rotation instead of NaN.
    Eigen::Index least_aligned = 0;
    z_axis.cwiseAbs().minCoeff(&least_aligned);
    x_axis = z_axis.cross(Eigen::Vector3d::Unit(least_aligned));
  }
  x_axis.normalize();
  const Eigen::Vector3d y_axis = z_axis.cross(x_axis);

  Eigen::Matrix3d R_world_cam;
  R_world_cam.col(0) = x_axis;
  R_world_cam.col(1) = y_axis;
  R_world_cam.col(2) = z_axis;

  RigidTransform T_world_cam;
  T_world_cam.q = Eigen::Quaterniond(R_world_cam).normalized();
  T_world_cam.t = eye;
  return T_world_cam;
}

}  // namespace panoptes
