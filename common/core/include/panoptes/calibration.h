// SPDX-License-Identifier: Apache-2.0
// Camera calibrations and rigid-body definitions (the files: panoptes/calibration_file.h).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"

namespace panoptes {

struct CameraCalibration {
  std::string id;
  CameraIntrinsics intrinsics;
  std::optional<RigidTransform> T_world_cam;  // absent: intrinsics only
  // YAML `nominal: true`: the intrinsics are a guess (focal length / pixel pitch, image centre,
  // no distortion), not a chessboard calibration; `calibrate solve` then refines them.
  bool nominal_intrinsics = false;
  // YAML `moving: true`: the camera moves with the user (inside-out tracking, docs/inside_out.md).
  // Its T_world_cam is then its mount on the rig it is carried by (T_rig_cam; absent: identity),
  // and the estimator tracks the rig's pose from the landmarks the camera sees. `rig` names that
  // pose (YAML `rig:`; empty: the camera id).
  bool moving = false;
  std::string rig;

  // Requires T_world_cam.
  CameraModel model() const;
};

struct SystemCalibration {
  std::vector<CameraCalibration> cameras;
  const CameraCalibration* find(std::string_view camera_id) const;
};

// How a body is found: passive markers are identified from triangulated 3D points; a 7-LED marker
// (seed 004, docs/monocular_markers.md) also from the blobs of a single camera. YAML key `type`:
// `passive` (default) or `led7`.
enum class BodyKind { kPassive, kLed7 };

struct BodyDefinition {
  std::string name;
  std::vector<Eigen::Vector3d> markers;  // metres, body frame
  BodyKind kind = BodyKind::kPassive;
};

}  // namespace panoptes
