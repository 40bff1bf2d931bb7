// SPDX-License-Identifier: Apache-2.0
// Rigid transforms named by their frames: T_a_b maps coordinates in frame b into frame a.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace panoptes {

struct RigidTransform {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // rotation R_a_b
  Eigen::Vector3d t = Eigen::Vector3d::Zero();            // origin of b expressed in a

  Eigen::Vector3d apply(const Eigen::Vector3d& p_b) const { return q * p_b + t; }
  Eigen::Matrix3d rotation() const { return q.toRotationMatrix(); }
  RigidTransform inverse() const {
    const Eigen::Quaterniond q_inv = q.conjugate();
    return {q_inv, -(q_inv * t)};
  }
  RigidTransform operator*(const RigidTransform& T_b_c) const { return {q * T_b_c.q, q * T_b_c.t + t}; }
};

// The cross-product matrix [v]×, with [v]× w = v × w.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// A rotation that makes a camera at `eye` look at `target`, with image "up" close to `up`.
// Returns T_world_cam in the OpenCV camera convention (x right, y down, z forward).
RigidTransform look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                       const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace panoptes
