// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate ...` (docs/calibration.md).
#include "panoptes/calib/calibrate_cli.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "calibrate_history_cli.h"
#include "calibrate_marker_cli.h"
#include "panoptes/calib/intrinsics.h"
#include "panoptes/calib/point_import.h"
#include "panoptes/calib/report.h"
#include "panoptes/calib/scale_check.h"
#include "panoptes/calib/wand.h"
#include "panoptes/calib/wand_solver.h"
#include "panoptes/calib/world_frame.h"
#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/calibration_history.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/glob.h"
#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/records.h"

namespace panoptes::calib {

namespace {

constexpr const char* kUsage =
    "estimator_node calibrate <subcommand> [options]   (docs/calibration.md)\n"
    "\n"
    "subcommands:\n"
    "  capture     record FeatureFrames from all cameras over DDS while the wand is waved\n"
    "  intrinsics  one camera's intrinsics from chessboard images (OpenCV)\n"
    "  solve       extrinsics (and optionally intrinsics, clock offsets) from wand features\n"
    "  world       set the world frame from an L-frame, markers on the floor, or the wand on the floor\n"
    "  import-points  a single-point recording of synchronised cameras (MultiCamSelfCal points.dat) as\n"
    "              features and nominal cameras for `solve --wand 0`\n"
    "  marker      self-calibration of a 7-LED marker (seed 004 §3)\n"
    "  surface     homographies of a wall's cameras for surface mode (docs/surface.md)\n"
    "  history     the versions of a calibration file (kept beside it in <file>.history/)\n"
    "  revert      restore an earlier version of a calibration file, byte for byte\n"
    "  accept      mark an automatic change to a calibration file as reviewed\n"
    "\n"
    "Each subcommand answers --help.\n";

int bad_input(const std::string& program, const std::string& reason) {
  std::fprintf(stderr, "%s: %s\n", program.c_str(), reason.c_str());
  return kExitBadInput;
}

void say(const std::string& line) {
  std::fprintf(stderr, "%s\n", line.c_str());
}

// Reads FeatureFrame files; groups by camera. Malformed lines are counted and named.
std::map<std::string, std::vector<FeatureFrame>> read_features(const std::vector<std::string>& files,
                                                               std::string& error) {
  std::map<std::string, std::vector<FeatureFrame>> by_camera;
  for (const auto& file : files) {
    std::vector<std::string> errors;
    std::vector<FeatureFrame> frames;
    try {
      frames = read_feature_frames(file, &errors);
    } catch (const std::exception& e) {
      error = e.what();
      return {};
    }
    if (!errors.empty())
      say(std::string(file)
              .append(": ")
              .append(std::to_string(errors.size()))
              .append(" malformed line(s) skipped, first: ")
              .append(errors.front()));
    for (auto& frame : frames) by_camera[frame.camera_id].push_back(std::move(frame));
  }
  return by_camera;
}

int run_intrinsics(int argc, char** argv) {
  std::string images, board, out, id = "cam0";
  double square = 0;
  CLI::App app{"calibrate intrinsics: one camera's intrinsics and distortion from chessboard images (OpenCV)",
               "estimator_node calibrate intrinsics"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--images", images, "glob(3) pattern of the images, quoted (e.g. 'left[0-9]*.jpg')")
      ->required();
  app.add_option("--board", board, "inner corners, <cols>x<rows> (e.g. 9x6)")->required();
  app.add_option("--square", square, "square size, m")->required();
  app.add_option("--out", out, "calibration YAML to write (the camera is added or replaced)")->required();
  app.add_option("--id", id, "camera id in the YAML")->capture_default_str();
  if (auto exit = parse_command_line(app, argc, argv)) return *exit;
  const std::string program = app.get_name();
  ChessboardOptions options;
  if (std::sscanf(board.c_str(), "%dx%d", &options.cols, &options.rows) != 2)
    return bad_input(program, "--board: expected <cols>x<rows>, got '" + board + "'");
  options.square_m = square;
  options.progress = say;
  std::vector<std::filesystem::path> paths;
  try {
    paths = glob_files(images);
  } catch (const std::runtime_error& error) {
    return bad_input(program, std::string("--images: ") + error.what());
  }
  if (paths.empty()) return bad_input(program, "--images: no file matches '" + images + "'");
  const ChessboardResult result = calibrate_chessboard(paths, options);
  if (!result.error.empty()) return bad_input(program, result.error);
  SystemCalibration calibration;
  if (std::filesystem::exists(out)) {
    try {
      calibration = load_calibration(out);
    } catch (const std::exception& e) {
      return bad_input(program, std::string("--out exists but is not a calibration file: ") + e.what());
    }
  }
  bool replaced = false;
  for (auto& camera : calibration.cameras)
    if (camera.id == id) {
      camera.intrinsics = result.intrinsics;
      camera.T_world_cam.reset();
      replaced = true;
    }
  if (!replaced) calibration.cameras.push_back({id, result.intrinsics, std::nullopt, false, false, {}});
  save_calibration(calibration, out);
  const auto& k = result.intrinsics;
  std::printf("%s: board found in %zu of %zu images; RMS reprojection error %.4f px\n", id.c_str(),
              result.used.size(), paths.size(), result.rms_px);
  std::printf("K: fx %.3f fy %.3f cx %.3f cy %.3f; distortion %.5f %.5f %.5f %.5f %.5f\n", k.fx, k.fy, k.cx,
              k.cy, k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3], k.distortion[4]);
  for (std::size_t i = 0; i < result.used.size(); ++i)
    std::printf("  %s: %.3f px\n", result.used[i].filename().string().c_str(), result.per_image_rms_px[i]);
  std::printf("wrote %s\n", out.c_str());
  return kExitOk;
}

// `calibrate import-points`: MultiCamSelfCal's points.dat (and Res.dat) as FeatureFrames and a
// cameras file with nominal intrinsics, for `calibrate solve --wand 0`.
int run_import_points(int argc, char** argv) {
  std::string points_file, resolutions_file, size, features_out, cameras_out, prefix = "cam";
  double focal = 0, rate = 100;
  CLI::App app{
      "calibrate import-points: a single bright point seen by synchronised cameras (MultiCamSelfCal "
      "points.dat: 3 rows x, y, 1 per camera, NaN where unseen, one column per frame)",
      "estimator_node calibrate import-points"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--points", points_file, "points.dat")->required();
  auto* res = app.add_option("--resolutions", resolutions_file, "Res.dat: 'width height' per camera");
  auto* size_option = app.add_option("--size", size, "image size of every camera, <width>x<height>");
  res->excludes(size_option);
  app.add_option("--focal", focal, "nominal focal length, px (lens focal length / pixel pitch)")->required();
  app.add_option("--rate", rate, "frame rate of the recording, Hz (stamps only)")->capture_default_str();
  app.add_option("--id-prefix", prefix, "camera ids are <prefix>0, <prefix>1, ...")->capture_default_str();
  app.add_option("--out-features", features_out, "FeatureFrame JSONL to write")->required();
  app.add_option("--out-cameras", cameras_out, "cameras YAML to write (intrinsics marked nominal: true)")
      ->required();
  if (auto exit = parse_command_line(app, argc, argv, [&] {
        if (resolutions_file.empty() && size.empty())
          throw CLI::ValidationError("--resolutions or --size", "one of them is required");
      }))
    return *exit;
  const std::string program = app.get_name();
  if (!(focal > 0)) return bad_input(program, "--focal: must be positive");
  if (!(rate > 0)) return bad_input(program, "--rate: must be positive");
  PointTable table;
  std::vector<std::pair<int, int>> sizes;
  try {
    table = read_multicam_points(points_file);
    if (!resolutions_file.empty()) sizes = read_multicam_resolutions(resolutions_file);
  } catch (const std::exception& e) {
    return bad_input(program, e.what());
  }
  if (!size.empty()) {
    int width = 0, height = 0;
    if (std::sscanf(size.c_str(), "%dx%d", &width, &height) != 2 || width <= 0 || height <= 0)
      return bad_input(program, "--size: expected <width>x<height>, got '" + size + "'");
    sizes.assign(table.cameras.size(), {width, height});
  }
  if (sizes.size() != table.cameras.size())
    return bad_input(program, resolutions_file + ": " + std::to_string(sizes.size()) + " cameras, " +
                                  points_file + " has " + std::to_string(table.cameras.size()));
  SystemCalibration cameras;
  std::vector<std::string> ids;
  for (std::size_t c = 0; c < table.cameras.size(); ++c) {
    ids.push_back(prefix + std::to_string(c));
    cameras.cameras.push_back(nominal_camera(ids.back(), sizes[c].first, sizes[c].second, focal));
  }
  const auto frames = point_feature_frames(table, ids, rate, 0);
  std::ofstream jsonl(features_out);
  if (!jsonl) return bad_input(program, features_out + ": cannot write");
  for (const auto& frame : frames) jsonl << to_json_line(frame) << "\n";
  jsonl.close();
  save_calibration(cameras, cameras_out);
  std::printf("%zu cameras x %d frames; wrote %s and %s (nominal intrinsics, f = %.1f px)\n",
              table.cameras.size(), table.frames, features_out.c_str(), cameras_out.c_str(), focal);
  std::printf(
      "next: estimator_node calibrate solve --cameras %s --in-features %s --wand 0 --out calibration.yaml\n",
      cameras_out.c_str(), features_out.c_str());
  return kExitOk;
}

int run_solve(int argc, char** argv) {
  std::string cameras_file, wand_text, out, reference;
  std::vector<std::string> feature_files;
  SolveOptions options;
  CLI::App app{"calibrate solve: camera poses from a waved wand (seed 003 Ch. 3, seed 000 §4.5.8)",
               "estimator_node calibrate solve"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--cameras", cameras_file, "calibration YAML with every camera's intrinsics")->required();
  app.add_option("--in-features", feature_files,
                 "FeatureFrame JSONL files (from `calibrate capture` or camera_node)")
      ->required()
      ->expected(1, -1);
  app.add_option("--wand", wand_text,
                 "marker positions along the wand, m, e.g. 0,0.18,0.5 (one value: a single LED)")
      ->required();
  app.add_option("--out", out, "calibration YAML to write; the report goes next to it")->required();
  auto* refine = app.add_flag(
      "--refine-intrinsics", options.refine_intrinsics,
      "refine fx, fy, cx, cy and all five distortion terms (without it, the focal length, k1 and k2 are "
      "refined automatically when the cameras file marks them nominal, and fx, fy, cx, cy, k1, k2 when the "
      "first adjustment shows they do not fit)");
  bool fixed_intrinsics = false;
  app.add_flag("--fixed-intrinsics", fixed_intrinsics,
               "never refine the intrinsics (no automatic refinement)")
      ->excludes(refine);
  app.add_flag("--time-offsets", options.time_offsets, "estimate a clock offset per camera");
  app.add_option("--reference", reference, "camera whose pose fixes the gauge")
      ->default_str("best connected");
  app.add_option("--sample-rate", options.sample_rate_hz, "wand instants per second")
      ->default_str("fastest camera");
  app.add_option("--min-frames", options.min_camera_frames, "wand frames a camera needs")
      ->capture_default_str();
  app.add_option("--min-pair-samples", options.min_pair_samples, "common samples for a relative pose")
      ->capture_default_str();
  app.add_option(
         "--alternation", options.alternation_iterations,
         "seed 003 §3.3.2 alternation with this many iterations instead of bundle adjustment (comparison)")
      ->default_str("off");
  if (auto exit = parse_command_line(app, argc, argv)) return *exit;
  const std::string program = app.get_name();
  options.reference_camera = reference;
  options.auto_intrinsics = !fixed_intrinsics;
  WandDefinition wand;
  try {
    wand = parse_wand(wand_text);
  } catch (const std::exception& e) {
    return bad_input(program, e.what());
  }
  SystemCalibration given;
  try {
    given = load_calibration(cameras_file);
  } catch (const std::exception& e) {
    return bad_input(program, e.what());
  }
  std::string error;
  auto by_camera = read_features(feature_files, error);
  if (!error.empty()) return bad_input(program, error);
  for (const auto& [id, frames] : by_camera)
    if (!given.find(id))
      say(std::string("warning: ")
              .append(std::to_string(frames.size()))
              .append(" frames of camera '")
              .append(id)
              .append("' ignored: not in ")
              .append(cameras_file));
  std::vector<CameraWandTrack> tracks;
  for (const auto& camera : given.cameras) {
    const auto found = by_camera.find(camera.id);
    if (found == by_camera.end()) continue;
    tracks.push_back(extract_wand_track(camera.id, found->second, camera.intrinsics, wand));
    const auto& c = tracks.back().counters;
    say(std::string("camera ")
            .append(camera.id)
            .append(": ")
            .append(std::to_string(c.frames))
            .append(" frames, wand identified in ")
            .append(std::to_string(c.identified)));
  }
  options.progress = say;
  const SolveResult result = solve_wand_calibration(given.cameras, tracks, wand, options);
  try {
    write_calibration_text(out, calibration_yaml(result), change_because("calibrate solve"));
    const auto files = write_report(result, out);
    std::cout << report_summary(result);
    std::cout << "wrote " << out;
    for (const auto& file : files) std::cout << ", " << file.filename().string();
    std::cout << "\n";
  } catch (const InputError& e) {  // the calibration file cannot be written
    return bad_input(program, e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
    return kExitFailure;
  }
  if (!result.ok()) {
    for (const auto& e : result.errors) std::fprintf(stderr, "%s: %s\n", program.c_str(), e.c_str());
    return kExitFailure;
  }
  return kExitOk;
}

// `calibrate world --wand-floor`: the floor plane fitted to the wand's positions (world_frame.h).
int run_wand_floor(const std::string& program, SystemCalibration& calibration,
                   const std::string& calibration_file, const std::vector<std::string>& feature_files,
                   const std::vector<FeatureFrame>& frames, const WandDefinition& wand, bool unscaled,
                   const WandFloorOptions& options, const std::string& out, double scale_tolerance) {
  const WandFloorResult result = wand_floor_frame(calibration, frames, wand, unscaled, options);
  std::string summary = wand_floor_summary(result);
  // On a metric calibration the wand's known length checks its scale (an unscaled one takes it).
  if (!unscaled && result.T_new_old)
    summary += scale_check_summary(check_scale({result.median_length_m}, {wand.length()}, scale_tolerance),
                                   "the wand's median length on the floor against --wand", scale_tolerance);
  if (!result.T_new_old) {
    std::fprintf(stderr, "%s", summary.c_str());
    std::string files;
    for (const auto& file : feature_files) files += (files.empty() ? "" : " ") + file;
    std::fprintf(stderr, "%s: %s: no world frame from the wand on the floor (cameras from %s): %s\n",
                 program.c_str(), files.c_str(), calibration_file.c_str(), result.error.c_str());
    return kExitFailure;
  }
  apply_world_transform(calibration, *result.T_new_old, result.scale);
  const std::filesystem::path out_path(out);
  const auto report_path = out_path.parent_path() / (out_path.stem().string() + ".world.txt");
  try {
    write_calibration_text(out, calibration_to_yaml(calibration),
                           change_because("calibrate world (wand on the floor)"));
    std::ofstream report(report_path);
    if (!report) throw std::runtime_error(report_path.string() + ": cannot write");
    report << "calibrate world --wand-floor: " << calibration_file << " -> " << out << "\n"
           << "floor offset " << options.floor_offset_m << " m\n"
           << summary;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
    return kExitFailure;
  }
  std::printf("%s", summary.c_str());
  std::printf("wrote %s, %s\n", out.c_str(), report_path.filename().string().c_str());
  return kExitOk;
}

// `calibrate world`'s command line.
struct WorldArgs {
  std::string program;
  std::string calibration_file, out, lframe, wand_text;
  std::vector<std::string> feature_files;
  bool floor = false, wand_floor = false;
  WandFloorOptions wand_floor_options;
  double scale_tolerance = kScaleTolerance;
};

// Parses `calibrate world`; an exit code if the program should stop (--help, a bad option).
std::optional<int> parse_world_args(int argc, char** argv, WorldArgs& args) {
  CLI::App app{
      "calibrate world: world frame (z up) from an L-frame, markers on the floor, or the wand laid on the "
      "floor",
      "estimator_node calibrate world"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--calibration", args.calibration_file, "calibration YAML from `calibrate solve`")
      ->required();
  app.add_option("--in-features", args.feature_files,
                 "a short recording of the static markers, or of the wand on the floor (JSONL)")
      ->required()
      ->expected(1, -1);
  auto* lframe_option =
      app.add_option("--lframe", args.lframe,
                     "L-frame of 3 markers: '<x arm m>,<y arm m>' (or 'auto': the longer arm "
                     "is x); on an unscaled (single-light) calibration the arms set the scale");
  auto* floor_option =
      app.add_flag("--floor", args.floor, "markers (>= 3) lying on the floor: z = their plane's normal");
  auto* wand_floor_option = app.add_flag(
      "--wand-floor", args.wand_floor,
      "the wand (--wand) laid on the floor at several places: z = the plane of its positions, origin = "
      "its first marker at the first rest, x = along it; on an unscaled calibration its length sets the "
      "scale");
  auto* wand_option =
      app.add_option("--wand", args.wand_text, "with --wand-floor: marker positions along the wand, m");
  app.add_option("--floor-offset", args.wand_floor_options.floor_offset_m,
                 "with --wand-floor: height of the marker centres above the floor, m (a marker's radius)")
      ->capture_default_str();
  app.add_option("--scale-tolerance", args.scale_tolerance,
                 "relative: warn when the L-frame's arms (--lframe x,y) or the wand's length (--wand-floor) "
                 "as the calibration measures them are off their known lengths by more (0.001 = 1000 ppm)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  lframe_option->excludes(floor_option);
  wand_floor_option->excludes(lframe_option)->excludes(floor_option)->needs(wand_option);
  wand_option->needs(wand_floor_option);
  app.add_option("--out", args.out, "calibration YAML to write")->required();
  args.program = app.get_name();
  return parse_command_line(app, argc, argv, [&] {
    if (args.lframe.empty() && !args.floor && !args.wand_floor)
      throw CLI::ValidationError("--lframe, --floor or --wand-floor", "one of them is required");
  });
}

// `calibrate world --lframe` or `--floor`: static markers triangulated, the frame fitted to them.
int run_static_marker_world(const WorldArgs& args, SystemCalibration& calibration, bool unscaled,
                            const std::vector<FeatureFrame>& frames) {
  const std::string& program = args.program;
  const auto points = triangulate_static_markers(calibration, frames);
  say("triangulated " + std::to_string(points.size()) + " static markers");
  Eigen::Vector3d up_hint = Eigen::Vector3d::Zero();
  int count = 0;
  for (const auto& camera : calibration.cameras)
    if (camera.T_world_cam) {
      up_hint += camera.T_world_cam->t;
      ++count;
    }
  if (count == 0) return bad_input(program, args.calibration_file + ": no camera has T_world_cam");
  up_hint /= count;
  std::optional<RigidTransform> T_new_old;
  double scale = 1.0;
  std::string error;
  if (args.floor) {
    T_new_old = floor_frame(points, up_hint, &error);
  } else {
    double x_arm = 0, y_arm = 0;
    if (args.lframe != "auto" &&
        (std::sscanf(args.lframe.c_str(), "%lf,%lf", &x_arm, &y_arm) != 2 || x_arm <= 0 || y_arm <= 0))
      return bad_input(program,
                       "--lframe: expected '<x arm m>,<y arm m>' or 'auto', got '" + args.lframe + "'");
    T_new_old = lframe_frame(points, up_hint, x_arm, y_arm, &error, unscaled ? &scale : nullptr);
  }
  if (!T_new_old) {
    std::fprintf(stderr, "%s: %s\n", program.c_str(), error.c_str());
    return kExitFailure;
  }
  apply_world_transform(calibration, *T_new_old, scale);
  write_calibration_text(args.out, calibration_to_yaml(calibration), change_because("calibrate world"));
  std::printf("world frame set from %s (%zu markers); wrote %s\n", args.floor ? "the floor" : "the L-frame",
              points.size(), args.out.c_str());
  if (unscaled) std::printf("metric scale set from the L-frame's arms: %.6f m per unit\n", scale);
  for (const auto& p : points) {
    const Eigen::Vector3d q = scale * T_new_old->apply(p);
    std::printf("  marker at [%.4f, %.4f, %.4f] m\n", q.x(), q.y(), q.z());
  }
  if (!unscaled && !args.floor && args.lframe != "auto") {
    double x_arm = 0, y_arm = 0;
    std::sscanf(args.lframe.c_str(), "%lf,%lf", &x_arm, &y_arm);
    const ScaleCheck check = check_scale(lframe_arm_lengths(points, *T_new_old, x_arm, y_arm), {x_arm, y_arm},
                                         args.scale_tolerance);
    std::printf(
        "%s",
        scale_check_summary(check, "the L-frame's arms against --lframe", args.scale_tolerance).c_str());
  }
  return kExitOk;
}

int run_world(int argc, char** argv) {
  WorldArgs args;
  if (auto exit = parse_world_args(argc, argv, args)) return *exit;
  const std::string& program = args.program;
  WandDefinition wand;
  if (args.wand_floor) {
    try {
      wand = parse_wand(args.wand_text);
    } catch (const std::exception& e) {
      return bad_input(program, e.what());
    }
    if (wand.marker_count() < 2)
      return bad_input(program,
                       "--wand-floor needs a wand of two or more markers (its direction sets x, its "
                       "length the scale of an unscaled calibration); --wand '" +
                           args.wand_text + "' is a single light");
  }
  SystemCalibration calibration;
  bool unscaled = false;
  try {
    calibration = load_calibration(args.calibration_file);
    unscaled = calibration_file_is_unscaled(args.calibration_file);
  } catch (const std::exception& e) {
    return bad_input(program, e.what());
  }
  // A single-light calibration has no metric scale: the L-frame's known arms or the wand's known
  // length give it.
  if (unscaled && (args.floor || args.lframe == "auto"))
    return bad_input(program,
                     args.calibration_file +
                         " is unscaled (a single-light calibration): give the L-frame's arm lengths, "
                         "--lframe <x arm m>,<y arm m>, or lay a wand of known length on the floor "
                         "(--wand-floor --wand ...), which set its metric scale");
  std::string error;
  auto by_camera = read_features(args.feature_files, error);
  if (!error.empty()) return bad_input(program, error);
  std::vector<FeatureFrame> frames;
  for (auto& [id, list] : by_camera) frames.insert(frames.end(), list.begin(), list.end());
  if (args.wand_floor)
    return run_wand_floor(program, calibration, args.calibration_file, args.feature_files, frames, wand,
                          unscaled, args.wand_floor_options, args.out, args.scale_tolerance);
  return run_static_marker_world(args, calibration, unscaled, frames);
}

}  // namespace

int run_calibrate(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "estimator_node calibrate: a subcommand is required (see --help)\n");
    return kExitBadInput;
  }
  const std::string_view sub = argv[1];
  if (sub == "--help" || sub == "-h" || sub == "help") {
    std::cout << kUsage;
    return kExitOk;
  }
  try {
    if (sub == "intrinsics") return run_intrinsics(argc - 1, argv + 1);
    if (sub == "solve") return run_solve(argc - 1, argv + 1);
    if (sub == "import-points") return run_import_points(argc - 1, argv + 1);
    if (sub == "world") return run_world(argc - 1, argv + 1);
    if (sub == "capture") return run_calibrate_capture(argc - 1, argv + 1);
    if (sub == "marker") return panoptes::estimator::run_calibrate_marker(argc - 1, argv + 1);
    if (sub == "history" || sub == "revert" || sub == "accept")
      return run_calibrate_history(argc - 1, argv + 1);
  } catch (const InputError& e) {  // a bad file, key or value, e.g. $PANOPTES_DOMAIN=abc, the DDS profile
    std::fprintf(stderr, "estimator_node calibrate %s: %s\n", std::string(sub).c_str(), e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "estimator_node calibrate %s: %s\n", std::string(sub).c_str(), e.what());
    return kExitFailure;
  }
  std::fprintf(stderr, "estimator_node calibrate: unknown subcommand '%s' (see --help)\n",
               std::string(sub).c_str());
  return kExitBadInput;
}

}  // namespace panoptes::calib
