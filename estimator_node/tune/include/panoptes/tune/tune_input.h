// SPDX-License-Identifier: Apache-2.0
// What the tuner replays: a calibration and every camera's feature frames in stamp order. The
// one input-side function reads the offline path's JSONL files; a recording reader (MCAP) only
// has to produce the same TuneInput.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/records.h"

namespace panoptes {
class Scene;
}

namespace panoptes::tune {

struct TuneInput {
  SystemCalibration calibration;
  std::vector<FeatureFrame> frames;  // sorted by stamp (session::sort_by_stamp)
  std::size_t bad_lines = 0;         // malformed input records, skipped
};

// Reads `calibration_file` and the FeatureFrame JSONL `feature_files` (as estimator_node
// --in-features). Throws ConfigError / std::runtime_error naming the file.
TuneInput load_feature_input(const std::string& calibration_file,
                             const std::vector<std::string>& feature_files);

// Every camera's frames of a simulated scene (mid-exposure in [0, duration)), stamped from
// `epoch_ns` as panoptes_sim features writes them, with the scene's calibration: a recording made
// in memory (tests, benchmarks).
TuneInput simulated_input(const Scene& scene, TimeNs epoch_ns);

// The ids of the cameras that have frames in `input` and a pose in its calibration, sorted.
std::vector<std::string> cameras_with_frames(const TuneInput& input);

}  // namespace panoptes::tune
