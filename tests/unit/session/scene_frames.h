// SPDX-License-Identifier: Apache-2.0
// The session tests' input: the first seconds of a simulated scene's feature frames.
#pragma once

#include <algorithm>
#include <cstdint>
#include <tuple>
#include <vector>

#include "panoptes/simulator.h"

namespace panoptes::session::testing {

// The first `seconds` of a scene's frames (every camera), in stamp order.
inline std::vector<FeatureFrame> simulate(const Scene& scene, double seconds) {
  std::vector<FeatureFrame> frames;
  for (const auto& camera : scene.cameras()) {
    CameraSimulator simulator(scene, camera.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < seconds_to_ns(seconds); ++k)
      frames.push_back(simulator.features(k));
  }
  std::stable_sort(frames.begin(), frames.end(), [](const FeatureFrame& a, const FeatureFrame& b) {
    return std::tie(a.stamp_ns, a.camera_id) < std::tie(b.stamp_ns, b.camera_id);
  });
  return frames;
}

}  // namespace panoptes::session::testing
