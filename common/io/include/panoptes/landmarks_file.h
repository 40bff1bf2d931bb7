// SPDX-License-Identifier: Apache-2.0
// Landmarks for inside-out tracking (docs/inside_out.md): markers fixed in the room whose world
// positions are known (surveyed, or measured by the outside-in system). A `landmarks:` list, in a
// file of its own or as a section of a simulator scene (the same schema, so a scene is its own
// landmarks file). Each entry has a unique `name` and either `markers` (a rigid constellation, at
// least three markers, world frame, m) or `position` (one fixed marker).
#pragma once

#include <filesystem>
#include <vector>

#include "panoptes/landmarks.h"

namespace panoptes {

class YamlReader;

// The `landmarks` list of the map `root`. Throws ConfigError naming the file and entry (duplicate
// names, a constellation of fewer than three markers, non-finite numbers, an empty list).
std::vector<LandmarkGroup> read_landmarks(const YamlReader& root);
// Throws ConfigError naming the file when it is missing, unreadable or has no `landmarks`.
std::vector<LandmarkGroup> load_landmarks(const std::filesystem::path& path);
void save_landmarks(const std::vector<LandmarkGroup>& landmarks, const std::filesystem::path& path);

}  // namespace panoptes
