// SPDX-License-Identifier: Apache-2.0
// What panoptes_label does (docs/marker_sets.md), apart from its command line: `model` reads a
// marker set and a static trial, builds the subject model, writes it and reports on it.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>

#include "panoptes/labelling/subject_model.h"

namespace panoptes::label_job {

struct ModelCommandOptions {
  std::string static_trial;  // .trc or .c3d
  std::string labelled;      // or an already-labelled dynamic trial (.trc or .c3d)
  std::string frames;        // "FIRST:LAST" (0-based, LAST excluded; either may be empty): part of the trial
  std::string marker_set;    // YAML
  std::string out;           // subject model YAML
  std::string subject;       // empty: the trial file's stem
  double sigmas = 3.0;
  double min_tolerance_mm = 2.0;
  double still_mm = 20.0;
};

// What is wrong with the combination of options (exactly one of --static and --labelled; --frames
// as FIRST:LAST with FIRST < LAST), or nullopt.
std::optional<std::string> find_problem(const ModelCommandOptions& options);

// The frames [first, last) --frames selects; last is SIZE_MAX when open.
std::pair<std::size_t, std::size_t> frame_range(const std::string& frames);

// The trial file: --static or --labelled.
const std::string& trial_file(const ModelCommandOptions& options);

// The subject's name: `options.subject`, or the trial file's stem.
std::string subject_name(const ModelCommandOptions& options);

// Reads, builds and writes. Throws ConfigError/InputError naming the file and entry on bad input.
labelling::SubjectModel run_model(const ModelCommandOptions& options);

// The human-readable report: per segment its markers, fit RMS and pose, then every flag and the
// ignored points of the trial.
std::string model_report(const labelling::SubjectModel& model);

// The one JSON line at the end of the report.
std::string model_summary_line(const labelling::SubjectModel& model);

}  // namespace panoptes::label_job
