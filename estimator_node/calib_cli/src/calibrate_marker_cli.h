// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate marker`: self-calibration of a 7-LED marker (seed 004 §3) from one
// camera's recorded features. No DDS; reads files, writes a bodies YAML (docs/monocular_markers.md).
#pragma once

namespace panoptes::estimator {

// argv[0] is the command name used in messages. Returns the process exit code (0 ok, 1 failure,
// 2 bad arguments or input).
int run_calibrate_marker(int argc, char** argv);

}  // namespace panoptes::estimator
