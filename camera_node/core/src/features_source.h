// SPDX-License-Identifier: Apache-2.0
// "features:<file.jsonl>" frame source: replay of recorded FeatureFrames at the recorded pace (or
// --rate-scale) (private to panoptes_camera).
#pragma once

#include <memory>
#include <string>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

// `target` is the part after "features:". Throws std::runtime_error naming the spec and the reason.
std::unique_ptr<FrameSource> open_features_source(const std::string& target, const SourceOptions& options);

}  // namespace panoptes::camera
