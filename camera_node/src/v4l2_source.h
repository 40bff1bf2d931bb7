// SPDX-License-Identifier: Apache-2.0
// "v4l2:/dev/videoN" frame source: Video4Linux2 capture device (mmap streaming) (private to panoptes_camera).
#pragma once

#include <memory>
#include <string>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

// `target` is the part after "v4l2:". Throws std::runtime_error naming the spec and the reason.
std::unique_ptr<FrameSource> open_v4l2_source(const std::string& target, const SourceOptions& options);

}  // namespace panoptes::camera
