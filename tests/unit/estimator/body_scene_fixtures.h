// SPDX-License-Identifier: Apache-2.0
// Seeded body scenes through the tracker and the synchronous snapshot solve they are compared
// with (issues 5, 16 and 35; docs/bodies.md): shared by test_bodies.cpp and test_body_grid.cpp.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "panoptes/estimator/body_snapshot.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/simulator.h"

namespace panoptes::estimator::body_fixtures {

inline constexpr TimeNs kEpoch = 1'700'000'000'000'000'000;

inline double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return quaternion_to_rotation_vector(a.conjugate() * b).norm() * 180.0 / M_PI;
}

// A body of a generated scene: its markers (body frame, YAML) and its motion, a Lissajous path and
// an oscillation about three axes whose frequencies are those at a peak rate of 2 rad/s.
struct SceneBody {
  const char* name;
  const char* markers;
  const char* center;
  double amplitude[3];      // path, m
  double frequency[3];      // path, Hz at 2 rad/s
  const char* phase;        // path
  double rot_amplitude[3];  // rad
  double rot_frequency[3];  // Hz at 2 rad/s
  const char* rot_phase;
  const char* initial;  // quaternion [x, y, z, w]
};

// Issue 16's three small bodies (4-5 markers, 8-12 cm across; ~20 m/s² and ~2 rad/s).
inline const std::vector<SceneBody>& small_fast_bodies() {
  static const std::vector<SceneBody> bodies = {
      {"small",
       "[[0.035, 0.033, 0.001], [-0.015, 0.03, 0.002], [0.0, -0.035, 0.01], [-0.021, -0.029, -0.011]]",
       "[0.35, 0.1, 1.0]",
       {0.21, 0.19, 0.1},
       {1.3, 1.1, 1.5},
       "[0, 1, 2]",
       {0.3, 0.25, 0.35},
       {0.6, 0.8, 0.5},
       "[0, 0.5, 1]",
       "[0, 0, 0, 1]"},
      {"five",
       "[[0.06, -0.004, -0.002], [-0.005, 0.031, 0.005], [-0.022, 0.033, -0.023], [0.012, -0.006, -0.007], "
       "[-0.044, -0.056, 0.028]]",
       "[-0.35, 0.25, 1.1]",
       {0.18, 0.21, 0.1},
       {1.2, 1.35, 1.45},
       "[2, 0.3, 1]",
       {0.33, 0.28, 0.23},
       {0.7, 0.5, 0.8},
       "[1, 2, 0]",
       "[0.0, 0.0, 0.7071068, 0.7071068]"},
      {"ten",
       "[[-0.023, -0.032, -0.032], [-0.002, 0.037, 0.019], [-0.027, -0.029, 0.008], [0.053, 0.023, 0.007]]",
       "[0.0, -0.4, 0.95]",
       {0.23, 0.17, 0.09},
       {1.15, 1.4, 1.6},
       "[0.7, 2.2, 0.1]",
       {0.24, 0.33, 0.28},
       {0.8, 0.6, 0.55},
       "[0.4, 1.1, 2.5]",
       "[0, 0, 0, 1]"},
  };
  return bodies;
}

inline std::string yaml_triple(const double v[3], double scale) {
  char text[96];
  std::snprintf(text, sizeof text, "[%.6g, %.6g, %.6g]", v[0] * scale, v[1] * scale, v[2] * scale);
  return text;
}

// A scene's `bodies:` section (4 mm markers, hidden beyond 110° from their normal). `speed_radps`
// is the peak angular rate: rotation frequencies scale with it and path frequencies with its square
// root (the peak linear acceleration with it), from the bodies' figures at 2 rad/s.
inline std::string bodies_yaml(const std::vector<SceneBody>& bodies, double speed_radps) {
  std::string yaml = "bodies:\n";
  const double rot_scale = speed_radps / 2.0, path_scale = std::sqrt(speed_radps / 2.0);
  for (const SceneBody& body : bodies) {
    yaml += std::string("  - name: ") + body.name + "\n    markers: " + body.markers +
            "\n    marker_radius: 0.004\n    path: {type: lissajous, center: " + body.center +
            ", amplitude: " + yaml_triple(body.amplitude, 1.0) +
            ", frequency: " + yaml_triple(body.frequency, path_scale) + ", phase: " + body.phase +
            "}\n    rotation: {type: oscillate, amplitude: " + yaml_triple(body.rot_amplitude, 1.0) +
            ", frequency: " + yaml_triple(body.rot_frequency, rot_scale) + ", phase: " + body.rot_phase +
            ", initial: " + body.initial + "}\n    occlusion: {facing_angle: 110}\n";
  }
  return yaml;
}

