// SPDX-License-Identifier: Apache-2.0
// TRC marker files (OpenSim, Motion Analysis): the one reader and writer of the project.
#pragma once

#include <filesystem>

#include "panoptes/formats/marker_trajectories.h"

namespace panoptes {

// Positions converted to metres from the file's Units. Throws ConfigError naming the file and the
// line ("line 7") on any problem.
MarkerTrajectories load_trc(const std::filesystem::path& path);

// Writes `data` in data.units ("mm" if empty), six decimals, an empty field where a marker is
// invalid. Frame numbers start at 1. Throws ConfigError naming the file if it cannot be written.
void write_trc(const std::filesystem::path& path, const MarkerTrajectories& data);

}  // namespace panoptes
