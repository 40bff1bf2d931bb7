// SPDX-License-Identifier: Apache-2.0
// How far the solve's figures can be trusted beyond its reprojection error: per camera, the
// correlation of the focal length with the camera's distance to the wand volume and the
// propagated position uncertainty, from the final adjustment's normal equations (J^T J at the
// solution); the warnings the report prints. docs/calibration.md, "Focal length and depth".
#pragma once

#include <string>
#include <vector>

#include "panoptes/calib/bundle_adjustment.h"
#include "panoptes/calib/solve_result.h"
#include "panoptes/calib/solve_stats.h"

namespace panoptes::calib {

struct SolveDiagnostics {
  std::vector<FocalDepthStats> cameras;  // per camera of the state
  // The wand's end-to-end length triangulated from the adjusted cameras, RMS error the reprojection
  // noise alone would give (each marker's covariance from its cameras, the cameras held fixed), mm.
  double predicted_length_rms_mm = 0;
  double reprojection_rms_axis_px = 0;  // of the final adjustment's residuals
};

// From `state` (the final adjustment's, with `options` its last pass): the covariance of the
// cameras and wand instants is the inverse of J_r^T J_r / s^2 + J_c^T J_c, s the reprojection RMS
// per axis, J_c the weighted wand-length (or single-light gauge) rows.
SolveDiagnostics solve_diagnostics(const BundleState& state, const WandDefinition& wand,
                                   const PassOptions& options);

// The plain-language warnings for `result`: one per camera whose |correlation| exceeds
// options.focal_depth_correlation_warning, and one when the free wand length varies more than
// options.length_consistency_warning times what the reprojection noise predicts.
// Posterior 1-sigma of every camera's free intrinsics (kEvidence: the tangent columns of
// options.free_intrinsics, marginalised over everything else the adjustment moves; the reprojection rows
// weighted by their own RMS per axis): per camera, per tangent column; empty where the intrinsics are fixed.
struct IntrinsicsPosterior {
  std::vector<std::vector<double>> sigma;
  double rms_axis_px = 0;
  bool ok = false;
};
IntrinsicsPosterior intrinsics_posterior(const BundleState& state, const WandDefinition& wand,
                                         const PassOptions& options);

std::vector<std::string> solve_warnings(const SolveResult& result, const SolveOptions& options);

}  // namespace panoptes::calib
