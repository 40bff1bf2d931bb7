// SPDX-License-Identifier: Apache-2.0
// PLACEHOLDER: being written; replaced before landing.
#include "aravis_source.h"

#include <stdexcept>

namespace panoptes::camera {

std::unique_ptr<FrameSource> open_aravis_source(const std::string& target, const SourceOptions& /*options*/) {
  throw std::runtime_error("aravis:" + target + ": the aravis backend is not built yet");
}

}  // namespace panoptes::camera
