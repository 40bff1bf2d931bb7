// SPDX-License-Identifier: Apache-2.0
// Rounding and small shapes the console's models share when they write JSON.
#pragma once

#include <cmath>

#include <nlohmann/json.hpp>

#include "panoptes/console/console_records.h"

namespace panoptes::console::detail {

// Rounded to `decimals` so that the JSON carries short numbers (x * 10^d / 10^d prints shortest).
inline double round_to(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

inline double seconds(TimeNs ns, int decimals) {
  return round_to(static_cast<double>(ns) * 1e-9, decimals);
}

inline nlohmann::json pose_json(const Pose& pose) {
  return {{"p", pose.position}, {"q", pose.orientation}};
}

}  // namespace panoptes::console::detail
