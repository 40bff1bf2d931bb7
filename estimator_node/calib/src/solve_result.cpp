// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/solve_result.h"

#include <algorithm>

namespace panoptes::calib {

int SolveResult::calibrated_count() const {
  return static_cast<int>(std::count_if(cameras.begin(), cameras.end(),
                                        [](const CameraResult& c) { return c.T_world_cam.has_value(); }));
}

}  // namespace panoptes::calib
