// SPDX-License-Identifier: Apache-2.0
// PLACEHOLDER: being written; replaced before landing.
#include "features_source.h"

#include <stdexcept>

namespace panoptes::camera {

std::unique_ptr<FrameSource> open_features_source(const std::string& target, const SourceOptions& /*options*/) {
  throw std::runtime_error("features:" + target + ": the features backend is not built yet");
}

}  // namespace panoptes::camera
