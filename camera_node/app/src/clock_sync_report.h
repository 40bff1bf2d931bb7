// SPDX-License-Identifier: Apache-2.0
// camera_node's log lines about the clock synchronisation (tests/integration/test_clock_sync.sh
// reads them).
#pragma once

#include <string>

#include "panoptes/camera/node_clock.h"
#include "panoptes/dds/time_sync.h"

namespace panoptes::camera_app {

std::string format_seconds(TimeNs ns);  // "12.34"

// One line on the state of the clock synchronisation; with a simulated skew also the truth (the
// time service is assumed to run on this host, whose wall clock is then the common time base).
std::string clock_sync_line(const dds::TimeSyncClientStatus& status, const camera::NodeClock& clock);

}  // namespace panoptes::camera_app
