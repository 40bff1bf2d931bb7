// SPDX-License-Identifier: Apache-2.0
// Writing an Image as a binary PGM (P5), the simplest file any viewer opens.
#pragma once

#include <filesystem>

#include "panoptes/image.h"

namespace panoptes {

// 8-bit images as bytes, deeper ones as big-endian 16-bit samples (as the format requires).
// Throws std::runtime_error naming the file if it cannot be written.
void write_pgm(const Image& image, const std::filesystem::path& path);

}  // namespace panoptes
