// SPDX-License-Identifier: Apache-2.0
// What panoptes_label does (docs/marker_sets.md), apart from its command line: `model` reads a
// marker set and a static trial, builds the subject model, writes it and reports on it.
#pragma once

#include <string>

#include "panoptes/labelling/subject_model.h"

namespace panoptes::label_job {

struct ModelCommandOptions {
  std::string static_trial;  // .trc or .c3d
  std::string marker_set;    // YAML
  std::string out;           // subject model YAML
  std::string subject;       // empty: the static file's stem
  double sigmas = 3.0;
  double min_tolerance_mm = 2.0;
  double still_mm = 20.0;
};

// The subject's name: `options.subject`, or the static file's stem.
std::string subject_name(const ModelCommandOptions& options);

// Reads, builds and writes. Throws ConfigError/InputError naming the file and entry on bad input.
labelling::SubjectModel run_model(const ModelCommandOptions& options);

// The human-readable report: per segment its markers, fit RMS and pose, then every flag and the
// ignored points of the trial.
std::string model_report(const labelling::SubjectModel& model);

// The one JSON line at the end of the report.
std::string model_summary_line(const labelling::SubjectModel& model);

}  // namespace panoptes::label_job
