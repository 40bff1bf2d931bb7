// SPDX-License-Identifier: Apache-2.0
// Frame sources for camera_node, chosen by --source: images:<dir or glob>, sim:<scene>#<camera>.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "panoptes/calibration.h"
#include "panoptes/image.h"
#include "panoptes/time.h"

namespace panoptes::camera {

struct CapturedFrame {
  Image image;
  std::int64_t sequence = 0;
  TimeNs stamp_ns = 0;    // mid-exposure on the common time base (0 for image files)
  TimeNs arrival_ns = 0;  // when the frame reached the node (wall clock)
};

struct SourceInfo {
  std::string camera_id;
  std::string backend;  // "images", "sim", ...
  std::string model;
  std::string serial;
  int width = 0;
  int height = 0;
  double nominal_rate_hz = 0;
  std::optional<CameraCalibration> calibration;  // known intrinsics/pose (the simulator knows them)
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const SourceInfo& info() const = 0;
  // Blocks until the next frame (paced sources wait for its time); nullopt at the end of the
  // stream or after stop().
  virtual std::optional<CapturedFrame> next() = 0;
  virtual void stop() {}
};

struct SourceOptions {
  std::string camera_id;         // overrides the id the source would choose
  TimeNs sim_epoch_ns = 0;       // sim: wall time of scene time 0 (0 = now, rounded up to 1 s)
  bool paced = true;             // sim: wait for each frame's wall time; false = as fast as possible
  std::int64_t max_frames = -1;  // stop after this many frames (-1 = the source's own end)
};

// Parses "images:<dir or glob>" or "sim:<scene.yaml>#<camera id>". Throws std::runtime_error
// (ConfigError for scene files) with a message naming what is wrong.
std::unique_ptr<FrameSource> open_source(const std::string& spec, const SourceOptions& options);

}  // namespace panoptes::camera
