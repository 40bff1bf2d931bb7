// SPDX-License-Identifier: Apache-2.0
// What panoptes_label does (docs/marker_sets.md), apart from its command line: `model` reads a
// marker set and a static trial, builds the subject model, writes it and reports on it; `run`
// labels a trial's tracks offline, fills gaps and writes the labelled trajectories.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/formats/marker_trajectories.h"
#include "panoptes/labelling/gap_fill.h"
#include "panoptes/labelling/offline_labelling.h"
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

struct RunCommandOptions {
  std::string tracks;                 // .c3d, .trc, or the estimator's track JSON Lines (--out-tracks)
  std::string in_recording;           // or an MCAP recording: the tracks as published live
  std::vector<std::string> subjects;  // subject model YAML files (panoptes_label model)
  std::string out;                    // .c3d, .trc or .csv
  std::string report;                 // optional JSON report
  double max_gap_s = 0.3;             // longer gaps stay open
  std::string fill = "pattern";       // pattern, relational, spline, linear, none
  double rate_hz = 100.0;             // the grid track JSON Lines are resampled to
  std::vector<std::string> soft_segments{"Torso"};
};

// A bad --fill or --max-gap-s, an output that is not .c3d/.trc/.csv (naming the option), or nullopt.
std::optional<std::string> find_problem(const RunCommandOptions& options);

// The run's input: --tracks or --in-recording.
const std::string& input_of(const RunCommandOptions& options);

// "pattern", "relational", "spline", "linear" or "none" as a fill method; nullopt otherwise.
std::optional<labelling::FillMethod> parse_fill_method(const std::string& name);

struct SubjectFill {
  std::string subject;
  labelling::FillReport fill;
  std::size_t marker_frames = 0;  // the subject's labelled marker-frames before filling
};

struct RunSummary {
  std::string input_format;  // "c3d", "trc", "tracks"
  std::size_t tracks = 0;    // input columns (track ids)
  labelling::OfflineLabelling labelling;
  std::vector<SubjectFill> subjects;
  MarkerTrajectories output;  // as written
  std::size_t skipped_records = 0;
};

// Reads the tracks and the models, labels (forward and backward), fills gaps, writes --out (and
// --report). Throws ConfigError/InputError naming the file on bad input.
RunSummary run_labelling(const RunCommandOptions& options);

// The report: a human-readable text and its JSON (written to --report, and as the last line).
std::string run_report(const RunCommandOptions& options, const RunSummary& summary);
std::string run_report_json(const RunCommandOptions& options, const RunSummary& summary);

}  // namespace panoptes::label_job