struct BodyErrors {
  double sum_p2 = 0, sum_a2 = 0, max_p = 0;
  std::size_t samples = 0, published = 0, correct = 0, wrong = 0;
  double rmse_mm() const { return samples ? std::sqrt(sum_p2 / samples) * 1e3 : NAN; }
  double rmse_deg() const { return samples ? std::sqrt(sum_a2 / samples) : NAN; }
  double tracked() const { return samples ? static_cast<double>(correct) / static_cast<double>(samples) : 0; }
  // One published pose against the truth: more than 2 cm or 5° off is a wrong pose (a wrong
  // identification or a lost filter), not counted in the RMSE.
  void judge(const RigidTransform& pose, const RigidTransform& truth) {
    const double dp = (pose.t - truth.t).norm();
    const double da = angle_deg(pose.q, truth.q);
    if (dp > 0.02 || da > 5.0) {
      ++wrong;
      return;
    }
    ++correct;
    sum_p2 += dp * dp;
    sum_a2 += da * da;
    max_p = std::max(max_p, dp);
  }
};

// Filters a frame before the tracker sees it: camera index, the frame (blobs in visible_markers
// order when the scene has no false blobs or merging), its visible marker indices. False: drop it.
using FrameFilter = std::function<bool(std::size_t, FeatureFrame&, const std::vector<int>&)>;

struct SceneRun {
  std::map<std::string, BodyErrors> bodies;
  BodyStats stats;
};

// A camera frame of a scene: its stamp, camera (index into the scene's cameras) and frame number.
struct SceneFrame {
  TimeNs stamp;
  std::size_t camera;
  std::int64_t k;
  bool operator>(const SceneFrame& o) const { return std::tie(stamp, camera) > std::tie(o.stamp, o.camera); }
};

// Every camera's frames over the scene, in stamp order (the order the tracker is fed).
inline std::vector<SceneFrame> frame_order(const Scene& scene,
                                           const std::vector<CameraSimulator>& simulators) {
  std::vector<SceneFrame> queue;
  for (std::size_t c = 0; c < simulators.size(); ++c) {
    for (std::int64_t k = 0; simulators[c].frame_time_ns(k) <= scene.duration_ns(); ++k)
      queue.push_back({simulators[c].frame_stamp_ns(k), c, k});
  }
  std::sort(queue.begin(), queue.end(), [](const SceneFrame& a, const SceneFrame& b) { return b > a; });
  return queue;
}

inline std::vector<CameraSimulator> scene_simulators(const Scene& scene) {
  std::vector<CameraSimulator> simulators;
  for (const auto& camera : scene.cameras()) simulators.emplace_back(scene, camera.calibration.id);
  return simulators;
}

inline SceneRun run_scene(const Scene& scene, double warmup_s, const FrameFilter& filter = {},
                          TimeNs horizon_ns = 0, double window_start_s = 0, double window_end_s = 1e9,
                          const TrackerOptions& options = {}) {
  std::vector<CameraSimulator> simulators = scene_simulators(scene);
  const std::vector<SceneFrame> queue = frame_order(scene, simulators);

  Tracker tracker(options);
  tracker.set_calibration(scene.calibration());
  tracker.set_bodies(scene.body_definitions());
  SceneRun run;
  for (const SceneFrame& next : queue) {
    FeatureFrame frame = simulators[next.camera].features(next.k);
    if (filter && !filter(next.camera, frame, simulators[next.camera].visible_markers(next.k))) continue;
    const TimeNs scene_time = frame.stamp_ns;
    frame.stamp_ns += kEpoch;
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time);
    if (t < warmup_s || t < window_start_s || t > window_end_s) continue;
    const auto poses = tracker.current_poses(horizon_ns);
    // With smoothing, poses are stamped behind the newest frame: each is judged at its own stamp.
    const TimeNs lag_ns = options.bodies.smoothing_ns;
    for (const BodyTruth& truth : scene.bodies_at(scene_time - lag_ns + horizon_ns)) {
      BodyErrors& errors = run.bodies[truth.name];
      ++errors.samples;
      for (const PoseRecord& pose : poses) {
        if (pose.body != truth.name) continue;
        EXPECT_EQ(pose.stamp_ns, frame.stamp_ns - lag_ns);
        ++errors.published;
        const Eigen::Quaterniond q(pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z());
        errors.judge({q, pose.p}, truth.T_world_body);
      }
    }
  }
  run.stats = tracker.body_stats();
  return run;
}

