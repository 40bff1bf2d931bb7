// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/command_line.h"
#include "panoptes/dds/domain_option.h"

#include <filesystem>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/security_options.h"
#include "panoptes/landmarks_file.h"
#include "panoptes/time.h"

namespace panoptes::estimator_app {

namespace {

// The settings flags, bound to a default configuration so --help shows the defaults.
struct SettingsFlags {
  session::EstimatorConfig values;
  std::string anchors_file;
  double rewind_horizon_ms = ns_to_seconds(values.tracker.rewind_horizon_ns) * 1e3;
  double smoothing_ms = ns_to_seconds(values.tracker.bodies.smoothing_ns) * 1e3;
  std::vector<std::pair<CLI::Option*, std::function<void(session::EstimatorConfig&)>>> options;

  void add(CLI::App& app) {
    auto& node = values.node;
    auto& tracker = values.tracker;
    const auto bind = [&](CLI::Option* option, std::function<void(session::EstimatorConfig&)> apply) {
      options.emplace_back(option, std::move(apply));
    };
    bind(app.add_option("--prediction-horizon-ms", node.prediction_horizon_ms,
                        "publish body poses predicted this far ahead of the newest frame (seed 000 Ch. 5)")
             ->check(CLI::Range(0.0, 1000.0)),
         [this](auto& c) { c.node.prediction_horizon_ms = values.node.prediction_horizon_ms; });
    bind(app.add_option(
                "--smoothing-ms", smoothing_ms,
                "report body poses this far behind the newest frame, smoothed with the frames after them "
                "(fixed-lag; 0: off)")
             ->check(CLI::Range(0.0, 1000.0)),
         [this](auto& c) { c.tracker.bodies.smoothing_ns = seconds_to_ns(smoothing_ms * 1e-3); });
    bind(
        app.add_option("--latency-window-ms", node.latency_window_ms,
                       "live: how long frames wait to be ordered by stamp (0: not at all; frames that arrive "
                       "out of order are replayed from a checkpoint, bursts in one replay)")
            ->check(CLI::Range(0.0, 10000.0)),
        [this](auto& c) { c.node.latency_window_ms = values.node.latency_window_ms; });
    bind(app.add_flag("!--no-predictions", node.predictions, "live: do not publish predicted windows"),
         [this](auto& c) { c.node.predictions = values.node.predictions; });
    bind(app.add_option("--prediction-margin-px", node.prediction_margin_px,
                        "live: pixels added around each predicted gate")
             ->check(CLI::Range(0.0, 1000.0)),
         [this](auto& c) { c.node.prediction_margin_px = values.node.prediction_margin_px; });
    bind(app.add_option("--rewind-horizon-ms", rewind_horizon_ms,
                        "late frames up to this much older than the newest are replayed, older ones dropped")
             ->check(CLI::Range(0.0, 60000.0)),
         [this](auto& c) { c.tracker.rewind_horizon_ns = seconds_to_ns(rewind_horizon_ms * 1e-3); });
    bind(app.add_option("--status-period", node.status_period_s, "live: seconds between progress lines")
             ->check(CLI::PositiveNumber),
         [this](auto& c) { c.node.status_period_s = values.node.status_period_s; });
    bind(app.add_option("--process-noise", tracker.process_noise,
                        "σ² of white acceleration, m²/s³ (seed 003 A.48)")
             ->check(CLI::PositiveNumber),
         [this](auto& c) { c.tracker.process_noise = values.tracker.process_noise; });
    bind(app.add_option("--measurement-noise-px", tracker.measurement_noise_px, "σ of a centroid, px")
             ->check(CLI::PositiveNumber),
         [this](auto& c) { c.tracker.measurement_noise_px = values.tracker.measurement_noise_px; });
    bind(app.add_option("--continuous-calibration", tracker.calibration.mode,
                        "watch each camera's residuals against the tracks the others determine; detect: "
                        "stop fusing a camera whose residuals are significantly biased (a bump) until they "
                        "are not; correct: as detect, and re-estimate the quarantined camera's pose from the "
                        "tracks, apply it when well determined and bring the camera back; off: do not watch "
                        "(docs/continuous_calibration.md)")
             ->check(CLI::Validator(session::check_continuous_calibration, "off|detect|correct")),
         [this](auto& c) { c.tracker.calibration.mode = values.tracker.calibration.mode; });
    bind(app.add_option("--anchors", anchors_file,
                        "correct: anchor markers, a landmarks YAML (docs/inside_out.md) of fixed markers at "
                        "known positions that hold the world frame while the cameras' drift is followed "
                        "(docs/continuous_calibration.md)")
             ->check(CLI::ExistingFile),
         [this](auto& c) {
           c.tracker.calibration.anchors.clear();
           for (const auto& group : load_landmarks(anchors_file))
             c.tracker.calibration.anchors.insert(c.tracker.calibration.anchors.end(), group.points.begin(),
                                                  group.points.end());
         });
    bind(app.add_option("--confirm-cameras", tracker.confirm_cameras,
                        "distinct cameras that must see a new track before it is published")
             ->check(CLI::Range(2, 64)),
         [this](auto& c) { c.tracker.confirm_cameras = values.tracker.confirm_cameras; });
    bind(app.add_option("--frames", node.frames,
                        "rt/panoptes/frames, ROS 2 and offline --out-tracks/--out-poses: per-camera (one per "
                        "camera frame), fixed (--frame-rate-hz, on a grid) or auto (fixed live, per-camera "
                        "records offline; docs/frames.md)")
             ->check(CLI::IsMember({"auto", "per-camera", "fixed"})),
         [this](auto& c) { c.node.frames = values.node.frames; });
    bind(app.add_option("--frame-rate-hz", node.frame_rate_hz, "rate of --frames fixed")
             ->check(CLI::Range(1, 10000)),
         [this](auto& c) { c.node.frame_rate_hz = values.node.frame_rate_hz; });
    bind(app.add_option(
                "--realtime-priority", node.realtime_priority,
                "live: run the estimator thread (which publishes fixed-rate frames) at this SCHED_FIFO "
                "priority, 1-99 (0: the normal scheduler; needs root or CAP_SYS_NICE; docs/frames.md)")
             ->check(CLI::Range(0, 99)),
         [this](auto& c) { c.node.realtime_priority = values.node.realtime_priority; });
    bind(app.add_flag("--ros2,!--no-ros2", values.ros2.enabled,
                      "live: publish the ROS 2 topics (docs/ros2.md: rt/panoptes/<body>/pose, twist, rt/tf, "
                      "rt/rigid_bodies, rt/markers)"),
         [this](auto& c) { c.ros2.enabled = values.ros2.enabled; });
    bind(app.add_option("--ros2-tf-rate-hz", values.ros2.tf_rate_hz,
                        "live: /tf at most this often, one per period of a grid on the capture clock (0: "
                        "with every output frame; docs/ros2.md)")
             ->check(CLI::Range(0, session::kMaxTfRateHz)),
         [this](auto& c) { c.ros2.tf_rate_hz = values.ros2.tf_rate_hz; });
    bind(app.add_option(
                "--ros2-namespace", values.ros2.topic_namespace,
                "live: ROS 2 namespace of every ROS 2 topic but /tf, e.g. /lab1 gives /lab1/rigid_bodies "
                "(docs/ros2.md)")
             ->check(CLI::Validator(session::check_ros2_namespace, "NAMESPACE")),
         [this](auto& c) { c.ros2.topic_namespace = values.ros2.topic_namespace; });
    add_subjects(app, bind);
  }

