// SPDX-License-Identifier: Apache-2.0
// estimator_node: fuses the asynchronous 2D features of every camera into 3D tracks.
//   live:    subscribes to rt/panoptes/features and camera_info, publishes rt/panoptes/tracks,
//            predictions and estimator_status, and serves rt/panoptes/time_sync
//   offline: --no-dds --in-features <files...> --out-tracks <file>   (architecture.md, Contracts)
//            --in-recording <file.mcap> --out-tracks <file>: the same from a recording (docs/recording.md)
//   --print-config: the effective settings as YAML (--config loads them)
//   tune:    searches filter settings over recorded features (docs/recording.md, "Tune the filter")
// The work is in libraries: session/ (EstimatorSession, offline replay, settings YAML) and app/
// (command line, live DDS loop).
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "panoptes/calib/calibrate_cli.h"
#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/config.h"
#include "panoptes/estimator_app/command_line.h"
#include "panoptes/estimator_app/live_estimator.h"
#include "panoptes/estimator_app/recording_input.h"
#include "panoptes/process.h"
#include "panoptes/session/body_file.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/label_stage.h"
#include "panoptes/session/log.h"
#include "panoptes/session/offline_replay.h"
#include "panoptes/surface_app/calibrate_surface.h"
#include "panoptes/surface_app/surface_mode.h"
#include "panoptes/tune/tune_cli.h"

