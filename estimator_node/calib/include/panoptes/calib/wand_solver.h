// SPDX-License-Identifier: Apache-2.0
// Extrinsic (and optionally intrinsic and time-offset) calibration of many asynchronous cameras
// from a waved wand or light: pairwise essential matrices, global unification ranked by residual
// (seed 003 §3.3.1), metric scale from the wand (seed 000 §4.5.8), then one bundle adjustment
// over cameras, wand samples and clock offsets (docs/calibration.md explains why it replaces the
// EKF virtual-object iteration of seed 003 §3.3.2).
#pragma once

#include <vector>

#include "panoptes/calib/solve_options.h"
#include "panoptes/calib/solve_result.h"
#include "panoptes/calib/triangulate.h"
#include "panoptes/calib/wand.h"
#include "panoptes/calibration.h"

namespace panoptes::calib {

// `cameras` supplies the intrinsics (T_world_cam ignored); `tracks` one per camera (matched by
// id; a camera without a track "never saw the wand"). For a wand whose ends look alike, the
// tracks' label runs are first reconciled across cameras (resolve_bar_labels, on a copy). Never
// throws on bad data: problems go to SolveResult::errors and the cameras' failure fields.
SolveResult solve_wand_calibration(const std::vector<CameraCalibration>& cameras,
                                   const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand,
                                   const SolveOptions& options = {});

}  // namespace panoptes::calib
