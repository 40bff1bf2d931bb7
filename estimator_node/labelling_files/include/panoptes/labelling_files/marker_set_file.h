// SPDX-License-Identifier: Apache-2.0
// The marker set YAML file (docs/marker_sets.md, "File formats").
#pragma once

#include <filesystem>

#include "panoptes/labelling/marker_set.h"

namespace panoptes::labelling {

// Reads and validates a marker set. Throws ConfigError "<file>: <entry>: <reason>" for a missing
// file, bad YAML, an unknown key, or any problem find_marker_set_problem reports.
MarkerSet load_marker_set(const std::filesystem::path& path);

}  // namespace panoptes::labelling
