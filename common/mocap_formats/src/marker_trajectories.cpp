// SPDX-License-Identifier: Apache-2.0
#include "panoptes/formats/marker_trajectories.h"

namespace panoptes {

double metres_per_unit(const std::string& units) {
  if (units == "mm") return 1e-3;
  if (units == "cm") return 1e-2;
  if (units == "m") return 1.0;
  return 0.0;
}

}  // namespace panoptes
