// SPDX-License-Identifier: Apache-2.0
// Frame period of each camera, to predict where its next frame will show the tracks.
#pragma once

#include <map>
#include <string>

#include "panoptes/time.h"

namespace panoptes::estimator_app {

class FramePeriods {
 public:
  // Returns the expected stamp of the camera's next frame (`stamp_ns` until a period is known).
  TimeNs next_stamp(const std::string& camera_id, TimeNs stamp_ns) {
    auto& p = periods_[camera_id];
    const TimeNs gap = stamp_ns - p.last_ns;
    if (p.last_ns != 0 && gap > 0 && gap < kNsPerSecond)
      p.period_ns =
          p.period_ns == 0 ? static_cast<double>(gap) : 0.9 * p.period_ns + 0.1 * static_cast<double>(gap);
    p.last_ns = stamp_ns;
    return stamp_ns + static_cast<TimeNs>(p.period_ns);
  }

 private:
  struct Period {
    TimeNs last_ns = 0;
    double period_ns = 0;
  };
  std::map<std::string, Period> periods_;
};

}  // namespace panoptes::estimator_app
