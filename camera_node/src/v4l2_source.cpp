// SPDX-License-Identifier: Apache-2.0
// PLACEHOLDER: being written; replaced before landing.
#include "v4l2_source.h"

#include <stdexcept>

namespace panoptes::camera {

std::unique_ptr<FrameSource> open_v4l2_source(const std::string& target, const SourceOptions& /*options*/) {
  throw std::runtime_error("v4l2:" + target + ": the v4l2 backend is not built yet");
}

}  // namespace panoptes::camera
