// SPDX-License-Identifier: Apache-2.0
// Landmarks for inside-out tracking (docs/inside_out.md): markers fixed in the room whose world
// positions are known (surveyed, or measured by the outside-in system). A `landmarks:` list, in a
// file of its own or as a section of a simulator scene (the same schema, so a scene is its own
// landmarks file). Each entry has a unique `name` and either `markers` (a rigid constellation, at
// least three markers, world frame, m) or `position` (one fixed marker).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "panoptes/landmarks.h"

namespace panoptes {

class YamlReader;

// The `landmarks` list of the map `root`. Throws ConfigError naming the file and entry (duplicate
// names, a constellation of fewer than three markers, non-finite numbers, an empty list).
std::vector<LandmarkGroup> read_landmarks(const YamlReader& root);
// Throws ConfigError naming the file when it is missing, unreadable or has no `landmarks`.
std::vector<LandmarkGroup> load_landmarks(const std::filesystem::path& path);
// Markers carried by the rigs of moving cameras, rig frame, by rig name: the optional
// `rig_markers: {<rig>: [[x, y, z], ...]}` map of the same file. Fixed cameras that see them
// update the rig's pose too (fusion, docs/inside_out.md). Throws ConfigError naming the file and key.
using RigMarkers = std::map<std::string, std::vector<Eigen::Vector3d>>;
RigMarkers load_rig_markers(const std::filesystem::path& path);

void save_landmarks(const std::vector<LandmarkGroup>& landmarks, const std::filesystem::path& path,
                    const RigMarkers& rig_markers = {});

}  // namespace panoptes
