// SPDX-License-Identifier: Apache-2.0
// Stage 2 of the wand solver: the pairwise relative poses (two_view.h) unified into one frame,
// ranked by residual (seed 003 §3.3.1, eq. 3.4-3.5). The largest connected component of the view
// graph is placed from the reference camera outwards, best-ranked pair first; the cameras of the
// other components are reported. docs/calibration.md, "Stages".
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/calib/two_view.h"
#include "panoptes/calibration.h"

namespace panoptes::calib {

struct ViewGraphInput {
  std::vector<std::string> camera_ids;
  std::vector<bool> usable;      // per camera: false for cameras already failed
  std::vector<PairPose> pairs;   // from pairwise_relative_poses
  bool metric = true;            // the pairs' baselines are metric (a wand of two or more markers)
  std::string reference_camera;  // "" = the best-connected camera of the largest component
  int min_pair_samples = 25;     // named in the failure of a camera with no pair at all
};

struct ViewGraphResult {
  int reference = -1;  // camera index at the world origin; -1: no usable camera
  std::vector<std::optional<RigidTransform>> T_world_cam;  // per camera; absent: not placed
  std::vector<std::string> failures;                       // per camera: why it was not placed, or ""
  std::vector<std::size_t> used_edges;                     // edge_index of every pair that placed a camera
  int placed = 0;                                          // cameras placed, the reference included
};

ViewGraphResult unify_view_graph(const ViewGraphInput& input);

}  // namespace panoptes::calib
