// SPDX-License-Identifier: Apache-2.0
// Calibration and body-definition files (architecture.md, "Contracts").
#pragma once

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"

namespace panoptes {

class YamlReader;

struct CameraCalibration {
  std::string id;
  CameraIntrinsics intrinsics;
  std::optional<RigidTransform> T_world_cam;  // absent: intrinsics only

  // Requires T_world_cam.
  CameraModel model() const;
};

struct SystemCalibration {
  std::vector<CameraCalibration> cameras;
  const CameraCalibration* find(std::string_view camera_id) const;
};

// Throws ConfigError naming the file and key on any problem.
SystemCalibration load_calibration(const std::filesystem::path& path);
void save_calibration(const SystemCalibration& calibration, const std::filesystem::path& path);
std::string calibration_to_yaml(const SystemCalibration& calibration);

// How a body is found: passive markers are identified from triangulated 3D points; a 7-LED marker
// (seed 004, docs/monocular_markers.md) also from the blobs of a single camera. YAML key `type`:
// `passive` (default) or `led7`.
enum class BodyKind { kPassive, kLed7 };

struct BodyDefinition {
  std::string name;
  std::vector<Eigen::Vector3d> markers;  // metres, body frame
  BodyKind kind = BodyKind::kPassive;
};

std::vector<BodyDefinition> load_bodies(const std::filesystem::path& path);
// Reads one body (`name`, `markers`) from a YAML map; `names` collects names to reject duplicates.
// Used by body files and simulator scenes alike. Throws ConfigError naming the file and key.
BodyDefinition read_body_definition(const YamlReader& item, std::set<std::string>& names);
void save_bodies(const std::vector<BodyDefinition>& bodies, const std::filesystem::path& path);

}  // namespace panoptes
