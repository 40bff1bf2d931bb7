// SPDX-License-Identifier: Apache-2.0
// camera_node: captures frames, finds and centroids IR blobs, publishes timestamped 2D features.
//   live:    --source sim:<scene>#<camera> | images:<dir or glob>  → rt/panoptes/features
//   offline: --source images:<...> --no-dds --out-features <file.jsonl>  (architecture.md, Contracts)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>

#include "panoptes/bounded_queue.h"
#include "panoptes/camera/detector.h"
#include "panoptes/camera/sources.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace {

using panoptes::TimeNs;
namespace cam = panoptes::camera;

struct Options {
  std::string source;
  std::string camera_id;
  std::string config_file;
  bool no_dds = false;
  std::string out_features;
  std::string dds_profile;
  long long sim_epoch_ns = 0;
  double duration_s = 0;
  long long max_frames = -1;
  bool unpaced = false;
  std::size_t queue_capacity = 4;
  bool quiet = false;
};

std::string g_name = "camera_node";  // set once from the camera id, for log lines
void log(const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", g_name.c_str(), message.c_str());
}

// Detection-time percentiles over the last status period.
class Percentiles {
 public:
  void add(double value) { values_.push_back(value); }
  double at(double q) {
    if (values_.empty()) return 0.0;
    const auto k = static_cast<std::size_t>(q * static_cast<double>(values_.size() - 1));
    std::nth_element(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(k), values_.end());
    return values_[k];
  }
  void clear() { values_.clear(); }

 private:
  std::vector<double> values_;
};

panoptes::FeatureFrame detect_frame(cam::Detector& detector, const cam::CapturedFrame& captured,
                                    const std::string& camera_id) {
  const TimeNs begin = panoptes::monotonic_now_ns();
  panoptes::FeatureFrame frame;
  frame.blobs = detector.detect(captured.image);
  frame.processing_ns = panoptes::monotonic_now_ns() - begin;
  frame.camera_id = camera_id;
  frame.frame = captured.sequence;
  // Image files carry no capture time: stamp them when they were read.
  frame.stamp_ns = captured.stamp_ns != 0 ? captured.stamp_ns : captured.arrival_ns;
  frame.arrival_ns = captured.arrival_ns;
  return frame;
}

int run_offline(const Options& options, cam::FrameSource& source, cam::Detector& detector,
                const std::string& camera_id) {
  panoptes::JsonlWriter out(options.out_features);
  std::size_t frames = 0;
  std::size_t blobs = 0;
  while (!panoptes::stop_requested()) {
    auto captured = source.next();
    if (!captured) break;
    if (captured->arrival_ns == 0) captured->arrival_ns = panoptes::wall_now_ns();
    const auto frame = detect_frame(detector, *captured, camera_id);
    blobs += frame.blobs.size();
    out.write(frame);
    ++frames;
    if (!options.quiet && frames % 100 == 0) std::fprintf(stderr, "\r%s: %zu frames", g_name.c_str(), frames);
  }
  if (!options.quiet && frames >= 100) std::fprintf(stderr, "\n");
  log("wrote " + std::to_string(frames) + " frames with " + std::to_string(blobs) + " blobs to " +
      options.out_features);
  return panoptes::kExitOk;
}

