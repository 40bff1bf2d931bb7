// SPDX-License-Identifier: Apache-2.0
// camera_node: captures frames, finds and centroids IR blobs, publishes timestamped 2D features
// (docs/camera_node.md; the pipeline inside: "Inside camera_node: the pipeline").
//   live:    --source <spec>  → rt/panoptes/features, camera_info, camera_status (1 Hz),
//            camera_preview (on request); ← camera_command, predictions
//   offline: --source <spec> --no-dds --out-features <file.jsonl>  (architecture.md, Contracts)
// Live, the node synchronises its clock with the estimator's time service (rt/panoptes/time_sync)
// and publishes every stamp on the common time base.
#include <memory>
#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>

#include "panoptes/camera/detector.h"
#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/node_log.h"
#include "panoptes/camera/pipeline.h"
#include "panoptes/camera/sources.h"
#include "panoptes/camera_app/live_camera.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/dds/security_options.h"
#include "panoptes/process.h"

namespace {

namespace cam = panoptes::camera;

struct Options {
  std::string source;
  std::string camera_id;
  std::string config_file;
  bool no_dds = false;
  std::string out_features;
  std::string clock_skew;  // "<offset_ms>,<drift_ppm>", parsed into live.clock_skew
  long long sim_epoch_ns = 0;
  std::string sim_epoch_file;
  long long max_frames = -1;
  bool unpaced = false;
  double rate_scale = 1.0;
  // GenICam timing flags; "" = as the config's `source:` section says (docs/camera_node.md).
  std::string ptp;
  std::string trigger;
  std::string trigger_activation;
  std::string strobe;
  panoptes::camera_app::LiveOptions live;
};

void add_timing_options(CLI::App& app, Options& options) {
  app.add_option(
         "--ptp", options.ptp,
         "aravis: on = enable the camera's PTP (PtpEnable or GevIEEE1588), wait for PtpStatus Slave/Master "
         "and take its PTP stamps as capture times, without software clock sync (config: source.ptp; "
         "default off)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option(
      "--trigger", options.trigger,
      "aravis: hardware frame trigger: the TriggerSource (Line0, Line1, Software, ...) or off (config: "
      "source.trigger; default off = free-running)");
  app.add_option("--trigger-activation", options.trigger_activation,
                 "aravis: the trigger's edge (config: source.trigger_activation; default RisingEdge)")
      ->check(CLI::IsMember({"RisingEdge", "FallingEdge"}));
  app.add_option("--strobe", options.strobe,
                 "aravis: output line (LineSelector, e.g. Line2) driven by ExposureActive, or off (config: "
                 "source.strobe; default off)");
}

// The timing flags over the config's settings; throws std::invalid_argument (exit 2) naming the
// option when they exclude each other.
void apply_timing_flags(const Options& options, cam::SourceSettings& settings) {
  if (!options.ptp.empty()) settings.ptp = options.ptp == "on";
  if (!options.trigger.empty()) settings.trigger = options.trigger == "off" ? "" : options.trigger;
  if (!options.trigger_activation.empty()) settings.trigger_activation = options.trigger_activation;
  if (!options.strobe.empty()) settings.strobe = options.strobe == "off" ? "" : options.strobe;
  cam::check_timing(settings, [](const std::string& key, const std::string& why) {
    throw std::invalid_argument("source." + key + ": " + why);
  });
}

void add_options(CLI::App& app, Options& options) {
  panoptes::camera_app::LiveOptions& live = options.live;
  app.option_defaults()->always_capture_default();
  app.add_option("--source", options.source,
                 "sim:<scene.yaml>#<camera id> | images:<dir or glob> | aravis:<ip or device id> | "
                 "v4l2:/dev/videoN | features:<file.jsonl>")
      ->required();
  app.add_option("--camera-id", options.camera_id, "camera id to publish under (default: the source's)");
  app.add_option("--config", options.config_file,
                 "YAML with `detector:` (threshold, masks, ...) and `source:` (exposure_us, gain_db, "
                 "frame_rate_hz, roi, pixel_format, ...) sections; see docs/camera_node.md");
  add_timing_options(app, options);
  app.add_flag("--no-dds", options.no_dds, "offline: no DDS; requires --out-features");
  app.add_option("--out-features", options.out_features, "write every FeatureFrame to this JSONL file");
  app.add_option("--dds-profile", live.dds_profile,
                 "Fast DDS XML profile (default: deploy/dds/loopback.xml)");
  panoptes::dds::add_security_options(app, live.security);
  app.add_option("--sim-epoch-ns", options.sim_epoch_ns,
                 "sim: wall-clock ns of scene time 0 (default: now, rounded up to a whole second); features: "
                 "wall-clock ns of the recording's epoch (its first stamp rounded down to a second), so "
                 "several replaying nodes stay aligned (default: the replay starts now)");
  app.add_option("--sim-epoch-file", options.sim_epoch_file,
                 "features: wait for this file to hold the recording's epoch (wall-clock ns, decimal) and "
                 "replay from it: a start gate for nodes that should synchronise their clocks first (write "
                 "the file whole, e.g. by rename)")
      ->excludes("--sim-epoch-ns");
  app.add_option("--duration", live.duration_s, "stop after this many seconds (0 = until the source ends)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-frames", options.max_frames,
                 "stop after this many frames (-1 = until the source ends)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--unpaced", options.unpaced,
               "sim, features: produce frames as fast as possible instead of in real time");
  app.add_option("--rate-scale", options.rate_scale, "features: replay speed (2 = twice the recorded pace)")
      ->check(CLI::PositiveNumber);
  app.add_option("--prediction-max-age-ms", live.prediction_max_age_ms,
                 "use predicted windows (rt/panoptes/predictions) only if stamped within this many ms of the "
                 "frame; otherwise search the full frame")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--queue-capacity", live.queue_capacity,
                 "frames waiting for detection before the oldest is dropped")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--no-clock-sync", live.no_clock_sync,
               "do not synchronise with the estimator's time service: publish stamps as read (for hosts "
               "kept on the common time base by PTP or chrony)");
  app.add_option("--clock-sync-wait", live.clock_sync_wait_s,
                 "hold frames up to this many seconds after start until the clock is synchronised; "
                 "later, unsynchronised stamps are published as read (and counted)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--clock-skew", options.clock_skew,
                 "testing aid: <offset_ms>,<drift_ppm>; the node's clock runs off the host's by offset + "
                 "drift * (time since start), for its frame stamps and its clock-sync requests alike");
  app.add_option("--inject-loss", live.inject_loss,
                 "testing aid: drop this fraction of feature frames before sending (a lossy link where "
                 "tc netem is unavailable)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--inject-jitter-ms", live.inject_jitter_ms,
                 "testing aid: send each feature frame after a random delay, uniform in [0, 2 x this] ms")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag(
      "--latency-probe", live.latency_probe,
      "benchmark aid: after each feature frame, write a probe of the same size on "
      "rt/panoptes/latency_probe/request for estimator_node --latency-probe to echo (bench_latency)");
  app.add_flag("--quiet", live.quiet, "less output");
}

