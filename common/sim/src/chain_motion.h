// SPDX-License-Identifier: Apache-2.0
// Articulated chains in scenes (docs/simulator.md, `chains:`; docs/articulated.md): a finger whose
// base follows a path and rotation like a body and whose joints bend open ↔ closed in scripted
// grab/release cycles; its markers follow the chain's forward kinematics (chain_definition.h).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "motion.h"
#include "panoptes/chain_definition.h"
#include "panoptes/config.h"
#include "panoptes/geometry.h"

namespace panoptes::sim {

// Joint angles over time: `start` s open, then cycles of a raised-cosine transition to closed
// (`transition` s), a hold closed, a transition back, a hold open; holds cycle through the lists.
struct BendScript {
  std::vector<double> open_rad;
  std::vector<double> closed_rad;
  double start_s = 0.5;
  double transition_s = 0.6;
  std::vector<double> hold_closed_s{0.8};
  std::vector<double> hold_open_s{0.8};

  std::vector<double> angles_at(double t_s) const;
};

struct ChainSpec {
  ChainDefinition definition;
  double marker_radius = 0.005;
  Path path;          // marker 0 (the base)
  Rotation rotation;  // the base frame: x towards marker 1, joints bend about z
  BendScript bend;
};

struct ChainSample {
  RigidTransform T_world_base;
  std::vector<double> angles;
  std::vector<Eigen::Vector3d> markers;  // world, base first
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
};

// Throws ConfigError naming the entry's key.
ChainSpec read_chain_spec(const YamlReader& reader, double default_marker_radius);
ChainSample sample_chain(const ChainSpec& chain, double t_s);

}  // namespace panoptes::sim
