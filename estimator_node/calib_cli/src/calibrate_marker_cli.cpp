// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate marker`: a single 7-LED marker moved in front of one camera (seed 004
// §3: ~500 frames at a short distance, turning it), its FeatureFrame JSONL, the camera's intrinsics
// and the measured |M0 M3| -> the LED positions as a `led7` body.
#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "calibrate_marker_cli.h"
#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/estimator/led_marker.h"
#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/records.h"

namespace panoptes::estimator {

namespace {

// The frames usable for the calibration, and why the others were left out.
struct IdentifiedMarkerFrames {
  std::vector<LedPoints> observations;
  int other_camera = 0, too_few = 0, no_cluster = 0, unidentified = 0, l42 = 0;
};

// Frames of that camera -> one cluster of seven -> model-free identification; L42 frames are
// left out (§3: they cannot be assigned without the 3D structure).
IdentifiedMarkerFrames identify_marker_frames(const std::vector<FeatureFrame>& frames,
                                              const std::string& camera_id, const CameraModel& model,
                                              double line_tolerance) {
  IdentifiedMarkerFrames identified;
  for (const FeatureFrame& frame : frames) {
    if (frame.camera_id != camera_id) {
      ++identified.other_camera;
      continue;
    }
    std::vector<Eigen::Vector2d> points;
    for (const Blob& blob : frame.blobs) {
      const Eigen::Vector2d p = model.pixel_to_normalized(Eigen::Vector2d(blob.x, blob.y));
      if (p.allFinite()) points.push_back(p);
    }
    if (points.size() < std::size_t(kLedCount)) {
      ++identified.too_few;
      continue;
    }
    std::vector<int> chosen;
    for (const auto& cluster : cluster_led_points(points, int(points.size()) / kLedCount)) {
      if (cluster.size() != std::size_t(kLedCount)) continue;
      if (!chosen.empty()) {  // two complete clusters: not a single marker in view
        chosen.clear();
        break;
      }
      chosen = cluster;
    }
    if (chosen.empty()) {
      ++identified.no_cluster;
      continue;
    }
    LedPoints p;
    for (int i = 0; i < kLedCount; ++i) p[i] = points[chosen[i]];
    const auto id = identify_led_pattern(p, line_tolerance);
    if (!id) {
      ++identified.unidentified;
      continue;
    }
    if (id->alternative) {
      ++identified.l42;
      continue;
    }
    LedPoints ordered;
    for (int i = 0; i < kLedCount; ++i) ordered[i] = p[id->index[i]];
    identified.observations.push_back(ordered);
  }
  return identified;
}

// `calibrate marker`'s command line.
struct MarkerArgs {
  std::string program;
  std::string calibration_file, camera_id, features_file, name = "led_marker", out_file;
  double d03 = 0;
  LedCalibrationOptions calib;
  double line_tolerance = 0.02;
};

// Parses `calibrate marker`; an exit code if the program should stop (--help, a bad option).
std::optional<int> parse_marker_args(int argc, char** argv, MarkerArgs& args) {
  args.program = argc > 0 ? argv[0] : "calibrate marker";
  CLI::App app{
      "Self-calibrates a 7-LED marker (seed 004 section 3) from one camera's recorded features: the\n"
      "marker alone in view, moved and turned at a short distance; |M0 M3| measured by hand.",
      args.program};
  app.add_option("--calibration", args.calibration_file, "calibration YAML with the camera's intrinsics")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--camera", args.camera_id, "camera id (frames of other cameras are ignored)")->required();
  app.add_option("--in-features", args.features_file, "FeatureFrame JSON Lines recorded from that camera")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--d03", args.d03, "measured distance |M0 M3| between the end LEDs of the long arm, metres")
      ->required()
      ->check(CLI::Validator(
          [](std::string& value) {
            try {
              return std::stod(value) > 0 ? std::string()
                                          : "must be a positive distance in metres, got " + value;
            } catch (const std::exception&) {
              return "not a number: " + value;
            }
          },
          "METRES"));
  app.add_option("--name", args.name, "body name written to --out")->capture_default_str();
  app.add_option("--out", args.out_file, "bodies YAML to write (one led7 body)")->required();
  app.add_option("--subsample", args.calib.subsample, "initialisation uses every n-th frame (paper: 50)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--line-tolerance", args.line_tolerance,
                 "LED identification line tolerance (fraction of the marker size)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 0.2));
  return parse_command_line(app, argc, argv);
}

int fail(const MarkerArgs& args, int code, const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", args.program.c_str(), message.c_str());
  return code;
}

// The calibrated marker printed and written to --out as a led7 body.
int write_marker(const MarkerArgs& args, const LedCalibrationResult& result) {
  BodyDefinition body;
  body.name = args.name;
  body.kind = BodyKind::kLed7;
  for (int i = 0; i < kLedCount; ++i) {
    const Eigen::Vector3d& m = result.leds[i];
    std::printf("  M%d  %9.3f %9.3f %9.3f mm  (initialisation %9.3f %9.3f %9.3f)\n", i, m.x() * 1e3,
                m.y() * 1e3, m.z() * 1e3, result.initial[i].x() * 1e3, result.initial[i].y() * 1e3,
                result.initial[i].z() * 1e3);
    body.markers.push_back(m);
  }
  try {
    const auto led_model = LedMarkerModel::from_body(body);
    std::printf("%s: cross-ratio CR(M0, M3; M2, M1) = %.4f\n", args.program.c_str(), led_model.cross_ratio());
    save_bodies({body}, args.out_file);
  } catch (const std::exception& e) {
    return fail(args, kExitFailure, e.what());
  }
  std::printf("%s: wrote body '%s' to %s\n", args.program.c_str(), args.name.c_str(), args.out_file.c_str());
  return kExitOk;
}

}  // namespace

int run_calibrate_marker(int argc, char** argv) {
  MarkerArgs args;
  if (auto code = parse_marker_args(argc, argv, args)) return *code;
  const std::string& program = args.program;
  SystemCalibration system;
  try {
    system = load_calibration(args.calibration_file);
  } catch (const std::exception& e) {
    return fail(args, kExitBadInput, e.what());
  }
  const CameraCalibration* camera = system.find(args.camera_id);
  if (!camera)
    return fail(args, kExitBadInput, args.calibration_file + ": no camera '" + args.camera_id + "'");
  const CameraModel model(camera->intrinsics, RigidTransform{});

  std::vector<FeatureFrame> frames;
  std::vector<std::string> errors;
  try {
    frames = read_feature_frames(args.features_file, &errors);
  } catch (const std::exception& e) {
    return fail(args, kExitBadInput, e.what());
  }
  for (std::size_t i = 0; i < errors.size() && i < 5; ++i)
    std::fprintf(stderr, "%s: skipped %s\n", program.c_str(), errors[i].c_str());
  std::printf("%s: %zu frames read from %s (%zu malformed lines skipped)\n", program.c_str(), frames.size(),
              args.features_file.c_str(), errors.size());

  const IdentifiedMarkerFrames identified =
      identify_marker_frames(frames, args.camera_id, model, args.line_tolerance);
  const auto& observations = identified.observations;
  std::printf(
      "%s: camera '%s': %zu frames identified; skipped: %d other camera, %d fewer than 7 blobs, %d without "
      "a single 7-blob cluster, %d not identified, %d L42 (ambiguous without the model)\n",
      program.c_str(), args.camera_id.c_str(), observations.size(), identified.other_camera,
      identified.too_few, identified.no_cluster, identified.unidentified, identified.l42);
  if (observations.size() < 20)
    return fail(args, kExitBadInput,
                args.features_file + ": only " + std::to_string(observations.size()) +
                    " usable frames of camera '" + args.camera_id +
                    "' (need at least 20; seed 004 uses ~500)");

  LedCalibrationResult result;
  try {
    std::printf("%s: calibrating (initialisation from every %d-th frame, then refinement)...\n",
                program.c_str(), args.calib.subsample);
    std::fflush(stdout);
    result = calibrate_led_marker(observations, args.d03, args.calib);
  } catch (const std::exception& e) {
    return fail(args, kExitFailure, e.what());
  }
  const double f = 0.5 * (camera->intrinsics.fx + camera->intrinsics.fy);
  std::printf(
      "%s: %d initialisation pairs, %d refinement iterations, %d frames with a pose, reprojection RMS %.3f "
      "px\n",
      program.c_str(), result.pairs_used, result.iterations, result.frames_used, result.rms * f);
  return write_marker(args, result);
}

}  // namespace panoptes::estimator
