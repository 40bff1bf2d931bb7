// SPDX-License-Identifier: Apache-2.0
// The calibration report: a terminal summary, text and JSON files, coverage images and a residual
// plot, written next to the calibration YAML.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "panoptes/calib/wand_solver.h"

namespace panoptes::calib {

// Share (0..1) of an 8 x 8 grid over the image that holds at least one wand observation.
double image_coverage(const SolveResult& result, int camera);

// A few lines per camera: state, RMS, offsets, coverage; then the wand-length figures and errors.
std::string report_summary(const SolveResult& result);

// Writes <out>.report.txt, <out>.report.json, <out>.coverage_<camera>.png, <out>.residuals.png and
// <out>.layout.png (top view). Returns the files written; throws std::runtime_error naming a file
// it could not write.
std::vector<std::filesystem::path> write_report(const SolveResult& result,
                                                const std::filesystem::path& out_yaml);

// The calibration as the contract YAML: calibrated cameras with T_world_cam, failed ones with
// intrinsics only and a comment naming the reason. A single-light result starts with the comment
// line kUnscaledMarker...: its positions have no metric scale until `calibrate world` sets it.
std::string calibration_yaml(const SolveResult& result);

inline constexpr const char* kUnscaledMarker = "# UNSCALED";

// Whether the calibration file at `path` carries the kUnscaledMarker comment (in its leading
// comment lines). Throws std::runtime_error naming the file if it cannot be read.
bool calibration_file_is_unscaled(const std::filesystem::path& path);

}  // namespace panoptes::calib
