// SPDX-License-Identifier: Apache-2.0
// "aravis:<ip or device id>" frame source: GenICam camera over GigE Vision / USB3 Vision via Aravis (private
// to panoptes_camera).
#pragma once

#include <memory>
#include <string>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

// `target` is the part after "aravis:". Throws std::runtime_error naming the spec and the reason.
std::unique_ptr<FrameSource> open_aravis_source(const std::string& target, const SourceOptions& options);

}  // namespace panoptes::camera
