// SPDX-License-Identifier: Apache-2.0
// Versioned calibration (issue 36 item 5, docs/calibration.md "Versions"): every change to a
// calibration file (a camera corrected while tracking, a drift refinement, a new wand solve, a
// revert) becomes a numbered version stored beside the file, with its time, reason, the cameras
// it touched and the residuals before and after. The file itself is always the current version;
// any earlier one can be restored byte for byte.
//
// Layout: for `calibration.yaml`, the directory `calibration.yaml.history/` holds `v0001.yaml`,
// `v0002.yaml`, ... (the exact bytes of each version) and `history.jsonl` (one JSON object per
// version, in order). Version 1 is the file as it was when the history began ("initial"); a file
// edited by hand since the last version is stored as a version of its own ("edited outside the
// history") before the next change, so nothing is lost.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "panoptes/calibration.h"

namespace panoptes {

// What a new version changes and why (the caller's account; the time is taken when recorded).
struct CalibrationChange {
  std::string reason;                // e.g. "cam3 corrected after a bump", "revert to 2"
  std::vector<std::string> cameras;  // the cameras whose parameters changed (empty: all or none)
  double residual_before_px = std::numeric_limits<double>::quiet_NaN();  // NaN: not known
  double residual_after_px = std::numeric_limits<double>::quiet_NaN();
};

// A change with its reason, the cameras it touched and the residuals (NaN: not known).
CalibrationChange change_because(std::string reason, std::vector<std::string> cameras = {},
                                 double residual_before_px = std::numeric_limits<double>::quiet_NaN(),
                                 double residual_after_px = std::numeric_limits<double>::quiet_NaN());

enum class VersionState { kApplied, kAccepted, kReverted };
const char* to_string(VersionState state);

struct CalibrationVersion {
  int version = 0;
  std::int64_t time_ns = 0;  // wall clock, ns since the Unix epoch
  std::string time_utc;      // the same, ISO 8601 ("2026-11-28T16:58:03Z")
  CalibrationChange change;
  VersionState state = VersionState::kApplied;  // kReverted: a later revert went back past it
  std::string file;                             // its bytes, relative to the history directory
};

// A version as the JSON object of its history.jsonl line (version, time_ns, time_utc, reason,
// cameras, state, file relative to the history directory, residual_before_px and
// residual_after_px, null when not known): for readers that show versions (the console).
std::string version_json(const CalibrationVersion& version);

class CalibrationHistory {
 public:
  explicit CalibrationHistory(std::filesystem::path calibration_file);

  const std::filesystem::path& calibration_file() const { return file_; }
  std::filesystem::path directory() const;

  // Every version, oldest first; empty when no history was started. Throws ConfigError naming
  // history.jsonl and the line when it cannot be read.
  std::vector<CalibrationVersion> versions() const;

  // Writes `calibration` as the new current file (to a temporary file, then renamed over it) and
  // stores it as the next version. Starts the history with the current file as version 1 when
  // there is none, and stores a hand-edited current file first. Returns the new version.
  CalibrationVersion record(const SystemCalibration& calibration, const CalibrationChange& change);
  // The same for a calibration file's text as written by someone else (with comments, a header).
  CalibrationVersion record_text(const std::string& yaml, const CalibrationChange& change);

  // Restores version `version`'s exact bytes as the current file, recorded as a new version
  // ("revert to N", the cameras that differ); the versions after it are marked reverted. Throws
  // ConfigError naming the history for a version that does not exist.
  CalibrationVersion revert(int version);

  // Starts the history (the current file as version 1) if there is none; later writes of the file
  // by `calibrate solve|world` are then versions too (write_calibration_text).
  void start();

  // Marks `version` accepted (an operator reviewed an automatic change). Throws like revert.
  void accept(int version);

  // The exact bytes of a stored version.
  std::string bytes_of(int version) const;

 private:
  std::filesystem::path index() const;
  CalibrationVersion append(const std::string& bytes, const CalibrationChange& change);
  void begin_if_needed();
  void write_index(const std::vector<CalibrationVersion>& versions) const;

  std::filesystem::path file_;
};

// Writes `yaml` (a calibration file's text) to `path`: as a new version when `path` has a history
// (its `.history/` directory exists; `change.cameras` filled from the difference when empty), else
// plainly. Throws ConfigError naming the file.
void write_calibration_text(const std::filesystem::path& path, const std::string& yaml,
                            CalibrationChange change);

// The cameras whose intrinsics or pose differ between two calibrations (by id; a camera in only one
// of them counts), in the order of `after`, then those only in `before`.
std::vector<std::string> changed_cameras(const SystemCalibration& before, const SystemCalibration& after);

}  // namespace panoptes
