// SPDX-License-Identifier: Apache-2.0
// The `surface:` section of the estimator settings (docs/surface.md, "Set up a wall"): the
// surface's extent, a plane in the world and/or a 3 × 3 homography per camera, and the stroke
// tracker's options. Reading and checking it is the node's job; the maths stays in
// panoptes_surface. Errors are ConfigError naming the file and the dotted key.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/surface/surface_tracker.h"

namespace panoptes {
class YamlReader;
}

namespace panoptes::surface_app {

struct SurfaceCameraSetting {
  std::string id;
  std::optional<Eigen::Matrix3d> homography;  // pixels -> surface metres; absent: the plane
  std::string key;                            // its dotted key, for errors ("surface.cameras[1]")
};

struct SurfaceSettings {
  std::string file;  // where the section was read from
  surface::SurfacePlane plane;
  bool has_plane = false;                     // `plane:` given (cameras without a homography need it)
  std::vector<SurfaceCameraSetting> cameras;  // empty with a plane: every calibrated camera
  surface::SurfaceTrackerOptions tracker;
  double latency_window_ms = 10.0;  // live: frames wait this long to be put in stamp order
};

// The `surface:` section of `path`, or nullopt when it has none. Throws ConfigError.
std::optional<SurfaceSettings> load_surface_settings(const std::filesystem::path& path);
// The section itself (`reader` is the `surface` map). Throws ConfigError.
SurfaceSettings read_surface_settings(const YamlReader& reader);

// The tracker and the camera ids of its indices, ready to run.
struct SurfaceSetup {
  std::vector<std::string> camera_ids;  // index i: camera_ids[i]
  std::unique_ptr<surface::SurfaceTracker> tracker;
  int camera_index(const std::string& id) const;  // -1: not on the surface
};

// Builds the mappings: a homography as given, otherwise the plane seen by the camera's calibration
// (from `calibration`, which may be null when every camera has a homography). Throws ConfigError
// naming the settings file and key (and the calibration file) for a degenerate homography, a
// plane behind or edge-on to a camera, or a camera without calibration.
SurfaceSetup build_surface(const SurfaceSettings& settings, const SystemCalibration* calibration,
                           const std::string& calibration_file);

}  // namespace panoptes::surface_app
