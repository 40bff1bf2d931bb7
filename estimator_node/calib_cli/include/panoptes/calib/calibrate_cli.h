// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate <subcommand>`: intrinsics, solve, world, capture, marker.
#pragma once

namespace panoptes::calib {

// argv[0] is "calibrate". Returns the process exit code: 0 ok, 1 a run-time failure (e.g. some
// cameras could not be calibrated; partial results are still written), 2 bad arguments or input.
int run_calibrate(int argc, char** argv);

// `calibrate capture` (the only subcommand that uses DDS). argv[0] is "capture".
int run_calibrate_capture(int argc, char** argv);

}  // namespace panoptes::calib
