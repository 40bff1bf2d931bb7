// SPDX-License-Identifier: Apache-2.0
// Single-point observations recorded by other self-calibration tools, imported as FeatureFrames so
// that `calibrate solve --wand 0` calibrates from them (docs/calibration.md, "Importing a
// single-point recording").
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/records.h"

namespace panoptes::calib {

// One bright point seen by synchronised cameras: per camera, per frame, its pixel or nothing.
struct PointTable {
  std::vector<std::vector<std::optional<Eigen::Vector2d>>> cameras;  // [camera][frame]
  int frames = 0;
};

// MultiCamSelfCal's `points.dat`: whitespace-separated numbers, 3 rows per camera (x, y, 1; NaN
// where the camera did not see the point), one column per synchronised frame. Throws
// std::runtime_error naming the file and the row that is malformed.
PointTable read_multicam_points(const std::filesystem::path& path);

// MultiCamSelfCal's `Res.dat`: one row per camera, "width height". Throws std::runtime_error naming
// the file and row.
std::vector<std::pair<int, int>> read_multicam_resolutions(const std::filesystem::path& path);

// One FeatureFrame per camera and frame (one blob where the point was seen, none where not),
// camera ids from `ids`, stamps on one grid at `rate_hz` from `start_ns`: synchronised cameras,
// which `calibrate solve` uses frame by frame without interpolating.
std::vector<FeatureFrame> point_feature_frames(const PointTable& table, const std::vector<std::string>& ids,
                                               double rate_hz, TimeNs start_ns);

// Nominal intrinsics (marked `nominal: true`): fx = fy = `focal_px`, principal point at the image
// centre, no distortion, no pose.
CameraCalibration nominal_camera(const std::string& id, int width, int height, double focal_px);

}  // namespace panoptes::calib