  // Live labelling (docs/marker_sets.md): the `subjects:` section's flags.
  template <class Bind>
  void add_subjects(CLI::App& app, const Bind& bind) {
    auto& subjects = values.subjects;
    bind(app.add_option("--subjects", subjects.models,
                        "label point tracks with marker names from these subject models (panoptes_label "
                        "model; comma-separated; `subjects: models:` in --config; docs/marker_sets.md)")
             ->delimiter(','),
         [this](auto& c) {
           // From the working folder, written absolute: --print-config's output loads from anywhere.
           c.subjects.models.clear();
           for (const auto& model : values.subjects.models)
             c.subjects.models.push_back(std::filesystem::absolute(model).lexically_normal().string());
         });
    bind(app.add_option("--soft-segments", subjects.soft_segments,
                        "with --subjects: segments that deform while moving (e.g. Torso; comma-separated)")
             ->delimiter(','),
         [this](auto& c) { c.subjects.soft_segments = values.subjects.soft_segments; });
    bind(app.add_option("--label-rate-hz", subjects.rate_hz,
                        "with --subjects: run the labeller at most this often (0: every processed frame)")
             ->check(CLI::Range(0.0, 100000.0)),
         [this](auto& c) { c.subjects.rate_hz = values.subjects.rate_hz; });
    bind(app.add_option("--label-min-track-age", subjects.min_track_age,
                        "with --subjects: a track processed fewer frames is not used to acquire a subject")
             ->check(CLI::Range(1, 1000000)),
         [this](auto& c) { c.subjects.min_track_age = values.subjects.min_track_age; });
  }
};

void add_modes_and_files(CLI::App& app, NodeCommandLine& c) {
  app.add_option(
      "--config", c.config_file,
      "estimator settings YAML (docs/estimator.md, \"Configuration\"); flags given here override it");
  app.add_flag("--print-config", c.print_config,
               "print the effective settings as YAML (loadable with --config) and exit");
  app.add_option("--calibration", c.calibration_file, "calibration YAML (cameras with T_world_cam)");
  app.add_option("--bodies", c.bodies_file,
                 "rigid-body definitions YAML (docs/bodies.md); live, reloaded when the file changes");
  app.add_option(
      "--landmarks", c.landmarks_file,
      "inside-out mode: landmarks YAML (a landmarks: list, e.g. a simulator scene) for the cameras "
      "marked moving: true in --calibration; their rigs' poses are published like bodies "
      "(docs/inside_out.md)");
  app.add_option("--in-features", c.in_features, "offline: FeatureFrame JSONL files (one per camera)")
      ->expected(1, -1);
  app.add_option(
      "--in-recording", c.in_recording,
      "offline (no DDS): the FeatureFrames of an MCAP recording (panoptes_record, docs/recording.md)");
  app.add_flag("--no-dds", c.no_dds, "offline: do not use DDS; requires --in-features or --in-recording");
  app.add_option("--out-tracks", c.out_tracks, "write every published TrackFrame as Track JSONL");
  app.add_option("--out-poses", c.out_poses,
                 "write body poses as Pose JSONL (needs --bodies or --landmarks)");
  app.add_option(
      "--out-chains", c.out_chains,
      "write the articulated chains of the bodies file (type: chain) and their grab/release events as "
      "Chain JSONL (docs/articulated.md; needs --bodies; live mode also publishes rt/panoptes/chains)");
  app.add_option("--out-labels", c.out_labels,
                 "with --subjects: write the labelled tracks of every processed frame as JSONL");
  app.add_option("--dds-profile", c.dds_profile, "Fast DDS XML profile (default: deploy/dds/loopback.xml)");
  dds::add_security_options(app, c.security);
  app.add_flag("--shared-memory", c.shared_memory,
               "keep the profile's shared-memory transport (default: off, UDP only unless the profile has "
               "nothing else: a process on this host that dies while holding its shared-memory port's lock "
               "would stall the estimator's sends for 1 s; docs/protocol.md, \"A peer that dies\")");
  app.add_flag("--replay-arrival", c.replay_arrival,
               "offline: deliver frames in the order they reached the estimator (received_ns), through the "
               "latency window, as live mode would");
  app.add_option("--duration", c.duration_s, "live: stop after this many seconds (0 = until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--latency-probe", c.latency_probe,
               "live, benchmark aid: echo camera_node --latency-probe probes at once and trace when each "
               "frame's output is written (rt/panoptes/latency_probe/..., bench_latency)");
  app.add_flag("--quiet", c.quiet, "no progress output");
  app.add_option(
      "--surface", c.surface_file,
      "surface mode (LumiPoint, docs/surface.md): a YAML whose `surface:` section defines the wall; "
      "strokes on rt/panoptes/strokes instead of 3D tracks (a `surface:` section in --config does the same)");
  app.add_option("--out-strokes", c.out_strokes, "surface mode: write every stroke event as Stroke JSONL");
}

void validate(const NodeCommandLine& c) {
  if (c.print_config) return;  // prints and exits: no mode needed
  if (!c.in_recording.empty() && !c.in_features.empty())
    throw CLI::ValidationError("--in-recording and --in-features: give one of them");
  if (c.no_dds && c.in_features.empty() && c.in_recording.empty())
    throw CLI::ValidationError("--no-dds needs --in-features or --in-recording");
  if (!c.in_features.empty() && !c.no_dds) {
    throw CLI::ValidationError(
        "--in-features runs offline: add --no-dds (replaying onto DDS is camera_node's job)");
  }
  if ((c.no_dds || !c.in_recording.empty()) && c.calibration_file.empty() && c.surface_file.empty())
    throw CLI::ValidationError("offline mode needs --calibration");
  if (!c.out_poses.empty() && c.bodies_file.empty() && c.landmarks_file.empty())
    throw CLI::ValidationError("--out-poses needs --bodies or --landmarks");
  if (!c.out_chains.empty() && c.bodies_file.empty())
    throw CLI::ValidationError("--out-chains needs --bodies");
}

}  // namespace

session::EstimatorConfig NodeCommandLine::effective_config() const {
  session::EstimatorConfig config =
      config_file.empty() ? session::EstimatorConfig{} : session::load_estimator_config(config_file);
  for (const auto& apply : overrides) apply(config);
  return config;
}

std::optional<int> parse_node_command_line(int argc, char** argv, NodeCommandLine& command_line) {
  CLI::App app{"estimator_node: fuses asynchronous camera features into 3D tracks (Panoptes)",
               "estimator_node"};
  app.option_defaults()->always_capture_default();
  add_modes_and_files(app, command_line);
  panoptes::dds::add_domain_option(app);
  auto flags = std::make_shared<SettingsFlags>();
  flags->add(app);
  if (const auto exit_code = parse_command_line(app, argc, argv, [&] { validate(command_line); }))
    return exit_code;
  for (const auto& [option, apply] : flags->options) {
    // The appliers read the parsed values from `flags`: keep it alive with them.
    if (option->count() > 0)
      command_line.overrides.push_back([flags, apply = apply](auto& config) { apply(config); });
  }
  return std::nullopt;
}

}  // namespace panoptes::estimator_app
