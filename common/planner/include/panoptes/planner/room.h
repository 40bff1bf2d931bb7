// SPDX-License-Identifier: Apache-2.0
// What a camera placement plan is made of (docs/planner.md): the working volume where markers
// move, the surfaces cameras may be mounted on, static obstacles, and the lenses to choose from.
// Types and geometry only; the room file is read by panoptes_plan (tools/plan).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"

namespace panoptes::planner {

// An axis-aligned box, metres, world frame.
struct Box {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();

  bool contains(const Eigen::Vector3d& p) const;
  double volume() const;
  // True when the open segment a→b passes through the box (slab test).
  bool blocks(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
};

// A part of the working volume with its own weight: how likely a marker is there, relative to the
// other regions (seed 003 §4.3.6, non-uniform spatial sampling).
struct Region {
  Box box;
  double weight = 1.0;
};

// Where cameras may be mounted: the parallelogram corner + s·edge_u + t·edge_v, s, t ∈ [0, 1]; a
// line (a truss) when edge_v is zero.
struct MountSurface {
  std::string name;
  Eigen::Vector3d corner = Eigen::Vector3d::Zero();
  Eigen::Vector3d edge_u = Eigen::Vector3d::Zero();
  Eigen::Vector3d edge_v = Eigen::Vector3d::Zero();

  Eigen::Vector3d at(double s, double t) const { return corner + s * edge_u + t * edge_v; }
};

// A camera model a plan may use: image size, focal length in pixels, usable depth range.
struct Lens {
  std::string name;
  CameraIntrinsics intrinsics;
  double min_depth_m = 0.3;
  double max_depth_m = 12.0;
};

struct Room {
  Box volume;                        // where markers move
  std::vector<Region> regions;       // empty: uniform over `volume`
  std::vector<Box> obstacles;        // pillars, furniture: block lines of sight
  std::vector<MountSurface> mounts;  // walls, ceiling, trusses
  std::vector<Lens> lenses;          // at least one; a plan picks one per camera
};

// A camera of a plan: its model and the depth range in which it sees markers.
struct PlannedCamera {
  std::string id;
  CameraModel model;
  std::string lens;
  double min_depth_m = 0.3;
  double max_depth_m = 12.0;
};

PlannedCamera make_camera(std::string id, const Lens& lens, const Eigen::Vector3d& position,
                          const Eigen::Vector3d& aim);

}  // namespace panoptes::planner
