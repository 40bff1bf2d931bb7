// SPDX-License-Identifier: Apache-2.0
#pragma once

namespace panoptes::calib {

// `calibrate history`, `calibrate revert`, `calibrate accept`: argv[0] is the subcommand.
int run_calibrate_history(int argc, char** argv);

}  // namespace panoptes::calib
