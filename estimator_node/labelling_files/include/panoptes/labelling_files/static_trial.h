// SPDX-License-Identifier: Apache-2.0
// A static (or any) trial's named marker samples from a TRC or C3D file, read by the project's
// readers in panoptes_mocap_formats.
#pragma once

#include <filesystem>

#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

// ".c3d" (any case) is read as C3D, anything else as TRC. Positions in metres. Throws the
// readers' ConfigError naming the file.
MarkerSamples load_marker_samples(const std::filesystem::path& path);

}  // namespace panoptes::labelling
