// SPDX-License-Identifier: Apache-2.0
// The command line of `panoptes_label angles` (docs/marker_sets.md, "Segment poses and joint
// angles"); the work is panoptes/label_job/angles_job.h's.
#pragma once

#include <CLI/CLI.hpp>

#include "panoptes/label_job/angles_job.h"

namespace panoptes::label_job {

// Adds the `angles` subcommand to `app`, its options read into `options`.
CLI::App* add_angles_command(CLI::App& app, AnglesCommandOptions& options);

// Runs it and prints the report; returns the exit code.
int run_angles_command(const AnglesCommandOptions& options);

}  // namespace panoptes::label_job