namespace {

namespace app = panoptes::estimator_app;
namespace session = panoptes::session;

// Calibration and bodies into the tracker, and the settings printed; throws on a bad file.
void prepare(const app::NodeCommandLine& command_line, session::EstimatorSession& estimator,
             session::BodyFile& body_file) {
  if (!command_line.calibration_file.empty()) {
    auto calibration = panoptes::load_calibration(command_line.calibration_file);
    // Moving cameras (inside-out mode, docs/inside_out.md) are not fixed cameras of the tracker.
    session::set_up_inside_out(estimator.inside_out(), calibration, command_line.calibration_file,
                               command_line.landmarks_file);
    estimator.tracker().set_calibration(calibration);
    for (const auto& camera : calibration.cameras) {
      if (!camera.T_world_cam)
        session::log("camera '" + camera.id + "' in " + command_line.calibration_file +
                     " has no T_world_cam: ignored");
    }
  } else if (!command_line.landmarks_file.empty()) {
    throw panoptes::ConfigError(command_line.landmarks_file, "",
                                "landmarks need --calibration with a camera marked moving: true");
  }
  if (body_file.enabled()) body_file.load(estimator.tracker());
  if (!command_line.quiet) {
    std::ostringstream printed;
    estimator.config().tracker.print(printed);
    std::fprintf(stderr, "%s", printed.str().c_str());
  }
}

// Chain tips are also predicted this far ahead (seed 000 §6.4.5), on rt/panoptes/chains and in
// the Chain JSONL alike.
constexpr double kChainHorizonS = 0.08;

// The chains of the bodies file (docs/articulated.md), if it has any.
std::optional<session::ChainStage> chain_stage(const app::NodeCommandLine& command_line) {
  if (command_line.bodies_file.empty()) return std::nullopt;
  auto chains = panoptes::load_chains(command_line.bodies_file);
  if (chains.empty()) {
    if (!command_line.out_chains.empty())
      session::log(command_line.bodies_file + " has no type: chain entries: --out-chains writes nothing");
    return std::nullopt;
  }
  session::log("tracking " + std::to_string(chains.size()) + " articulated chain" +
               (chains.size() == 1 ? "" : "s") + " from " + command_line.bodies_file);
  // Live without a calibration file, the cameras come from their CameraInfo (add_camera).
  const auto calibration = command_line.calibration_file.empty()
                               ? panoptes::SystemCalibration{}
                               : panoptes::load_calibration(command_line.calibration_file);
  std::optional<session::ChainStage> stage(std::in_place, std::move(chains), calibration,
                                           command_line.out_chains);
  stage->set_prediction_horizon(kChainHorizonS);
  return stage;
}

// Live auto-labelling (--subjects, docs/marker_sets.md), if asked for.
std::optional<session::LabelStage> label_stage(const app::NodeCommandLine& command_line,
                                               const session::LabellingSettings& settings) {
  if (settings.models.empty()) {
    if (!command_line.out_labels.empty())
      throw panoptes::ConfigError("--out-labels", "", "needs --subjects (or subjects: models: in --config)");
    return std::nullopt;
  }
  panoptes::labelling::LabellerOptions options;
  options.soft_segments = settings.soft_segments;
  options.min_track_age = settings.min_track_age;
  std::optional<session::LabelStage> stage(session::LabelStage::from_files(
      settings.models, options, command_line.out_labels,
      settings.rate_hz > 0.0 ? panoptes::seconds_to_ns(1.0 / settings.rate_hz) : 0));
  session::log("labelling with " + std::to_string(settings.models.size()) + " subject model" +
               (settings.models.size() == 1 ? "" : "s"));
  return stage;
}

// Live segment poses after the labels (subjects: segment_poses, docs/marker_sets.md), if asked for.
std::optional<session::SegmentStage> segment_stage(const std::optional<session::LabelStage>& labels,
                                                   const session::LabellingSettings& settings) {
  if (!labels || !settings.segment_poses) return std::nullopt;
  panoptes::labelling::KinematicsOptions options;
  options.up = *panoptes::labelling::axis_from_name(settings.static_up);  // checked with the settings
  options.forward = *panoptes::labelling::axis_from_name(settings.static_forward);
  std::vector<panoptes::labelling::SubjectModel> models;
  for (std::size_t i = 0; i < labels->subject_count(); ++i) models.push_back(labels->model(i));
  std::optional<session::SegmentStage> stage(std::in_place, std::move(models), options);
  session::log("segment poses: " + std::to_string(stage->segment_count()) +
               " segments published like bodies");
  return stage;
}

int run(const app::NodeCommandLine& command_line, session::EstimatorSession& estimator,
        session::BodyFile& body_file) {
  session::OfflineReplayOptions replay{command_line.replay_arrival, !command_line.quiet};
  std::optional<session::ChainStage> chains = chain_stage(command_line);
  if (chains) replay.chains = &*chains;
  std::optional<session::LabelStage> labels = label_stage(command_line, estimator.config().subjects);
  if (labels) replay.labels = &*labels;
  if (!command_line.in_recording.empty()) {
    session::FeatureFiles input =
        panoptes::as_input_error([&] { return app::read_recording_features(command_line.in_recording); });
    return session::run_offline(estimator, std::move(input), replay, command_line.out_tracks,
                                command_line.out_poses);
  }
  if (command_line.no_dds) {
    return session::run_offline(estimator, command_line.in_features, replay, command_line.out_tracks,
                                command_line.out_poses);
  }
  app::LiveOptions live;
  live.dds_profile = command_line.dds_profile;
  live.security = command_line.security;
  live.shared_memory = command_line.shared_memory;
  live.calibration_file = command_line.calibration_file;
  live.out_tracks = command_line.out_tracks;
  live.out_poses = command_line.out_poses;
  live.duration_s = command_line.duration_s;
  live.latency_probe = command_line.latency_probe;
  live.quiet = command_line.quiet;
  if (chains) live.chains = &*chains;
  if (labels) live.labels = &*labels;
  const std::optional<session::SegmentStage> segments = segment_stage(labels, estimator.config().subjects);
  if (segments) live.segments = &*segments;
  const int exit_code = app::run_live(live, estimator, body_file);
  if (labels) {
    labels->flush();
    session::log(labels->summary());
  }
  if (chains) {
    chains->flush();
    session::log(chains->summary());
  }
  return exit_code;
}

// Surface mode (docs/surface.md): the `surface:` section of --surface, else of --config; nullopt
// when neither has one. Throws ConfigError.
std::optional<panoptes::surface_app::SurfaceSettings> surface_settings(
    const app::NodeCommandLine& command_line) {
  namespace surface_app = panoptes::surface_app;
  if (!command_line.surface_file.empty()) {
    auto settings = surface_app::load_surface_settings(command_line.surface_file);
    if (!settings) throw panoptes::ConfigError(command_line.surface_file, "surface", "missing");
    return settings;
  }
  if (command_line.config_file.empty()) return std::nullopt;
  return surface_app::load_surface_settings(command_line.config_file);
}

// Reading the calibration, building the surface and reading offline input fail only on bad input
// (exit 2); the run itself fails as its errors say (a DDS failure live: exit 1).
int run_surface_mode(const app::NodeCommandLine& command_line,
                     const panoptes::surface_app::SurfaceSettings& settings,
                     session::EstimatorSession& estimator) {
  namespace surface_app = panoptes::surface_app;
  auto setup = panoptes::as_input_error([&] {
    std::optional<panoptes::SystemCalibration> calibration;
    if (!command_line.calibration_file.empty())
      calibration = panoptes::load_calibration(command_line.calibration_file);
    return surface_app::build_surface(settings, calibration ? &*calibration : nullptr,
                                      command_line.calibration_file);
  });
  if (command_line.no_dds || !command_line.in_recording.empty()) {
    auto input = panoptes::as_input_error([&] {
      return command_line.in_recording.empty() ? session::read_feature_files(command_line.in_features)
                                               : app::read_recording_features(command_line.in_recording);
    });
    return surface_app::run_surface_offline(setup, std::move(input), command_line.out_strokes,
                                            command_line.quiet);
  }
  surface_app::SurfaceLiveOptions live;
  live.dds_profile = command_line.dds_profile;
  live.security = command_line.security;
  live.out_strokes = command_line.out_strokes;
  live.duration_s = command_line.duration_s;
  live.latency_window_ms = settings.latency_window_ms;
  live.quiet = command_line.quiet;
  return surface_app::run_surface_live(live, setup, estimator);
}

// Errors escape to run_program, which picks the exit code by their type (panoptes/errors.h);
// reading the settings, the surface, the calibration and the bodies is the input's part (exit 2).
int run_estimator_node(int argc, char** argv) {
  if (argc >= 3 && std::string_view(argv[1]) == "calibrate" && std::string_view(argv[2]) == "surface")
    return panoptes::surface_app::run_calibrate_surface(argc - 2, argv + 2);
  if (argc >= 2 && std::string_view(argv[1]) == "calibrate")
    return panoptes::calib::run_calibrate(argc - 1, argv + 1);
  if (argc >= 2 && std::string_view(argv[1]) == "tune")
    return panoptes::tune::run_tune(argc - 1, argv + 1, panoptes::estimator_app::read_recording_features);
  app::NodeCommandLine command_line;
  if (const auto exit_code = app::parse_node_command_line(argc, argv, command_line)) return *exit_code;

  const session::EstimatorConfig config =
      panoptes::as_input_error([&] { return command_line.effective_config(); });
  if (command_line.print_config) {
    std::fputs(session::estimator_config_to_yaml(config).c_str(), stdout);
    return panoptes::kExitOk;
  }

  panoptes::install_stop_handlers();
  session::EstimatorSession estimator(config);
  if (const auto surface = panoptes::as_input_error([&] { return surface_settings(command_line); }))
    return run_surface_mode(command_line, *surface, estimator);
  session::BodyFile body_file(command_line.bodies_file);
  panoptes::as_input_error([&] { prepare(command_line, estimator, body_file); });
  return run(command_line, estimator, body_file);
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("estimator_node", [&] { return run_estimator_node(argc, argv); });
}
