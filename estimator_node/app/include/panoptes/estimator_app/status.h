// SPDX-License-Identifier: Apache-2.0
// EstimatorUsage (usage.h) as the rt/panoptes/estimator_status message (docs/protocol.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "panoptes/estimator/usage.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::estimator_app {

msg::EstimatorStatus to_status_message(const estimator::EstimatorUsage& usage);
// One camera's calibration health as on the wire; `stamp_ns` (the status's) dates quarantined_for_s.
msg::CameraCalibrationHealth to_message(const estimator::CameraCalibrationHealth& health, TimeNs stamp_ns);

// What the live status line shows beside the usage.
struct StatusLineExtras {
  TimeNs elapsed_ns = 0;  // since the node started
  std::size_t bodies = 0, bodies_tracked = 0;
  std::uint64_t time_sync_answered = 0;
};

// The live progress line (docs/estimator.md, "The status line"), e.g.
// "t=12s cameras 3/4 live: c0 100% c1 99% c2 100% c3 lost 1.2 s | tracks 3+0 coasting | replays 0
// (0/s) | cpu 14% | time sync answered 52"; a quarantined camera adds "| c3 quarantined 1.4 s: whole
// image: bias (-8.33, +4.71) px = 9.57 px over 45 residuals, ..." (docs/continuous_calibration.md).
std::string status_line(const estimator::EstimatorUsage& usage, const StatusLineExtras& extras);

}  // namespace panoptes::estimator_app
