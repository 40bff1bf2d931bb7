// SPDX-License-Identifier: Apache-2.0
// What panoptes_export does (docs/recording.md, "Export"), apart from its command line: the
// estimator's tracks and body poses (JSON Lines, or the MocapFrames of an MCAP recording as they
// were published) re-sampled to a fixed rate, or a marker file (TRC, C3D) converted, and written as
// C3D, TRC and CSV; a recording's records also as the estimator's JSON Lines.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include "panoptes/up_axis.h"

namespace panoptes::export_job {

struct ExportOptions {
  std::string tracks;        // tracks JSON Lines file (estimator_node --out-tracks)
  std::string poses;         // body poses JSON Lines file (estimator_node --out-poses)
  std::string markers;       // a TRC or C3D file to convert instead of records
  std::string in_recording;  // an MCAP recording (panoptes_record): its MocapFrames as published
  std::string c3d;
  std::string trc;
  std::string csv;
  std::string bodies_csv;
  std::string out_tracks;  // JSON Lines of the recording's track records (as --out-tracks)
  std::string out_poses;   // JSON Lines of the recording's pose records (as --out-poses)
  std::string units = "mm";
  double rate_hz = 100.0;
  double max_gap_ms = 100.0;
  bool include_tentative = false;
  bool no_body_points = false;
  // The world's up axis of every written position and orientation (--up-axis; docs/recording.md,
  // "Axis conventions"): z as recorded, or y ((x, y, z) -> (x, z, -y)). Not the JSON Lines records.
  UpAxis up_axis = UpAxis::kZ;
  // Resampling rate given (--rate): a recording of fixed-rate frames is otherwise exported at its
  // own rate.
  bool rate_given = false;
};

// Sets the output named by `path` by its extension (any case): .c3d, .trc, .csv (markers), and for
// `poses` .jsonl (pose records) or .csv (bodies CSV). Returns false for another extension.
bool set_output(ExportOptions& options, const std::string& path);
bool set_poses_output(ExportOptions& options, const std::string& path);

// A combination of options that cannot be exported: `option` names it (as the command line's
// check reports it), `reason` says why.
struct OptionsProblem {
  std::string option;
  std::string reason;
};

// The first problem with the combination of inputs and outputs, or nullopt when it can run.
std::optional<OptionsProblem> find_problem(const ExportOptions& options);

enum class MarkerFileFormat { kC3d, kTrc };

// The format of a marker file to convert, by its extension (any case): ".c3d" is C3D, anything
// else is read as TRC (whose reader names the file when it is not one).
MarkerFileFormat marker_file_format(const std::string& path);

struct ExportSummary {
  std::size_t frames = 0;
  std::size_t markers = 0;
  std::size_t bodies = 0;
  double rate_hz = 0.0;
  std::size_t skipped_records = 0;
  double seconds = 0.0;              // wall time of the export
  std::size_t recorded_frames = 0;   // MocapFrames read from a recording (0: not a recording)
  std::size_t labelled_markers = 0;  // marker points named after a body marker
};

// Reads, re-samples and writes what `options` asks for. Each malformed record is reported on
// stderr ("skipped <reason>") and counted. Throws ConfigError (naming the file) when there is
// nothing to export, and the readers' and writers' errors.
ExportSummary run_export(const ExportOptions& options);

// The one JSON line panoptes_export prints on success.
std::string summary_line(const ExportSummary& summary);

}  // namespace panoptes::export_job