int run_live(const Options& options, cam::FrameSource& source, cam::Detector& detector,
             const std::string& camera_id) {
  namespace msg = panoptes::msg;
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.participant_name = "camera_node/" + camera_id;
  panoptes::dds::Bus bus(bus_options);
  auto info_writer = bus.make_writer<msg::CameraInfo>();
  auto feature_writer = bus.make_writer<msg::FeatureFrame>();
  auto status_writer = bus.make_writer<msg::CameraStatus>();

  const auto& info = source.info();
  msg::CameraInfo camera_info;
  if (info.calibration) {
    camera_info =
        panoptes::dds::to_camera_info(camera_id, info.calibration->intrinsics, info.calibration->T_world_cam);
  } else {
    camera_info.camera_id(camera_id);
    camera_info.width(static_cast<uint32_t>(info.width));
    camera_info.height(static_cast<uint32_t>(info.height));
  }
  camera_info.model(info.model);
  camera_info.serial(info.serial);
  camera_info.backend(info.backend);
  camera_info.nominal_rate_hz(info.nominal_rate_hz);
  camera_info.stamp_ns(panoptes::wall_now_ns());
  info_writer->write(camera_info);
  if (!options.quiet) log("publishing on DDS (profile " + bus.profile_file().string() + ")");

  // Capture thread → bounded queue → detection and publishing on this thread.
  panoptes::BoundedQueue<cam::CapturedFrame> queue(options.queue_capacity);
  std::atomic<bool> source_ended{false};
  std::thread capture([&] {
    while (!panoptes::stop_requested()) {
      auto captured = source.next();
      if (!captured) break;
      if (captured->arrival_ns == 0) captured->arrival_ns = panoptes::wall_now_ns();
      queue.push(std::move(*captured));
    }
    source_ended.store(true);
    queue.close();
  });

  const TimeNs start = panoptes::wall_now_ns();
  TimeNs next_status = start + panoptes::kNsPerSecond;
  std::uint64_t frames = 0;
  std::uint64_t frames_at_status = 0;
  Percentiles detect_ms;
  std::optional<panoptes::JsonlWriter> out;
  if (!options.out_features.empty()) out.emplace(options.out_features);

  while (!panoptes::stop_requested()) {
    auto captured = queue.pop(std::chrono::milliseconds(50));
    const TimeNs now = panoptes::wall_now_ns();
    if (captured) {
      const auto frame = detect_frame(detector, *captured, camera_id);
      auto message = panoptes::dds::to_message(frame);
      message.publish_ns(panoptes::wall_now_ns());
      feature_writer->write(message);
      if (out) out->write(frame);
      detect_ms.add(static_cast<double>(frame.processing_ns) * 1e-6);
      ++frames;
    } else if (source_ended.load() && queue.size() == 0) {
      break;
    }
    if (now >= next_status) {
      const double period = panoptes::ns_to_seconds(now - next_status) + 1.0;
      msg::CameraStatus status;
      status.camera_id(camera_id);
      status.stamp_ns(now);
      status.fps(static_cast<double>(frames - frames_at_status) / period);
      status.frames(frames);
      status.drops_queue(queue.drops());
      status.detect_p50_ms(detect_ms.at(0.5));
      status.detect_p99_ms(detect_ms.at(0.99));
      status.queue_depth(static_cast<uint32_t>(queue.size()));
      status.threshold(detector.config().threshold);
      status_writer->write(status);
      frames_at_status = frames;
      detect_ms.clear();
      next_status = now + panoptes::kNsPerSecond;
    }
    if (options.duration_s > 0 && now - start >= panoptes::seconds_to_ns(options.duration_s)) break;
  }
  source.stop();
  queue.close();
  capture.join();
  log("stopped after " + std::to_string(frames) + " frames (" + std::to_string(queue.drops()) +
      " dropped in the queue)");
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"camera_node: detects IR blobs in camera frames and publishes 2D features (Panoptes)",
               "camera_node"};
  app.add_option("--source", options.source, "sim:<scene.yaml>#<camera id> | images:<dir or glob>")
      ->required();
  app.add_option("--camera-id", options.camera_id, "camera id to publish under (default: the source's)");
  app.add_option("--config", options.config_file,
                 "YAML with a `detector:` section (threshold, min_area, ...)");
  app.add_flag("--no-dds", options.no_dds, "offline: no DDS; requires --out-features");
  app.add_option("--out-features", options.out_features, "write every FeatureFrame to this JSONL file");
  app.add_option("--dds-profile", options.dds_profile,
                 "Fast DDS XML profile (default: deploy/dds/loopback.xml)");
  app.add_option("--sim-epoch-ns", options.sim_epoch_ns,
                 "sim: wall-clock ns of scene time 0 (default: now, rounded up to a whole second)");
  app.add_option("--duration", options.duration_s, "stop after this many seconds (0 = until the source ends)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-frames", options.max_frames, "stop after this many frames")
      ->check(CLI::PositiveNumber);
  app.add_flag("--unpaced", options.unpaced,
               "sim: produce frames as fast as possible instead of in real time");
  app.add_option("--queue-capacity", options.queue_capacity,
                 "frames waiting for detection before the oldest is dropped")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--quiet", options.quiet, "less output");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (options.no_dds && options.out_features.empty())
          throw CLI::ValidationError("--no-dds needs --out-features");
      })) {
    return *exit_code;
  }

  panoptes::install_stop_handlers();
  std::unique_ptr<cam::FrameSource> source;
  cam::DetectorConfig detector_config;
  try {
    if (!options.config_file.empty()) {
      const panoptes::YamlReader config(options.config_file, panoptes::load_yaml_file(options.config_file));
      if (config.has("detector")) detector_config = cam::DetectorConfig::from_yaml(config.child("detector"));
    }
    cam::SourceOptions source_options;
    source_options.camera_id = options.camera_id;
    source_options.sim_epoch_ns = options.sim_epoch_ns;
    source_options.paced = !options.unpaced;
    source_options.max_frames = options.max_frames;
    source = cam::open_source(options.source, source_options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "camera_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  }
  const std::string camera_id = options.camera_id.empty() ? source->info().camera_id : options.camera_id;
  g_name = "camera_node[" + camera_id + "]";
  cam::Detector detector(detector_config);

  try {
    return options.no_dds ? run_offline(options, *source, detector, camera_id)
                          : run_live(options, *source, detector, camera_id);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s: %s\n", g_name.c_str(), error.what());
    return panoptes::kExitFailure;
  }
}
