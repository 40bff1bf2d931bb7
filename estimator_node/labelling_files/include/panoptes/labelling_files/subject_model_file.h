// SPDX-License-Identifier: Apache-2.0
// The subject model YAML file (docs/marker_sets.md, "File formats"), in metres.
#pragma once

#include <filesystem>
#include <string>

#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

std::string subject_model_to_yaml(const SubjectModel& model);

// Throws ConfigError naming the file if it cannot be written.
void save_subject_model(const SubjectModel& model, const std::filesystem::path& path);

// Throws ConfigError "<file>: <key>: <reason>" for a missing file, bad YAML, an unknown key, a
// format version other than 1 or a value of the wrong type.
SubjectModel load_subject_model(const std::filesystem::path& path);

}  // namespace panoptes::labelling
