// SPDX-License-Identifier: Apache-2.0
// estimator_node --in-recording: the FeatureFrames of an MCAP recording (panoptes_record), decoded
// from their CDR as the live node decodes them, for the offline path (docs/recording.md).
#pragma once

#include <string>

#include "panoptes/session/offline_replay.h"

namespace panoptes::estimator_app {

// Every FeatureFrame on /panoptes/features, in recording order, with received_ns set to the time
// the recorder received it (its log time). A damaged chunk or an undecodable message is counted in
// bad_lines and logged with the file and offset; an empty or non-MCAP file throws (naming it).
session::FeatureFiles read_recording_features(const std::string& path);

}  // namespace panoptes::estimator_app
