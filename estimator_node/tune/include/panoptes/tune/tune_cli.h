// SPDX-License-Identifier: Apache-2.0
// `estimator_node tune ...` (docs/recording.md, "Tune the filter"): the command line over the
// criteria and the search; writes the tuned settings as --config YAML, the curve as CSV and PNG.
#pragma once

namespace panoptes::tune {

// argv[0] is "tune". Returns the exit code (0 ok, 1 failure, 2 bad arguments or input).
int run_tune(int argc, char** argv);

}  // namespace panoptes::tune
