// SPDX-License-Identifier: Apache-2.0
// "v4l2:/dev/videoN" frame source: Video4Linux2 capture device (mmap streaming) (private to panoptes_camera).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

class V4l2Device;

// Opens the device node at a path; throws V4l2OpenError (v4l2_device.h) when it cannot.
using V4l2DeviceFactory = std::function<std::unique_ptr<V4l2Device>(const std::string& path)>;

// The v4l2 source on any device implementation (tests pass an in-memory fake). The factory is
// called at start-up and again on every reconnection attempt. Throws std::runtime_error
// "v4l2:<path>: <reason>" when the device cannot be opened or configured.
std::unique_ptr<FrameSource> make_v4l2_source(std::string path, V4l2DeviceFactory open_device,
                                              const SourceOptions& options);

// `target` is the part after "v4l2:". Throws std::runtime_error naming the spec and the reason.
std::unique_ptr<FrameSource> open_v4l2_source(const std::string& target, const SourceOptions& options);

}  // namespace panoptes::camera