// Checks across options, after parsing; throws CLI::ValidationError.
void validate(Options& options) {
  if (options.no_dds && options.out_features.empty())
    throw CLI::ValidationError("--no-dds needs --out-features");
  try {
    options.live.clock_skew = cam::parse_clock_skew(options.clock_skew);
  } catch (const std::invalid_argument& error) {
    throw CLI::ValidationError(error.what());
  }
  if (options.no_dds && !options.clock_skew.empty())
    throw CLI::ValidationError("--clock-skew tests the clock synchronisation over DDS; not with --no-dds");
  if (!options.sim_epoch_file.empty() && options.source.rfind("features:", 0) != 0)
    throw CLI::ValidationError("--sim-epoch-file is for a features: source (a replay), not " +
                               options.source);
  options.live.source_spec = options.source;
  options.live.out_features = options.out_features;
}

// Opens the source with the settings of --config; fills `detector_config`. Anything that goes wrong
// here is the input's fault (a missing device or file, a bad source or configuration): InputError.
std::unique_ptr<cam::FrameSource> open_source(const Options& options, cam::DetectorConfig& detector_config) {
  return panoptes::as_input_error([&] {
    cam::SourceOptions source_options;
    if (!options.config_file.empty()) {
      const panoptes::YamlReader config(options.config_file, panoptes::load_yaml_file(options.config_file));
      config.expect_only({"detector", "source"});
      if (config.has("detector")) detector_config = cam::DetectorConfig::from_yaml(config.child("detector"));
      if (config.has("source"))
        source_options.settings = cam::SourceSettings::from_yaml(config.child("source"));
    }
    apply_timing_flags(options, source_options.settings);
    source_options.camera_id = options.camera_id;
    source_options.sim_epoch_ns = options.sim_epoch_ns;
    source_options.sim_epoch_file = options.sim_epoch_file;
    source_options.paced = !options.unpaced;
    source_options.max_frames = options.max_frames;
    source_options.rate_scale = options.rate_scale;
    return cam::open_source(options.source, source_options);
  });
}

// Errors escape to run_program: a bad source or config and refused DDS Security files exit 2,
// anything failing later 1.
int run_camera_node(int argc, char** argv) {
  Options options;
  CLI::App app{"camera_node: detects IR blobs in camera frames and publishes 2D features (Panoptes)",
               "camera_node"};
  add_options(app, options);
  panoptes::dds::add_domain_option(app);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] { validate(options); })) {
    return *exit_code;
  }

  panoptes::install_stop_handlers();
  cam::DetectorConfig detector_config;
  const std::unique_ptr<cam::FrameSource> source = open_source(options, detector_config);
  const std::string camera_id = options.camera_id.empty() ? source->info().camera_id : options.camera_id;
  cam::NodeLog log("camera_node[" + camera_id + "]");
  if (const auto& features = source->info().timing_features; !features.empty()) {
    std::string line;
    for (const auto& [name, value] : features) {
      if (!line.empty()) line += ' ';
      line.append(name).append("=").append(value);
    }
    log("GenICam timing features as read back: " + line);
  }
  cam::Detector detector(detector_config);
  if (options.no_dds) {
    const cam::OfflineOptions offline{options.out_features, options.live.queue_capacity, options.live.quiet};
    return cam::run_offline(offline, *source, detector, camera_id, log);
  }
  panoptes::camera_app::LiveCamera live(options.live, *source, detector, camera_id, log);
  return live.run();
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("camera_node", [&] { return run_camera_node(argc, argv); });
}
