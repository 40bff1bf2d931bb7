// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate surface` (docs/surface.md, "Calibrate the homographies"): per camera, a
// homography from pixels to the surface fitted to known pixel <-> surface points (four clicked
// corners of the wall, or the points of a pattern shown on the display), written as a `surface:`
// settings file that estimator_node --surface runs.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace panoptes::surface_app {

struct SurfaceCorrespondences {
  std::string camera_id;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<Eigen::Vector2d> surface;  // m
  std::string key;                       // dotted key in the points file, for errors
};

// Reads the points file: `size: [W, H]` and `cameras: [{id, points: [{surface: [s, t], pixel: [x, y]}, ...]
// | corners: [[x, y] x 4]}]` (corners: the pixels of (0, 0), (W, 0), (W, H), (0, H)). Throws ConfigError.
std::vector<SurfaceCorrespondences> load_surface_points(const std::string& path, Eigen::Vector2d& size);

// The subcommand; argv[0] is "surface". Returns the exit code.
int run_calibrate_surface(int argc, char** argv);

}  // namespace panoptes::surface_app
