// SPDX-License-Identifier: Apache-2.0
// The benchmarks' rig: a ring of cameras around a 6 x 6 m room looking inward, markers (and
// optionally 4-marker rigid bodies) on Lissajous paths, 0.1 px centroid noise; optionally a
// network that delivers frames out of stamp order. Shared by bench_estimator and bench_reorder.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "panoptes/records.h"
#include "panoptes/simulator.h"

namespace panoptes::bench {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;

// Delivery to the estimator (the simulator's latency keys, docs/simulator.md): each camera's
// fixed latency uniform in [latency_min_s, latency_max_s] (hosts and detection loads differ), an
// exponential jitter per frame, and a small fraction of frames held up much longer.
struct RingNetwork {
  double latency_min_s = 0.002, latency_max_s = 0.002;
  double jitter_s = 0;
  double late_fraction = 0;
  double late_min_s = 0.005, late_max_s = 0.030;
};

struct RingConfig {
  int cameras = 32;
  double rate_hz = 120;
  int markers = 40;
  double warmup_s = 1.0;
  double seconds = 2.0;
  int bodies = 0;  // rigid bodies of 4 markers each, besides the loose markers
  RingNetwork network;
};

// Cameras on a circle of radius 3 m (the walls of a 6 x 6 m room) at 2.3-2.9 m, looking at the
// middle of the volume; random phases (the rig is not synchronised). Markers on Lissajous paths
// with centres spread over the floor, |x|, |y| up to about 1.6 m, z 0.4-1.7 m, speeds up to
// about 1.5 m/s.
inline std::string scene_yaml(const RingConfig& config, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uniform = [&](double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(rng);
  };
  // A stream of its own, so that the network model never changes the scene's other draws.
  std::mt19937_64 network_rng(seed ^ 0x6e6574776f726bULL);
  const RingNetwork& net = config.network;
  std::ostringstream yaml;
  yaml.precision(9);
  yaml << "seed: " << seed << "\nduration: " << config.warmup_s + config.seconds << "\n"
       << "defaults: {width: 1280, height: 1024, K: [1000.0, 1000.0, 639.5, 511.5], rate: " << config.rate_hz
       << ", centroid_noise: 0.1, latency_jitter: " << net.jitter_s
       << ", late_fraction: " << net.late_fraction << ", late_delay: [" << net.late_min_s << ", "
       << net.late_max_s << "]}\ncameras:\n";
  for (int c = 0; c < config.cameras; ++c) {
    const double angle = 2.0 * M_PI * c / config.cameras;
    const double height = c % 2 == 0 ? 2.3 : 2.9;
    const double latency =
        std::uniform_real_distribution<double>(net.latency_min_s, net.latency_max_s)(network_rng);
    yaml << "  - {id: cam" << c << ", look_at: {eye: [" << 3.0 * std::cos(angle) << ", "
         << 3.0 * std::sin(angle) << ", " << height
         << "], target: [0.0, 0.0, 1.0]}, phase: " << uniform(0.0, 1.0 / config.rate_hz)
         << ", latency: " << latency << "}\n";
  }
  yaml << "markers:\n";
  for (int m = 0; m < config.markers; ++m) {
    yaml << "  - {name: m" << m << ", path: {type: lissajous, center: [" << uniform(-0.5, 0.5) << ", "
         << uniform(-0.5, 0.5) << ", " << uniform(0.9, 1.2) << "], amplitude: [" << uniform(0.5, 1.1) << ", "
         << uniform(0.5, 1.1) << ", " << uniform(0.15, 0.45) << "], frequency: [" << uniform(0.08, 0.2)
         << ", " << uniform(0.08, 0.2) << ", " << uniform(0.1, 0.3) << "], phase: [" << uniform(0, 2 * M_PI)
         << ", " << uniform(0, 2 * M_PI) << ", " << uniform(0, 2 * M_PI) << "]}}\n";
  }
  if (config.bodies > 0) yaml << "bodies:\n";
  for (int b = 0; b < config.bodies; ++b) {
    // Random constellations of 4 markers within a 20 cm cube (distinct for identification).
    yaml << "  - {name: body" << b << ", markers: [[0, 0, 0]";
    for (int m = 1; m < 4; ++m)
      yaml << ", [" << uniform(-0.1, 0.1) << ", " << uniform(-0.1, 0.1) << ", " << uniform(-0.1, 0.1) << "]";
    yaml << "], path: {type: lissajous, center: [" << uniform(-0.5, 0.5) << ", " << uniform(-0.5, 0.5) << ", "
         << uniform(0.9, 1.2) << "], amplitude: [" << uniform(0.5, 1.1) << ", " << uniform(0.5, 1.1) << ", "
         << uniform(0.15, 0.45) << "], frequency: [" << uniform(0.08, 0.2) << ", " << uniform(0.08, 0.2)
         << ", " << uniform(0.1, 0.3)
         << "]}, rotation: {type: oscillate, amplitude: [0.5, 0.5, 1.0], frequency: [" << uniform(0.1, 0.3)
         << ", " << uniform(0.1, 0.3) << ", " << uniform(0.1, 0.3) << "]}}\n";
  }
  return yaml.str();
}

// Every camera's frames, in stamp order, stamps and received_ns shifted by kEpoch.
inline std::vector<FeatureFrame> simulate(const Scene& scene) {
  std::vector<FeatureFrame> frames;
  for (const auto& camera : scene.cameras()) {
    CameraSimulator simulator(scene, camera.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < scene.duration_ns(); ++k) {
      frames.push_back(simulator.features(k));
      frames.back().stamp_ns += kEpoch;
      frames.back().received_ns += kEpoch;
    }
  }
  std::stable_sort(frames.begin(), frames.end(), [](const FeatureFrame& a, const FeatureFrame& b) {
    return std::tie(a.stamp_ns, a.camera_id) < std::tie(b.stamp_ns, b.camera_id);
  });
  return frames;
}

}  // namespace panoptes::bench
