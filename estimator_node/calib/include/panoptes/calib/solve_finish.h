// SPDX-License-Identifier: Apache-2.0
// Stage 4 of the wand solver: the adjusted cameras and wand into the SolveResult. Per-camera and
// overall reprojection statistics, the raw frames against the solved wand path, the wand
// triangulated again without its length terms (its length error, and the spacing check that fails
// a wrong --wand), and the provisional world frame (z up from the cameras' layout).
// docs/calibration.md, "Stages".
#pragma once

#include <vector>

#include "panoptes/calib/bundle_adjustment.h"
#include "panoptes/calib/solve_result.h"

namespace panoptes::calib {

// `partial` carries what the earlier stages set (cameras with their ids, counters and failures,
// edges, reference, convergence); `adjusted` the bundle adjustment's state; `cameras` the given
// intrinsics and ids; `tracks` one per camera. Returns `partial` completed.
SolveResult finish_solution(SolveResult partial, const BundleState& adjusted,
                            const std::vector<CameraCalibration>& cameras,
                            const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand);

}  // namespace panoptes::calib
