// SPDX-License-Identifier: Apache-2.0
// `estimator_node tune ...` (docs/recording.md, "Tune the filter"): the command line over the
// criteria and the search; writes the tuned settings as --config YAML, the curve as CSV and PNG.
#pragma once

#include <functional>
#include <string>

#include "panoptes/session/offline_replay.h"

namespace panoptes::tune {

// Reads the FeatureFrames of a recording (estimator_node passes its MCAP reader, which decodes
// CDR and so lives on the DDS side of the layering; this library stays without DDS).
using RecordingReader = std::function<session::FeatureFiles(const std::string& path)>;

// argv[0] is "tune". Returns the exit code (0 ok, 1 failure, 2 bad arguments or input). Without a
// `read_recording`, --in-recording is refused.
int run_tune(int argc, char** argv, const RecordingReader& read_recording = {});

}  // namespace panoptes::tune
