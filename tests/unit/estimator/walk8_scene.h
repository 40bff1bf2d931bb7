// SPDX-License-Identifier: Apache-2.0
// The walk8 scene (deploy/scenes/walk8.yaml: a person walking, eight cameras, clutter, merging,
// self-occlusion) with another length and seed, for the estimator tests.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "panoptes/simulator.h"

namespace panoptes::estimator {

// `extra`: YAML appended to the scene (e.g. a `landmarks:` list).
inline Scene walk8_scene(double duration_s, int seed, const std::string& extra = {}) {
  const std::string dir = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes";
  std::ifstream in(dir + "/walk8.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = yaml.find(from);
    if (at == std::string::npos) throw std::runtime_error("walk8.yaml: no '" + from + "'");
    yaml.replace(at, from.size(), to);
  };
  replace("seed: 8\n", "seed: " + std::to_string(seed) + "\n");
  replace("duration: 20.0\n", "duration: " + std::to_string(duration_s) + "\n");
  return Scene::from_yaml_string(yaml + extra, dir, "walk8.yaml");
}

}  // namespace panoptes::estimator
