// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera/sources.h"

#include <stdexcept>
#include <string>

#include "image_source.h"
#include "sim_source.h"

namespace panoptes::camera {

std::unique_ptr<FrameSource> open_source(const std::string& spec, const SourceOptions& options) {
  const auto colon = spec.find(':');
  const std::string kind = colon == std::string::npos ? spec : spec.substr(0, colon);
  const std::string target = colon == std::string::npos ? std::string() : spec.substr(colon + 1);
  if (kind == "images") {
    if (target.empty()) throw std::runtime_error("images: expected images:<directory or glob>");
    return open_image_source(target, options);
  }
  if (kind == "sim") {
    if (target.empty()) throw std::runtime_error("sim: expected sim:<scene.yaml>#<camera id>");
    return open_sim_source(target, options);
  }
  throw std::runtime_error("unknown source '" + spec +
                           "' (expected images:<dir or glob> or sim:<scene.yaml>#<camera id>)");
}

}  // namespace panoptes::camera
