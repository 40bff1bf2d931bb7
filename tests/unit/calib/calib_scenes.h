// SPDX-License-Identifier: Apache-2.0
// Simulated wand calibration runs for the calibration tests: scenes, features, and the errors of
// a solution against the truth after a rigid alignment.
#pragma once

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "panoptes/calib/report.h"
#include "panoptes/calib/wand.h"
#include "panoptes/calib/wand_solver.h"
#include "panoptes/calib/world_frame.h"
#include "panoptes/rigid_fit.h"
#include "panoptes/simulator.h"

namespace panoptes::calib::testing {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000;

struct CameraSpec {
  Eigen::Vector3d eye, target;
  double phase_s = 0, clock_offset_s = 0, rate_hz = 100;
};

struct SceneSpec {
  std::vector<CameraSpec> cameras;
  double noise_px = 0.1;
  double duration_s = 20;
  int width = 1280, height = 1024;
  double focal = 700;
  std::string distortion = "[0, 0, 0, 0, 0]";
  std::string wand_path;      // YAML flow map of the body path
  std::string wand_rotation;  // YAML flow map
  std::string wand_markers = "[[-0.25, 0, 0], [-0.07, 0, 0], [0.25, 0, 0]]";
  std::vector<Eigen::Vector3d> static_markers;  // e.g. an L-frame on the floor
  std::uint64_t seed = 7;
};

inline std::string v3(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out.precision(17);
  out << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return out.str();
}

inline std::string scene_yaml(const SceneSpec& spec) {
  std::ostringstream yaml;
  yaml.precision(17);
  yaml << "seed: " << spec.seed << "\nduration: " << spec.duration_s << "\ndefaults:\n  width: " << spec.width
       << "\n  height: " << spec.height << "\n  K: [" << spec.focal << ", " << spec.focal << ", "
       << (spec.width - 1) / 2.0 + 3.0 << ", " << (spec.height - 1) / 2.0 - 2.0
       << "]\n  distortion: " << spec.distortion << "\n  centroid_noise: " << spec.noise_px << "\ncameras:\n";
  for (std::size_t i = 0; i < spec.cameras.size(); ++i) {
    const auto& camera = spec.cameras[i];
    yaml << "  - id: cam" << i << "\n    look_at: {eye: " << v3(camera.eye)
         << ", target: " << v3(camera.target) << "}\n    rate: " << camera.rate_hz
         << "\n    phase: " << camera.phase_s << "\n    clock_offset: " << camera.clock_offset_s << "\n";
  }
  if (!spec.static_markers.empty()) {
    yaml << "markers:\n";
    for (std::size_t i = 0; i < spec.static_markers.size(); ++i)
      yaml << "  - {name: static" << i << ", path: {type: static, position: " << v3(spec.static_markers[i])
           << "}}\n";
  }
  if (!spec.wand_path.empty())
    yaml << "bodies:\n  - name: wand\n    markers: " << spec.wand_markers << "\n    path: " << spec.wand_path
         << "\n    rotation: " << spec.wand_rotation << "\n";
  return yaml.str();
}

// Eight cameras round a 4 x 4 x 2.5 m room (corners and wall centres, near the ceiling) with wide
// 1280x1024 lenses (f = 700 px, 85 deg), aimed near the centre; the wand reaches the walls.
inline SceneSpec room8() {
  SceneSpec spec;
  for (int i = 0; i < 8; ++i) {
    const double angle = M_PI / 4 * i + 0.1;
    const double r = (i % 2 == 0) ? 1.95 : 2.6;  // wall centres and corners of the 4 m square
    CameraSpec camera;
    camera.eye = Eigen::Vector3d(r * std::cos(angle), r * std::sin(angle), 2.35 - 0.05 * (i % 3));
    camera.target = Eigen::Vector3d(0.2 * std::cos(angle + 2), 0.2 * std::sin(angle + 2), 0.9);
    spec.cameras.push_back(camera);
  }
  spec.wand_path =
      "{type: lissajous, center: [0, 0, 1.15], amplitude: [1.25, 1.25, 0.75], frequency: [0.13, 0.171, "
      "0.23]}";
  spec.wand_rotation = "{type: oscillate, amplitude: [1.3, 1.1, 3.0], frequency: [0.29, 0.37, 0.083]}";
  return spec;
}

// The same 4 x 4 x 2.5 m room set up as a commercial studio would be: eight 2048x2048 cameras
// with f = 2150 px (51 deg, the OptiTrack Prime 41 / Vicon Vantage class) at the four corners and
// the four wall centres, 2.45-2.75 m high, aimed into the capture volume; the wand is waved
// through that volume (about 2 x 2 x 1.5 m), not into the corners where only two cameras see it.
struct StudioLayout {
  double corner_height = 2.75, wall_height = 2.5;
  double corner_target_z = 0.95, wall_target_z = 0.9;
  double corner_target_r = 0.0, wall_target_r = 0.0;  // aim past the centre, towards the far side
  Eigen::Vector3d centre{0, 0, 1.1}, amplitude{0.8, 0.8, 0.55};
};

inline SceneSpec studio8(const StudioLayout& layout = {}) {
  SceneSpec spec;
  spec.width = 2048;
  spec.height = 2048;
  spec.focal = 2150;
  for (int i = 0; i < 8; ++i) {
    const double angle = M_PI / 4 * i;
    const bool corner = i % 2 == 1;
    const double r = corner ? 1.9 * std::sqrt(2.0) : 1.92;  // 10 cm in from the walls
    const Eigen::Vector2d out(std::cos(angle), std::sin(angle));
    CameraSpec camera;
    const double height = (corner ? layout.corner_height : layout.wall_height) - 0.05 * (i % 3 == 0);
    camera.eye = Eigen::Vector3d(r * out.x(), r * out.y(), height);
    const Eigen::Vector2d target = -(corner ? layout.corner_target_r : layout.wall_target_r) * out;
    camera.target =
        Eigen::Vector3d(target.x(), target.y(), corner ? layout.corner_target_z : layout.wall_target_z);
    spec.cameras.push_back(camera);
  }
  spec.wand_path = "{type: lissajous, center: " + v3(layout.centre) + ", amplitude: " + v3(layout.amplitude) +
                   ", frequency: [0.13, 0.171, 0.23]}";
  spec.wand_rotation = "{type: oscillate, amplitude: [1.3, 1.1, 3.0], frequency: [0.29, 0.37, 0.083]}";
  return spec;
}

// deploy/scenes/wand_room.yaml: six 1280x1024 cameras (f = 700 px, principal point 3 px right and 2 px
// up of the image centre, phases 0-9 ms) round a 4 x 4 m room, aimed at (0, 0, 0.9), the wand
// waved through it for 8 s (issue 34's calibration finding was made on it).
inline SceneSpec wand_room6() {
  SceneSpec spec;
  const double eyes[6][3] = {{1.95, 0.2, 2.35}, {1.8, 1.8, 2.3},     {-0.2, 1.95, 2.35},
                             {-1.8, 1.8, 2.3},  {-1.95, -0.2, 2.35}, {0.2, -1.95, 2.3}};
  const double phases[6] = {0.0, 0.003, 0.006, 0.009, 0.002, 0.005};
  for (int i = 0; i < 6; ++i) {
    CameraSpec camera;
    camera.eye = Eigen::Vector3d(eyes[i][0], eyes[i][1], eyes[i][2]);
    camera.target = Eigen::Vector3d(0, 0, 0.9);
    camera.phase_s = phases[i];
    spec.cameras.push_back(camera);
  }
  spec.seed = 3;
  spec.duration_s = 8;
  spec.wand_path =
      "{type: lissajous, center: [0, 0, 1.15], amplitude: [1.2, 1.2, 0.7], frequency: [0.13, 0.171, 0.23]}";
  spec.wand_rotation = "{type: oscillate, amplitude: [1.3, 1.1, 3.0], frequency: [0.29, 0.37, 0.083]}";
  return spec;
}

// Ten ceiling cameras along an L-shaped corridor (8 m along x, then 6 m along y, 2 m wide); the
// wand is carried along it once, weaving and turning. No point is seen by all cameras.
inline SceneSpec corridor10() {
  SceneSpec spec;
  const auto centreline = [](double s) -> std::pair<Eigen::Vector2d, Eigen::Vector2d> {
    // Straight to x = 6.5, a quarter circle of radius 1.5 round (6.5, 1.5), then straight along y.
    const double straight = 6.5, arc = M_PI / 2 * 1.5;
    if (s < straight) return {Eigen::Vector2d(s, 0), Eigen::Vector2d(1, 0)};
    if (s < straight + arc) {
      const double a = (s - straight) / 1.5;
      return {Eigen::Vector2d(6.5 + 1.5 * std::sin(a), 1.5 - 1.5 * std::cos(a)),
              Eigen::Vector2d(std::cos(a), std::sin(a))};
    }
    return {Eigen::Vector2d(8.0, 1.5 + (s - straight - arc)), Eigen::Vector2d(0, 1)};
  };
  const double total = 6.5 + M_PI / 2 * 1.5 + 4.5;
  // Cameras every ~1.5 m of centreline, alternating sides, looking ahead and down.
  for (int i = 0; i < 10; ++i) {
    const double s = 0.2 + i * (total - 0.4) / 9.0;
    const auto [p, tangent] = centreline(s);
    const Eigen::Vector2d normal(-tangent.y(), tangent.x());
    const double side = (i % 2 == 0) ? 0.9 : -0.9;
    CameraSpec camera;
    const Eigen::Vector2d eye = p + side * normal - 0.3 * tangent;
    const auto [ahead, unused] = centreline(std::min(total, s + 1.2));
    camera.eye = Eigen::Vector3d(eye.x(), eye.y(), 2.6);
    camera.target =
        Eigen::Vector3d(ahead.x() - 0.4 * side * normal.x(), ahead.y() - 0.4 * side * normal.y(), 0.9);
    spec.cameras.push_back(camera);
  }
  spec.duration_s = 40;
  std::ostringstream points, times;
  points.precision(9);
  for (int k = 0; k <= 4000; ++k) {
    const double t = k * 0.01;
    const double s = total * (1 - std::cos(M_PI * t / 40.0)) / 2;
    const auto [p, tangent] = centreline(s);
    const Eigen::Vector2d normal(-tangent.y(), tangent.x());
    const Eigen::Vector2d q = p + 0.55 * std::sin(2 * M_PI * 0.21 * t) * normal;
    const double z = 1.2 + 0.5 * std::sin(2 * M_PI * 0.33 * t + 1);
    points << (k ? ", " : "") << "[" << q.x() << ", " << q.y() << ", " << z << "]";
    times << (k ? ", " : "") << t;
  }
  spec.wand_path = "{type: waypoints, points: [" + points.str() + "], times: [" + times.str() + "]}";
  spec.wand_rotation = "{type: oscillate, amplitude: [1.3, 1.1, 3.0], frequency: [0.29, 0.37, 0.083]}";
  return spec;
}

// `count` cameras on a 3 m circle 2.4-2.5 m high, all aimed at (0, 0, 0.9), frames phased 0.7 ms
// apart (asynchronous; bench_calibration uses 16); the wand waved through the middle for 20 s (2000 frames
// per camera).
inline SceneSpec ring(int count) {
  SceneSpec spec;
  for (int i = 0; i < count; ++i) {
    const double angle = 2 * M_PI * i / count;
    CameraSpec camera;
    camera.eye = Eigen::Vector3d(3.0 * std::cos(angle), 3.0 * std::sin(angle), 2.4 + 0.1 * (i % 2));
    camera.target = Eigen::Vector3d(0, 0, 0.9);
    camera.phase_s = 0.0007 * i;
    spec.cameras.push_back(camera);
  }
  spec.duration_s = 20;
  spec.wand_path =
      "{type: lissajous, center: [0, 0, 1.15], amplitude: [1.6, 1.6, 0.75], frequency: [0.13, 0.171, 0.23]}";
  spec.wand_rotation = "{type: oscillate, amplitude: [1.3, 1.1, 3.0], frequency: [0.29, 0.37, 0.083]}";
  return spec;
}

struct Measured {
  SolveResult result;
  double max_position_error_mm = 0;
  double max_rotation_error_deg = 0;
  double max_offset_error_ms = 0;
  double max_focal_error_rel = 0;
  // The same observations triangulated with the true cameras: the floor set by the noise.
  LengthStats truth_lengths;
  // The same, by the number of cameras that saw the wand's first marker: RMS length error (mm).
  std::map<std::size_t, std::pair<int, double>> truth_rms_by_cameras;
};

// Wand lengths triangulated freely from the observations in `result.residuals` through `models`.
// `rms_by_cameras`, if given, receives per number of cameras the sample count and RMS error (mm).
inline LengthStats free_lengths(const SolveResult& result, const std::vector<CameraModel>& models,
                                double length_m, int markers,
                                std::map<std::size_t, std::pair<int, double>>* rms_by_cameras = nullptr) {
  std::map<TimeNs, std::vector<std::vector<std::pair<int, Eigen::Vector2d>>>> by_sample;
  for (const auto& r : result.residuals) {
    auto& sample = by_sample[r.t_ns];
    sample.resize(static_cast<std::size_t>(markers));
    sample[static_cast<std::size_t>(r.marker)].emplace_back(r.camera, r.observed);
  }
  std::vector<double> errors;
  for (const auto& [t, sample] : by_sample) {
    std::vector<Eigen::Vector3d> points;
    for (const auto& views : sample) {
      std::vector<CameraModel> used;
      std::vector<Eigen::Vector2d> pixels;
      for (const auto& [camera, pixel] : views) {
        used.push_back(models[static_cast<std::size_t>(camera)]);
        pixels.push_back(pixel);
      }
      if (auto x = triangulate(used, pixels)) points.push_back(*x);
    }
    if (static_cast<int>(points.size()) == markers) {
      errors.push_back(((points.back() - points.front()).norm() - length_m) * 1e3);
      if (rms_by_cameras) {
        auto& [count, squared] = (*rms_by_cameras)[sample.front().size()];
        ++count;
        squared += errors.back() * errors.back();
      }
    }
  }
  if (rms_by_cameras)
    for (auto& [cameras, entry] : *rms_by_cameras) entry.second = std::sqrt(entry.second / entry.first);
  LengthStats stats;
  stats.count = static_cast<int>(errors.size());
  if (errors.empty()) return stats;
  for (double e : errors) stats.mean_error_mm += e / stats.count;
  for (double e : errors) {
    stats.sigma_mm += (e - stats.mean_error_mm) * (e - stats.mean_error_mm);
    stats.max_abs_error_mm = std::max(stats.max_abs_error_mm, std::abs(e));
  }
  stats.sigma_mm = std::sqrt(stats.sigma_mm / std::max(1, stats.count - 1));
  return stats;
}

// Camera `camera`'s feature frames over the whole scene, stamped from kEpoch.
inline std::vector<FeatureFrame> simulate_frames(const Scene& scene, std::size_t camera) {
  CameraSimulator simulator(scene, scene.cameras()[camera].calibration.id);
  std::vector<FeatureFrame> frames;
  for (std::int64_t k = 0; simulator.frame_time_ns(k) < scene.duration_ns(); ++k) {
    FeatureFrame frame = simulator.features(k);
    frame.stamp_ns += kEpoch;
    frames.push_back(std::move(frame));
  }
  return frames;
}

// An L-frame at the true origin (0.5 m arm along x, 0.3 m along y) seen by `spec`'s cameras for
// `duration_s`, triangulated with `result`'s cameras (in the solve's frame).
struct LFrameRecording {
  SystemCalibration solved;                           // `result`'s cameras
  Eigen::Vector3d up_hint = Eigen::Vector3d::Zero();  // their mean centre
  std::vector<Eigen::Vector3d> points;
};

inline LFrameRecording record_lframe(const SolveResult& result, SceneSpec spec, double duration_s) {
  LFrameRecording out;
  for (const auto& camera : result.cameras) {
    out.solved.cameras.push_back({camera.id, camera.intrinsics, camera.T_world_cam, false, false, {}});
    out.up_hint += camera.T_world_cam->t / static_cast<double>(result.cameras.size());
  }
  spec.wand_path.clear();
  spec.static_markers = {{0, 0, 0}, {0.5, 0, 0}, {0, 0.3, 0}};
  spec.duration_s = duration_s;
  const Scene lframe = Scene::from_yaml_string(scene_yaml(spec));
  std::vector<FeatureFrame> frames;
  for (std::size_t c = 0; c < lframe.cameras().size(); ++c) {
    auto camera_frames = simulate_frames(lframe, c);
    frames.insert(frames.end(), camera_frames.begin(), camera_frames.end());
  }
  out.points = triangulate_static_markers(out.solved, frames);
  return out;
}

inline std::vector<CameraWandTrack> simulate_tracks(const Scene& scene, const WandDefinition& wand,
                                                    const std::vector<CameraIntrinsics>& intrinsics) {
  std::vector<CameraWandTrack> tracks;
  for (std::size_t c = 0; c < scene.cameras().size(); ++c)
    tracks.push_back(extract_wand_track(scene.cameras()[c].calibration.id, simulate_frames(scene, c),
                                        intrinsics[c], wand));
  return tracks;
}

// Solves and compares with the truth. `intrinsics_error` perturbs the intrinsics given to the
// solver; `edit`, if given, changes the simulated tracks before the solve (deliberate damage);
// `edit_camera`, if given, changes each camera as given to the solver (e.g. nominal intrinsics).
inline Measured solve_and_measure(const Scene& scene, const WandDefinition& wand, const SolveOptions& options,
                                  double intrinsics_error = 0.0,
                                  const std::function<void(std::vector<CameraWandTrack>&)>& edit = {},
                                  const std::function<void(CameraCalibration&)>& edit_camera = {}) {
  std::vector<CameraCalibration> given;
  std::vector<CameraIntrinsics> intrinsics;
  for (const auto& config : scene.cameras()) {
    CameraCalibration camera = config.calibration;
    camera.T_world_cam.reset();
    auto& k = camera.intrinsics;
    k.fx *= 1 + intrinsics_error;
    k.fy *= 1 - intrinsics_error;
    k.cx += intrinsics_error * k.width * 0.2;
    k.cy -= intrinsics_error * k.height * 0.2;
    for (auto& d : k.distortion) d *= 1 + intrinsics_error;
    if (edit_camera) edit_camera(camera);
    given.push_back(camera);
    intrinsics.push_back(k);
  }
  auto tracks = simulate_tracks(scene, wand, intrinsics);
  if (edit) edit(tracks);
  Measured measured;
  measured.result = solve_wand_calibration(given, tracks, wand, options);
  const auto& result = measured.result;
  std::vector<Eigen::Vector3d> estimated, truth;
  std::vector<std::size_t> index;
  for (std::size_t c = 0; c < result.cameras.size(); ++c)
    if (result.cameras[c].T_world_cam) {
      estimated.push_back(result.cameras[c].T_world_cam->t);
      truth.push_back(scene.cameras()[c].calibration.T_world_cam->t);
      index.push_back(c);
    }
  std::vector<CameraModel> true_models;
  for (const auto& config : scene.cameras()) true_models.push_back(config.calibration.model());
  measured.truth_lengths =
      free_lengths(result, true_models, wand.length(), static_cast<int>(wand.marker_count()),
                   &measured.truth_rms_by_cameras);
  if (estimated.size() < 3) return measured;
  const RigidTransform T_true_est = fit_rigid_transform(estimated, truth).value();
  std::size_t reference = 0;
  for (std::size_t c = 0; c < result.cameras.size(); ++c)
    if (result.cameras[c].id == result.reference_camera) reference = c;
  const double true_reference_offset = static_cast<double>(scene.cameras()[reference].clock_offset_ns) * 1e-9;
  for (std::size_t i = 0; i < index.size(); ++i) {
    const std::size_t c = index[i];
    const RigidTransform aligned = T_true_est * *result.cameras[c].T_world_cam;
    const RigidTransform& true_pose = *scene.cameras()[c].calibration.T_world_cam;
    const double position_mm = (aligned.t - true_pose.t).norm() * 1e3;
    const double rotation_deg = true_pose.q.angularDistance(aligned.q) * 180 / M_PI;
    const double true_offset =
        static_cast<double>(scene.cameras()[c].clock_offset_ns) * 1e-9 - true_reference_offset;
    const double offset_ms = std::abs(result.cameras[c].time_offset_s - true_offset) * 1e3;
    const auto& k_true = scene.cameras()[c].calibration.intrinsics;
    const auto& k = result.cameras[c].intrinsics;
    const double focal_rel = std::max(std::abs(k.fx / k_true.fx - 1), std::abs(k.fy / k_true.fy - 1));
    measured.max_position_error_mm = std::max(measured.max_position_error_mm, position_mm);
    measured.max_rotation_error_deg = std::max(measured.max_rotation_error_deg, rotation_deg);
    measured.max_offset_error_ms = std::max(measured.max_offset_error_ms, offset_ms);
    measured.max_focal_error_rel = std::max(measured.max_focal_error_rel, focal_rel);
  }
  return measured;
}

inline void print(const char* name, const Measured& m) {
  const auto& r = m.result;
  std::printf(
      "[%s] cameras %d/%zu, rms %.4f px (2D, interpolated), raw rms %.4f px/axis, position max %.4f mm, "
      "rotation max %.5f deg, wand length mean %.4f mm "
      "sigma %.4f mm max %.4f mm (%d samples; true cameras: mean %.4f sigma %.4f), offset max err %.4f ms, "
      "focal max err %.5f%%, %.2f s, %d iterations\n",
      name, r.calibrated_count(), r.cameras.size(), r.rms_px, r.raw_rms_axis_px, m.max_position_error_mm,
      m.max_rotation_error_deg, r.lengths.mean_error_mm, r.lengths.sigma_mm, r.lengths.max_abs_error_mm,
      r.lengths.count, m.truth_lengths.mean_error_mm, m.truth_lengths.sigma_mm, m.max_offset_error_ms,
      m.max_focal_error_rel * 100, r.seconds, r.iterations);
  for (const auto& e : r.errors) std::printf("  error: %s\n", e.c_str());
}

// How much of the wand's path the cameras cover: the share of the grid instants that became a
// sample (all markers seen by >= 2 cameras), cameras per sample, and wand frames per camera.
inline void print_coverage(const Measured& measured, const Scene& scene) {
  const SolveResult& result = measured.result;
  const double instants = static_cast<double>(scene.duration_ns()) * 1e-9 * 100;  // 100 Hz grid
  std::map<int, int> by_count;
  double mean = 0;
  for (const auto& sample : result.samples) {
    ++by_count[sample.cameras];
    mean += sample.cameras;
  }
  if (!result.samples.empty()) mean /= static_cast<double>(result.samples.size());
  std::printf("  coverage: %zu samples (%.1f%% of the path), %.2f cameras per sample;", result.samples.size(),
              100.0 * static_cast<double>(result.samples.size()) / instants, mean);
  for (const auto& [count, n] : by_count) std::printf(" %d:%d", count, n);
  std::printf("\n  wand frames per camera:");
  for (const auto& camera : result.cameras) std::printf(" %s %d", camera.id.c_str(), camera.wand_frames);
  std::printf("\n  length RMS with the true cameras by cameras seeing the sample:");
  for (const auto& [cameras, entry] : measured.truth_rms_by_cameras)
    std::printf(" %zu: %.3f mm (%d)", cameras, entry.second, entry.first);
  std::printf("\n");
}

inline std::string report_summary_for_test(const SolveResult& result) {
  return report_summary(result);
}

}  // namespace panoptes::calib::testing
