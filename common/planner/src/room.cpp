// SPDX-License-Identifier: Apache-2.0
#include "panoptes/planner/room.h"

#include <algorithm>
#include <utility>

#include "panoptes/geometry.h"

namespace panoptes::planner {

bool Box::contains(const Eigen::Vector3d& p) const {
  return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
}

double Box::volume() const {
  return (max - min).cwiseMax(0.0).prod();
}

bool Box::blocks(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  // Parametric segment a + s (b - a), s in (0, 1): clip against the three slabs.
  double enter = 0.0, leave = 1.0;
  const Eigen::Vector3d d = b - a;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(d[axis]) < 1e-15) {
      if (a[axis] < min[axis] || a[axis] > max[axis]) return false;
      continue;
    }
    double s0 = (min[axis] - a[axis]) / d[axis];
    double s1 = (max[axis] - a[axis]) / d[axis];
    if (s0 > s1) std::swap(s0, s1);
    enter = std::max(enter, s0);
    leave = std::min(leave, s1);
    if (enter > leave) return false;
  }
  // Touching at an end point (a marker on the obstacle's surface, a camera on a wall) is not
  // blocking: the segment must run through the box's inside.
  return leave - enter > 1e-9 && enter < 1.0 - 1e-9 && leave > 1e-9;
}

PlannedCamera make_camera(std::string id, const Lens& lens, const Eigen::Vector3d& position,
                          const Eigen::Vector3d& aim) {
  PlannedCamera camera;
  camera.id = std::move(id);
  camera.model = CameraModel(lens.intrinsics, look_at(position, aim));
  camera.lens = lens.name;
  camera.min_depth_m = lens.min_depth_m;
  camera.max_depth_m = lens.max_depth_m;
  return camera;
}

}  // namespace panoptes::planner
