// SPDX-License-Identifier: Apache-2.0
// "images:<dir or glob>" frame source (private to panoptes_camera).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

// `pattern` is the part after "images:". Throws std::runtime_error naming the spec or file.
std::unique_ptr<FrameSource> open_image_source(const std::string& pattern, const SourceOptions& options);

}  // namespace panoptes::camera
