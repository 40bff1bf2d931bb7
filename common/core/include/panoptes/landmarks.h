// SPDX-License-Identifier: Apache-2.0
// Landmarks for inside-out tracking (docs/inside_out.md): markers fixed in the room whose world
// positions are known (surveyed, or measured by the outside-in system). The file format is
// panoptes/landmarks_file.h (panoptes_io).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace panoptes {

struct LandmarkGroup {
  std::string name;
  std::vector<Eigen::Vector3d> points;  // world frame, m
  bool constellation = true;            // false: a single fixed marker (`position`)
};

}  // namespace panoptes
