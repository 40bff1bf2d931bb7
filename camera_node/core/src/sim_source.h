// SPDX-License-Identifier: Apache-2.0
// "sim:<scene.yaml>#<camera id>" frame source (private to panoptes_camera).
#pragma once

#include <memory>
#include <string>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

// `target` is the part after "sim:". Throws std::runtime_error (ConfigError for scene files).
std::unique_ptr<FrameSource> open_sim_source(const std::string& target, const SourceOptions& options);

}  // namespace panoptes::camera
