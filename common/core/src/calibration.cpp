// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calibration.h"

#include <stdexcept>

namespace panoptes {

CameraModel CameraCalibration::model() const {
  if (!T_world_cam) throw std::logic_error("camera '" + id + "' has no T_world_cam (intrinsics only)");
  return CameraModel(intrinsics, *T_world_cam);
}

const CameraCalibration* SystemCalibration::find(std::string_view camera_id) const {
  for (const auto& camera : cameras) {
    if (camera.id == camera_id) return &camera;
  }
  return nullptr;
}

}  // namespace panoptes
