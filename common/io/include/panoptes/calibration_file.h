// SPDX-License-Identifier: Apache-2.0
// Calibration and body-definition files (docs/contracts.md).
#pragma once

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/chain_definition.h"

namespace panoptes {

class YamlReader;

// Throws ConfigError naming the file and key on any problem.
SystemCalibration load_calibration(const std::filesystem::path& path);
void save_calibration(const SystemCalibration& calibration, const std::filesystem::path& path);
std::string calibration_to_yaml(const SystemCalibration& calibration);

std::vector<BodyDefinition> load_bodies(const std::filesystem::path& path);
// Reads one body (`name`, `markers`) from a YAML map; `names` collects names to reject duplicates.
// Used by body files and simulator scenes alike. Throws ConfigError naming the file and key.
BodyDefinition read_body_definition(const YamlReader& item, std::set<std::string>& names);
// The `type: chain` entries of a bodies file (articulated chains, docs/articulated.md); load_bodies
// skips them. Throws ConfigError naming the file and entry for impossible links or limits.
std::vector<ChainDefinition> load_chains(const std::filesystem::path& path);
ChainDefinition read_chain_definition(const YamlReader& item, std::set<std::string>& names);
// A chain's own fields (`name`, `links`, `joint_limits`, `base`, `tip_offset`), validated
// (chain_definition_error); the caller checks which keys its entry may have. Used by bodies files
// and simulator scenes alike. Throws ConfigError naming the file and key.
ChainDefinition read_chain_fields(const YamlReader& item);
void save_bodies(const std::vector<BodyDefinition>& bodies, const std::filesystem::path& path);

}  // namespace panoptes
