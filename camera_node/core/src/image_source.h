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

// Loads one PGM/PNM/PNG file as a grey Image; 16-bit PGMs take their bit depth from maxval.
// Throws std::runtime_error naming the file.
Image load_grey_image(const std::filesystem::path& path);

}  // namespace panoptes::camera
