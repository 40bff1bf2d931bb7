// SPDX-License-Identifier: Apache-2.0
// camera::CameraStatusReport → rt/panoptes/camera_status message.
#pragma once

#include "panoptes/camera/camera_status.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::camera_app {

msg::CameraStatus to_message(const camera::CameraStatusReport& report);

}  // namespace panoptes::camera_app
