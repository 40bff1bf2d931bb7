// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera/sources.h"

#include <stdexcept>
#include <string>

#include "aravis_source.h"
#include "features_source.h"
#include "image_source.h"
#include "sim_source.h"
#include "v4l2_source.h"

namespace panoptes::camera {

namespace {
constexpr const char* kSourceForms =
    "images:<dir or glob>, sim:<scene.yaml>#<camera id>, aravis:<ip or device id>, v4l2:/dev/videoN or "
    "features:<file.jsonl>";
}

std::unique_ptr<FrameSource> open_source(const std::string& spec, const SourceOptions& options) {
  const auto colon = spec.find(':');
  const std::string kind = colon == std::string::npos ? spec : spec.substr(0, colon);
  const std::string target = colon == std::string::npos ? std::string() : spec.substr(colon + 1);
  using Opener = std::unique_ptr<FrameSource> (*)(const std::string&, const SourceOptions&);
  struct Backend {
    const char* kind;
    const char* form;
    Opener open;
  };
  static constexpr Backend kBackends[] = {
      {"images", "images:<directory or glob>", open_image_source},
      {"sim", "sim:<scene.yaml>#<camera id>", open_sim_source},
      {"aravis", "aravis:<ip or device id>", open_aravis_source},
      {"v4l2", "v4l2:/dev/videoN", open_v4l2_source},
      {"features", "features:<file.jsonl>", open_features_source},
  };
  const SourceSettings& settings = options.settings;
  if (kind != "aravis" && (settings.ptp || !settings.trigger.empty() || !settings.strobe.empty())) {
    throw std::runtime_error(
        "source '" + spec +
        "': ptp, trigger and strobe are GenICam camera features; only aravis: sources have them");
  }
  for (const Backend& backend : kBackends) {
    if (kind != backend.kind) continue;
    if (target.empty()) throw std::runtime_error(std::string(backend.kind) + ": expected " + backend.form);
    return backend.open(target, options);
  }
  throw std::runtime_error("unknown source '" + spec + "' (expected " + kSourceForms + ")");
}

}  // namespace panoptes::camera