inline void print(const char* scenario, const SceneRun& run) {
  for (const auto& [name, e] : run.bodies) {
    std::printf("%s: body %s tracked %.2f%% (wrong %zu of %zu) RMSE %.3f mm (max %.3f) / %.4f deg\n",
                scenario, name.c_str(), 100.0 * e.tracked(), e.wrong, e.samples, e.rmse_mm(), e.max_p * 1e3,
                e.rmse_deg());
  }
  std::printf("%s: identified %llu reidentified %llu lost %llu marker updates %llu\n", scenario,
              static_cast<unsigned long long>(run.stats.identified),
              static_cast<unsigned long long>(run.stats.reidentified),
              static_cast<unsigned long long>(run.stats.lost),
              static_cast<unsigned long long>(run.stats.marker_updates));
}

// The synchronous snapshot: at every frame instant of the synchronous rig, each body's pose by
// Gauss-Newton over all cameras' blobs of its markers (known correspondences), initialised from
// the previous instant's solution (the truth moved by 5 mm and 3° before the first one).
inline std::map<std::string, BodyErrors> run_snapshot(const Scene& scene, double warmup_s) {
  std::vector<CameraSimulator> simulators;
  std::vector<CameraModel> cameras;
  for (const auto& camera : scene.cameras()) {
    simulators.emplace_back(scene, camera.calibration.id);
    cameras.push_back(camera.calibration.model());
  }
  const auto definitions = scene.body_definitions();
  // Scene marker index -> (body, marker): bodies' markers are named "<body>/<index>".
  std::vector<std::pair<int, std::size_t>> owner;
  for (const std::string& name : scene.marker_names()) {
    const auto slash = name.find('/');
    int body = -1;
    for (std::size_t b = 0; b < definitions.size(); ++b)
      if (name.substr(0, slash) == definitions[b].name) body = static_cast<int>(b);
    owner.emplace_back(body, body < 0 ? 0 : std::stoul(name.substr(slash + 1)));
  }
  std::map<std::string, BodyErrors> errors;
  std::vector<std::optional<RigidTransform>> previous(definitions.size());
  for (std::int64_t k = 0; simulators[0].frame_time_ns(k) <= scene.duration_ns(); ++k) {
    const TimeNs t = simulators[0].frame_time_ns(k);
    std::vector<std::vector<SnapshotObservation>> observations(definitions.size());
    for (std::size_t c = 0; c < simulators.size(); ++c) {
      EXPECT_EQ(simulators[c].frame_time_ns(k), t);  // a synchronous rig
      const FeatureFrame frame = simulators[c].features(k);
      const auto visible = simulators[c].visible_markers(k);
      EXPECT_EQ(frame.blobs.size(), visible.size());
      for (std::size_t i = 0; i < visible.size(); ++i) {
        const auto [body, marker] = owner[static_cast<std::size_t>(visible[i])];
        if (body >= 0)
          observations[static_cast<std::size_t>(body)].push_back(
              {c, marker, {frame.blobs[i].x, frame.blobs[i].y}});
      }
    }
    const auto truths = scene.bodies_at(t);
    for (std::size_t b = 0; b < definitions.size(); ++b) {
      EXPECT_EQ(truths[b].name, definitions[b].name);
      const RigidTransform& truth = truths[b].T_world_body;
      const RigidTransform start =
          previous[b]
              ? *previous[b]
              : RigidTransform{truth.q * rotation_vector_to_quaternion(Eigen::Vector3d(0.03, -0.03, 0.03)),
                               truth.t + Eigen::Vector3d(0.003, -0.003, 0.003)};
      const auto solved = solve_snapshot_pose(definitions[b].markers, cameras, observations[b], start);
      previous[b] = solved ? std::optional(solved->T_world_body) : std::nullopt;
      if (ns_to_seconds(t) < warmup_s) continue;
      BodyErrors& e = errors[definitions[b].name];
      ++e.samples;
      if (!solved) continue;
      ++e.published;
      e.judge(solved->T_world_body, truth);
    }
  }
  return errors;
}

// Peak linear acceleration (m/s²) and angular velocity (rad/s) of a body's truth, by differences.
inline std::pair<double, double> peak_motion(const Scene& scene, const std::string& body) {
  const auto pose = [&](TimeNs t) {
    for (const BodyTruth& truth : scene.bodies_at(t))
      if (truth.name == body) return truth.T_world_body;
    return RigidTransform{};
  };
  const TimeNs h = 1'000'000;
  double accel = 0, rate = 0;
  for (TimeNs t = h; t + h <= scene.duration_ns(); t += h) {
    const RigidTransform a = pose(t - h), b = pose(t), c = pose(t + h);
    accel = std::max(accel, (a.t - 2 * b.t + c.t).norm() / 1e-6);
    rate = std::max(rate, quaternion_to_rotation_vector(b.q.conjugate() * c.q).norm() / 1e-3);
  }
  return {accel, rate};
}

}  // namespace panoptes::estimator::body_fixtures
