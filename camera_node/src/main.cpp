// SPDX-License-Identifier: Apache-2.0
// camera_node: captures frames, finds and centroids IR blobs, publishes timestamped 2D features
// (docs/camera_node.md).
//   live:    --source <spec>  → rt/panoptes/features, camera_info, camera_status (1 Hz),
//            camera_preview (on request); ← camera_command, predictions
//   offline: --source <spec> --no-dds --out-features <file.jsonl>  (architecture.md, Contracts)
// Live, the node synchronises its clock with the estimator's time service (rt/panoptes/time_sync)
// and publishes every stamp on the common time base.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>

#include "node_control.h"
#include "panoptes/bounded_queue.h"
#include "panoptes/camera/detector.h"
#include "panoptes/camera/sources.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/jsonl.h"
#include "panoptes/simulator.h"
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
  double rate_scale = 1.0;
  std::size_t queue_capacity = 4;
  double prediction_max_age_ms = 50;
  bool quiet = false;
  bool no_clock_sync = false;
  double clock_sync_wait_s = 2.0;
  std::string clock_skew;  // "<offset_ms>,<drift_ppm>", parsed into the two below
  TimeNs skew_offset_ns = 0;
  double skew_drift_ppm = 0;
  double inject_loss = 0;       // testing aid: fraction of feature frames not sent
  double inject_jitter_ms = 0;  // testing aid: frames sent after a uniform delay in [0, 2·jitter]
  bool latency_probe = false;   // benchmark aid: a LatencyProbe after each FeatureFrame
};

// Parses --clock-skew "<offset_ms>,<drift_ppm>"; throws CLI::ValidationError naming the option.
void parse_clock_skew(Options& options) {
  if (options.clock_skew.empty()) return;
  const std::string& text = options.clock_skew;
  const auto comma = text.find(',');
  const auto bad = [&text](const std::string& why) {
    return CLI::ValidationError("--clock-skew '" + text + "': " + why +
                                " (expected <offset_ms>,<drift_ppm>)");
  };
  if (comma == std::string::npos) throw bad("no comma");
  double offset_ms = 0;
  double drift_ppm = 0;
  try {
    std::size_t used = 0;
    offset_ms = std::stod(text.substr(0, comma), &used);
    if (used != comma) throw bad("offset is not a number");
    const std::string drift_text = text.substr(comma + 1);
    drift_ppm = std::stod(drift_text, &used);
    if (used != drift_text.size()) throw bad("drift is not a number");
  } catch (const std::logic_error&) {
    throw bad("not two numbers");
  }
  if (!std::isfinite(offset_ms) || std::abs(offset_ms) > 3.6e6) throw bad("offset beyond ±1 h");
  if (!std::isfinite(drift_ppm) || std::abs(drift_ppm) > 1e4) throw bad("drift beyond ±10000 ppm");
  options.skew_offset_ns = static_cast<TimeNs>(std::llround(offset_ms * 1e6));
  options.skew_drift_ppm = drift_ppm;
}

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

// Counts what went wrong with frames and commands, by reason, and remembers the last error.
struct NodeCounters {
  std::map<std::string, std::uint64_t> counts;
  std::string last_error;
  void count(const std::string& reason, const std::string& message) {
    const std::uint64_t n = ++counts[reason];
    last_error = message;
    // The first few of each kind are logged; after that only every 1000th, so a broken camera
    // cannot flood the log.
    if (n <= 3 || n % 1000 == 0) log(message + " (" + reason + " #" + std::to_string(n) + ")");
  }
};

std::string counters_line(const panoptes::camera::SourceCounters& counters) {
  std::string line;
  for (const auto& [name, value] : counters)
    line += (line.empty() ? "" : " ") + name + "=" + std::to_string(value);
  return line.empty() ? "none" : line;
}

// Detects blobs in a captured frame (or takes the blobs a feature source delivered). nullopt when
// the frame is unusable; the reason is counted.
std::optional<panoptes::FeatureFrame> detect_frame(cam::Detector& detector,
                                                   const cam::CapturedFrame& captured,
                                                   const std::string& camera_id,
                                                   std::span<const cam::SearchWindow> windows,
                                                   NodeCounters& counters, const cam::SourceInfo& info) {
  const TimeNs begin = panoptes::monotonic_now_ns();
  panoptes::FeatureFrame frame;
  if (captured.blobs) {
    frame.blobs = *captured.blobs;
  } else {
    const panoptes::Image& image = captured.image;
    if (image.width <= 0 || image.height <= 0) {
      counters.count("empty_frame", "frame " + std::to_string(captured.sequence) + " has no pixels");
      return std::nullopt;
    }
    try {
      frame.blobs = detector.detect(image, windows);
    } catch (const std::exception& error) {
      counters.count("bad_frame", "frame " + std::to_string(captured.sequence) + ": " + error.what());
      return std::nullopt;
    }
    if (info.offset_x != 0 || info.offset_y != 0) {
      for (panoptes::Blob& blob : frame.blobs) {
        blob.x += info.offset_x;
        blob.y += info.offset_y;
        blob.x0 += info.offset_x;
        blob.x1 += info.offset_x;
        blob.y0 += info.offset_y;
        blob.y1 += info.offset_y;
      }
    }
  }
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
  NodeCounters counters;
  // next() may block for long (a camera that is gone is retried until stop()): a signal must
  // reach the source, not only this loop.
  std::atomic<bool> done{false};
  std::thread watcher([&] {
    while (!done.load() && !panoptes::stop_requested())
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    source.stop();
  });
  struct JoinOnExit {
    std::atomic<bool>& done;
    std::thread& thread;
    ~JoinOnExit() {
      done.store(true);
      thread.join();
    }
  } join_on_exit{done, watcher};
  while (!panoptes::stop_requested()) {
    std::optional<cam::CapturedFrame> captured;
    try {
      captured = source.next();
    } catch (const std::exception& error) {
      counters.count("source_error", error.what());
      break;
    }
    if (!captured) break;
    if (captured->arrival_ns == 0) captured->arrival_ns = panoptes::wall_now_ns();
    const auto frame = detect_frame(detector, *captured, camera_id, {}, counters, source.info());
    if (!frame) continue;
    blobs += frame->blobs.size();
    out.write(*frame);
    ++frames;
    if (!options.quiet && frames % 100 == 0) std::fprintf(stderr, "\r%s: %zu frames", g_name.c_str(), frames);
  }
  if (!options.quiet && frames >= 100) std::fprintf(stderr, "\n");
  log("wrote " + std::to_string(frames) + " frames with " + std::to_string(blobs) + " blobs to " +
      options.out_features);
  auto all = source.counters();
  for (const auto& [name, value] : counters.counts) all[name] += value;
  log("source counters: " + counters_line(all));
  if (const std::string error = source.last_error(); !error.empty()) log("source's last error: " + error);
  return panoptes::kExitOk;
}

// Predicted windows for this camera, written by the DDS listener, read by the detection loop.
class PredictionBox {
 public:
  void store(TimeNs stamp_ns, std::vector<cam::SearchWindow> windows) {
    std::lock_guard lock(mutex_);
    stamp_ns_ = stamp_ns;
    windows_ = std::move(windows);
    ++received_;
  }
  // The windows if they were predicted within `max_age_ns` of `frame_stamp_ns`, else empty (a
  // full-frame search).
  void fresh_for(TimeNs frame_stamp_ns, TimeNs max_age_ns, std::vector<cam::SearchWindow>& out) const {
    std::lock_guard lock(mutex_);
    out.clear();
    if (received_ > 0 && std::llabs(frame_stamp_ns - stamp_ns_) <= max_age_ns) out = windows_;
  }

 private:
  mutable std::mutex mutex_;
  TimeNs stamp_ns_ = 0;
  std::uint64_t received_ = 0;
  std::vector<cam::SearchWindow> windows_;
};

template <class T>
class Mailbox {
 public:
  void push(T value) {
    std::lock_guard lock(mutex_);
    if (items_.size() >= 256) items_.pop_front();  // a command storm must not grow memory
    items_.push_back(std::move(value));
  }
  std::deque<T> take_all() {
    std::lock_guard lock(mutex_);
    return std::exchange(items_, {});
  }

 private:
  std::mutex mutex_;
  std::deque<T> items_;
};

// The node's own clock, on which its stamps are read and which the time-sync client measures
// (docs/camera_node.md, "Clock synchronisation"). Normally the host's wall clock. A sim camera's
// scene `clock_offset` is part of it (that camera's stamps carry the offset), and --clock-skew, a
// testing aid, makes it run off by offset + drift · (wall − start). Everything the node stamps is
// read on this clock, so one correction fixes all of it.
class NodeClock {
 public:
  NodeClock(TimeNs start_wall_ns, TimeNs source_offset_ns, TimeNs skew_offset_ns, double skew_drift_ppm)
      : start_wall_ns_(start_wall_ns),
        source_offset_ns_(source_offset_ns),
        skew_offset_ns_(skew_offset_ns),
        skew_drift_(skew_drift_ppm * 1e-6) {}

  TimeNs now() const { return from_wall(panoptes::wall_now_ns()); }
  TimeNs from_wall(TimeNs wall_ns) const { return wall_ns + source_offset_ns_ + skew(wall_ns); }
  // A stamp delivered by the source (the wall clock plus the source's own offset).
  TimeNs from_source(TimeNs stamp_ns) const { return stamp_ns + skew(stamp_ns - source_offset_ns_); }

  bool skewed() const { return skew_offset_ns_ != 0 || skew_drift_ != 0; }
  double drift_ppm() const { return skew_drift_ * 1e6; }

 private:
  TimeNs skew(TimeNs wall_ns) const {
    return skew_offset_ns_ +
           static_cast<TimeNs>(std::llround(skew_drift_ * static_cast<double>(wall_ns - start_wall_ns_)));
  }

  TimeNs start_wall_ns_;
  TimeNs source_offset_ns_;
  TimeNs skew_offset_ns_;
  double skew_drift_;
};

// The scene's `clock_offset` of a sim:<scene>#<camera> source (0 for any other source).
TimeNs source_clock_offset_ns(const std::string& spec) {
  if (spec.rfind("sim:", 0) != 0) return 0;
  const auto hash = spec.rfind('#');
  if (hash == std::string::npos || hash < 4) return 0;
  const panoptes::Scene scene = panoptes::Scene::load(spec.substr(4, hash - 4));
  const panoptes::SimCameraConfig* camera = scene.find_camera(spec.substr(hash + 1));
  return camera != nullptr ? camera->clock_offset_ns : 0;
}

std::string format_ms(double ns) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3f", ns * 1e-6);
  return buffer;
}

std::string format_s(TimeNs ns) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2f", panoptes::ns_to_seconds(ns));
  return buffer;
}

std::string format_us(double ns) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%+.1f", ns * 1e-3);
  return buffer;
}

std::string format_ppm(double ppm) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2f", ppm);
  return buffer;
}

// One line on the state of the clock synchronisation; with a simulated skew also the truth (the
// time service is assumed to run on this host, whose wall clock is then the common time base).
std::string clock_sync_line(const panoptes::dds::TimeSyncClientStatus& status, const NodeClock& clock) {
  const panoptes::ClockEstimate& estimate = status.estimate;
  if (!estimate.synchronised) {
    return "not synchronised (" + std::to_string(status.requests) + " requests, " +
           std::to_string(status.replies) + " replies)";
  }
  const TimeNs wall = panoptes::wall_now_ns();
  const TimeNs local = clock.from_wall(wall);
  const auto offset = static_cast<double>(estimate.offset_at(local));
  std::string line = "offset " + format_ms(offset) + " ms";
  if (clock.skewed()) {
    const auto truth = static_cast<double>(local - wall);
    line += " (true " + format_ms(truth) + " ms, error " + format_us(offset - truth) + " us)";
  }
  line += ", drift " + format_ppm(estimate.drift_ppm()) + " ppm";
  if (clock.skewed()) line += " (true " + format_ppm(clock.drift_ppm()) + ")";
  char sigma[32];
  std::snprintf(sigma, sizeof sigma, "%.1f", estimate.offset_sigma_ns * 1e-3);
  line += ", sigma " + std::string(sigma) + " us, round trip min/median/max " +
          std::to_string(status.round_trip_min_ns / 1000) + "/" +
          std::to_string(status.round_trip_median_ns / 1000) + "/" +
          std::to_string(status.round_trip_max_ns / 1000) + " us, " + std::to_string(estimate.samples) +
          " samples fitted";
  return line;
}

// --latency-probe (tests/bench/bench_latency.cpp): right after each FeatureFrame, a LatencyProbe of
// the same serialized size, which estimator_node --latency-probe echoes at once. The bench so
// measures the raw DDS hops through the pipeline's own processes, under the same load, beside the
// pipeline (docs/protocol.md, "Latency probes").
class LatencyProbeSender {
 public:
  explicit LatencyProbeSender(panoptes::dds::Bus& bus)
      : writer_(bus.make_writer<panoptes::msg::LatencyProbe>()) {}

  // `frame` was written just now; `now_ns` is on the common time base.
  void send(const panoptes::msg::FeatureFrame& frame, TimeNs now_ns) {
    probe_.camera_id(frame.camera_id());
    probe_.frame(frame.frame());
    probe_.arrival_ns(frame.arrival_ns());
    probe_.processing_ns(frame.processing_ns());
    probe_.feature_publish_ns(frame.publish_ns());
    probe_.padding().clear();
    // The padding is last: each octet adds exactly one byte.
    const std::size_t size = panoptes::msg::FeatureFrame::getCdrSerializedSize(frame);
    const std::size_t bare = panoptes::msg::LatencyProbe::getCdrSerializedSize(probe_);
    probe_.padding().resize(size > bare ? size - bare : 0);
    probe_.publish_ns(now_ns);
    writer_->write(probe_);
  }

 private:
  std::unique_ptr<panoptes::dds::Writer<panoptes::msg::LatencyProbe>> writer_;
  panoptes::msg::LatencyProbe probe_;  // reused: no allocation per frame once the padding has grown
};

// Publishes feature frames with every stamp moved from the node's clock to the common time base.
// Until the clock is first synchronised, frames are held, at most until `hold_until_wall_ns`; if
// the time service has not answered by then they go out with the node's own stamps (counted as
// `unsynchronised`) until it does. Without a time-sync client (--no-clock-sync) stamps go out as
// read.
class FeaturePublisher {
 public:
  static constexpr std::size_t kHoldCapacity = 8192;  // frames; 16 s at 500 Hz

  FeaturePublisher(const NodeClock& clock, const panoptes::dds::TimeSyncClient* sync,
                   TimeNs hold_until_wall_ns, panoptes::dds::Writer<panoptes::msg::FeatureFrame>& writer,
                   panoptes::JsonlWriter* out)
      : clock_(clock), sync_(sync), hold_until_wall_ns_(hold_until_wall_ns), writer_(writer), out_(out) {}

  // A local stamp on the common time base (unchanged while not synchronised).
  TimeNs to_common(TimeNs local_ns) const {
    if (sync_ == nullptr) return local_ns;
    return sync_->to_server(local_ns).value_or(local_ns);
  }

  // `frame` has its stamps on the node's clock.
  void add(panoptes::FeatureFrame frame) {
    held_.push_back(std::move(frame));
    if (holding()) {
      ++held_total_;
      if (held_.size() > kHoldCapacity) {
        held_.pop_front();
        ++hold_overflow_;
      }
      return;
    }
    release(false);
  }

  // Publishes what is held once synchronised, or once the hold has timed out (or `force`).
  void release(bool force) {
    if (held_.empty() || (!force && holding())) return;
    std::optional<panoptes::ClockEstimate> estimate;
    if (sync_ != nullptr) {
      panoptes::ClockEstimate current = sync_->estimate();
      if (current.synchronised) estimate = current;
    }
    if (sync_ != nullptr && !estimate && !warned_) {
      warned_ = true;
      log("no time service answered within the hold time; publishing the node's own stamps until one does "
          "(counted as unsynchronised)");
    }
    for (panoptes::FeatureFrame& frame : held_) {
      if (estimate) {
        frame.stamp_ns = estimate->to_server(frame.stamp_ns);
        frame.arrival_ns = estimate->to_server(frame.arrival_ns);
      } else if (sync_ != nullptr) {
        ++unsynchronised_;
      }
      auto message = panoptes::dds::to_message(frame);
      const TimeNs now = clock_.now();
      message.publish_ns(estimate ? estimate->to_server(now) : now);
      send(std::move(message));
      if (out_ != nullptr) out_->write(frame);
    }
    held_.clear();
  }

  // --inject-loss / --inject-jitter-ms: a lossy, jittery link emulated in the sender, for hosts
  // whose kernel has no netem (docs/deployment.md). The network then sees fewer, later frames.
  void inject_faults(double loss, double jitter_ms, std::uint64_t seed) {
    loss_ = loss;
    jitter_ns_ = static_cast<TimeNs>(jitter_ms * 1e6);
    random_.seed(seed);
  }

  // --latency-probe: `probe` sends a probe after each frame written.
  void enable_latency_probe(LatencyProbeSender* probe) { probe_ = probe; }

  // Sends delayed frames whose time has come.
  void send_due() {
    const TimeNs now = panoptes::wall_now_ns();
    while (!delayed_.empty() && delayed_.begin()->first <= now) {
      write(delayed_.begin()->second);
      delayed_.erase(delayed_.begin());
    }
  }

  std::uint64_t injected_losses() const { return injected_losses_; }

  std::uint64_t held_total() const { return held_total_; }
  std::uint64_t unsynchronised() const { return unsynchronised_; }
  std::uint64_t hold_overflow() const { return hold_overflow_; }

 private:
  void send(panoptes::msg::FeatureFrame message) {
    if (loss_ > 0 && std::uniform_real_distribution<double>(0.0, 1.0)(random_) < loss_) {
      ++injected_losses_;
      return;
    }
    if (jitter_ns_ <= 0) {
      write(message);
      return;
    }
    const auto delay = std::uniform_int_distribution<TimeNs>(0, 2 * jitter_ns_)(random_);
    delayed_.emplace(panoptes::wall_now_ns() + delay, std::move(message));
    send_due();
  }

  void write(const panoptes::msg::FeatureFrame& message) {
    writer_.write(message);
    if (probe_ != nullptr) probe_->send(message, to_common(clock_.now()));
  }

  bool holding() const {
    return sync_ != nullptr && !sync_->synchronised() && panoptes::wall_now_ns() < hold_until_wall_ns_;
  }

  const NodeClock& clock_;
  const panoptes::dds::TimeSyncClient* sync_;
  TimeNs hold_until_wall_ns_;
  panoptes::dds::Writer<panoptes::msg::FeatureFrame>& writer_;
  panoptes::JsonlWriter* out_;
  std::deque<panoptes::FeatureFrame> held_;
  std::uint64_t held_total_ = 0;
  std::uint64_t unsynchronised_ = 0;
  std::uint64_t hold_overflow_ = 0;
  bool warned_ = false;
  double loss_ = 0;
  TimeNs jitter_ns_ = 0;
  std::mt19937_64 random_;
  std::multimap<TimeNs, panoptes::msg::FeatureFrame> delayed_;
  std::uint64_t injected_losses_ = 0;
  LatencyProbeSender* probe_ = nullptr;
};

int run_live(const Options& options, cam::FrameSource& source, cam::Detector& detector,
             const std::string& camera_id) {
  namespace msg = panoptes::msg;
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.participant_name = "camera_node/" + camera_id;
  const NodeClock clock(panoptes::wall_now_ns(), source_clock_offset_ns(options.source),
                        options.skew_offset_ns, options.skew_drift_ppm);
  panoptes::dds::Bus bus(bus_options);
  // Started first: the estimate converges while the rest starts up.
  std::unique_ptr<panoptes::dds::TimeSyncClient> time_sync;
  if (!options.no_clock_sync) {
    panoptes::dds::TimeSyncClientOptions sync_options;
    sync_options.client_id = camera_id;
    sync_options.local_clock = [clock] { return clock.now(); };
    time_sync = std::make_unique<panoptes::dds::TimeSyncClient>(bus, std::move(sync_options));
  }
  auto info_writer = bus.make_writer<msg::CameraInfo>();
  auto feature_writer = bus.make_writer<msg::FeatureFrame>();
  auto status_writer = bus.make_writer<msg::CameraStatus>();
  auto preview_writer = bus.make_writer<msg::CameraPreview>();

  Mailbox<cam::Command> commands;
  auto command_reader = bus.make_reader<msg::CameraCommand>([&commands](msg::CameraCommand&& message) {
    cam::Command command{message.target(), message.seq(), message.command(), {}};
    command.arguments.assign(message.arguments().begin(), message.arguments().end());
    commands.push(std::move(command));
  });
  PredictionBox predictions;
  // Only this camera's predictions: the estimator's writer filters, so per-camera traffic does not
  // grow with the number of cameras.
  auto prediction_reader = bus.make_reader<msg::Predictions>(
      [&predictions, &camera_id](msg::Predictions&& message) {
        if (message.camera_id() != camera_id) return;
        std::vector<cam::SearchWindow> windows;
        windows.reserve(message.windows().size());
        for (const msg::PredictedWindow& w : message.windows()) {
          windows.push_back({w.x(), w.y(), w.half_width(), w.half_height()});
        }
        predictions.store(message.stamp_ns(), std::move(windows));
      },
      panoptes::dds::Qos::kDefault, camera_id);

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
      std::optional<cam::CapturedFrame> captured;
      try {
        captured = source.next();
      } catch (const std::exception& error) {
        // Sources recover by themselves; one that throws has no way back, so the stream ends
        // (and is logged) instead of taking the process down.
        log(std::string("source failed: ") + error.what());
        break;
      }
      if (!captured) break;
      if (captured->arrival_ns == 0) captured->arrival_ns = panoptes::wall_now_ns();
      queue.push(std::move(*captured));
    }
    source_ended.store(true);
    queue.close();
  });

  cam::CommandHandler handler(camera_id, detector, source);
  cam::CommandEffects effects;
  NodeCounters counters;
  const TimeNs max_prediction_age_ns = static_cast<TimeNs>(options.prediction_max_age_ms * 1e6);
  std::vector<cam::SearchWindow> windows;
  std::vector<std::string> awaiting_frame;  // commands applied, logged with the first frame they govern
  const TimeNs start = panoptes::wall_now_ns();
  TimeNs next_status = start + panoptes::kNsPerSecond;
  std::uint64_t frames = 0;
  std::uint64_t frames_at_status = 0;
  std::uint64_t guided_frames = 0;
  Percentiles detect_ms;
  std::optional<panoptes::JsonlWriter> out;
  if (!options.out_features.empty()) out.emplace(options.out_features);
  FeaturePublisher publisher(clock, time_sync.get(),
                             start + panoptes::seconds_to_ns(options.clock_sync_wait_s), *feature_writer,
                             out ? &*out : nullptr);
  if (options.inject_loss > 0 || options.inject_jitter_ms > 0) {
    publisher.inject_faults(options.inject_loss, options.inject_jitter_ms,
                            std::hash<std::string>{}(camera_id));
    log("testing aid: dropping " + std::to_string(options.inject_loss) + " of the feature frames, delaying " +
        "the rest by 0.." + std::to_string(2 * options.inject_jitter_ms) + " ms");
  }
  std::optional<LatencyProbeSender> latency_probe;
  if (options.latency_probe) {
    latency_probe.emplace(bus);
    publisher.enable_latency_probe(&*latency_probe);
    log("benchmark aid: a latency probe follows each feature frame (rt/panoptes/latency_probe/request)");
  }
  bool logged_synchronised = false;

  while (!panoptes::stop_requested()) {
    // Commands apply between frames, so each one governs the very next frame.
    for (const cam::Command& command : commands.take_all()) {
      if (!handler.addressed_to_me(command)) continue;
      const std::string error = handler.apply(command, effects);
      if (error.empty()) {
        awaiting_frame.push_back("command " + command.command + " #" + std::to_string(command.seq));
      } else {
        counters.last_error = error;
        log("command #" + std::to_string(command.seq) + " rejected: " + error);
      }
    }
    auto captured = queue.pop(std::chrono::milliseconds(50));
    const TimeNs now = panoptes::wall_now_ns();
    if (captured) {
      // On the node's clock; predictions are on the common time base, like published stamps.
      const TimeNs local_stamp =
          clock.from_source(captured->stamp_ns != 0 ? captured->stamp_ns : captured->arrival_ns);
      const TimeNs stamp = publisher.to_common(local_stamp);
      predictions.fresh_for(stamp, max_prediction_age_ns, windows);
      auto frame = detect_frame(detector, *captured, camera_id, windows, counters, info);
      for (const std::string& applied : awaiting_frame) {
        log(applied + " applied from frame " + std::to_string(captured->sequence));
      }
      awaiting_frame.clear();
      if (frame) {
        detect_ms.add(static_cast<double>(frame->processing_ns) * 1e-6);
        ++frames;
        if (!windows.empty() && !captured->blobs) ++guided_frames;
        frame->stamp_ns = local_stamp;
        frame->arrival_ns = clock.from_wall(frame->arrival_ns);
        publisher.add(std::move(*frame));
      }
      if (effects.preview_requests > 0 && captured->image.width > 0) {
        const panoptes::Image preview = cam::make_preview(captured->image, effects.preview_max_width);
        msg::CameraPreview preview_message;
        preview_message.camera_id(camera_id);
        preview_message.stamp_ns(stamp);  // common time base once synchronised
        preview_message.width(static_cast<uint32_t>(preview.width));
        preview_message.height(static_cast<uint32_t>(preview.height));
        preview_message.pixels(preview.data);
        preview_writer->write(preview_message);
        --effects.preview_requests;
      }
    } else if (source_ended.load() && queue.size() == 0) {
      break;
    }
    publisher.release(false);
    publisher.send_due();
    if (time_sync && !logged_synchronised && time_sync->synchronised()) {
      logged_synchronised = true;
      const auto sync_status = time_sync->status();
      log("clock synchronised after " + format_s(now - start) + " s: " + clock_sync_line(sync_status, clock));
    }
    if (now >= next_status) {
      const double period = panoptes::ns_to_seconds(now - next_status) + 1.0;
      cam::SourceCounters all = source.counters();
      std::uint64_t source_drops = 0;
      for (const auto& [name, value] : all) source_drops += value;
      for (const auto& [name, value] : counters.counts) all[name] += value;
      for (const auto& [name, value] : handler.counters()) all[name] += value;
      all["drops_queue"] = queue.drops();
      all["guided_frames"] = guided_frames;
      if (publisher.injected_losses() > 0) all["injected_losses"] = publisher.injected_losses();
      msg::CameraStatus status;
      if (time_sync) {
        const auto sync_status = time_sync->status();
        if (sync_status.estimate.synchronised) {
          status.clock_offset_ns(sync_status.estimate.offset_at(clock.from_wall(now)));
          status.clock_drift_ppm(sync_status.estimate.drift_ppm());
        }
        all["sync_held"] = publisher.held_total();
        all["unsynchronised"] = publisher.unsynchronised();
        all["sync_lost"] = sync_status.lost;
        all["sync_rejected"] = sync_status.rejected;
        all["sync_resets"] = sync_status.resets;
        if (publisher.hold_overflow() > 0) all["sync_hold_overflow"] = publisher.hold_overflow();
        // A simulated skew is a test: its truth is known, so the error is logged every second.
        if (clock.skewed()) {
          log("clock sync at " + format_s(now - start) + " s: " + clock_sync_line(sync_status, clock));
        }
      }
      status.camera_id(camera_id);
      status.stamp_ns(publisher.to_common(clock.from_wall(now)));
      status.fps(static_cast<double>(frames - frames_at_status) / period);
      status.frames(frames);
      status.drops_queue(queue.drops());
      status.drops_source(source_drops);
      status.detect_p50_ms(detect_ms.at(0.5));
      status.detect_p99_ms(detect_ms.at(0.99));
      status.queue_depth(static_cast<uint32_t>(queue.size()));
      status.threshold(detector.config().threshold_for_bits(info.bits));
      status.exposure_us(source.control(cam::Control::kExposureUs).value_or(0.0));
      status.gain_db(source.control(cam::Control::kGainDb).value_or(0.0));
      const std::string source_error = source.last_error();
      status.last_error(counters.last_error.empty() ? source_error : counters.last_error);
      for (const auto& [name, value] : all) {
        msg::Counter counter;
        counter.name(name);
        counter.value(value);
        status.counters().push_back(counter);
      }
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
  publisher.release(true);
  // A reliable reader (a calibration capture) may still be owed repairs of the last frames.
  if (!feature_writer->wait_for_acknowledgments(std::chrono::seconds(1))) {
    log("some reliable readers did not acknowledge the last frames within 1 s");
  }
  if (time_sync) {
    const auto sync_status = time_sync->status();
    const double elapsed_s = panoptes::ns_to_seconds(panoptes::wall_now_ns() - start);
    char traffic[64];
    std::snprintf(traffic, sizeof traffic, "%.1f", static_cast<double>(sync_status.requests) / elapsed_s);
    std::string when = "never synchronised";
    if (sync_status.synchronised_local_ns != 0) {
      when = "synchronised " + format_s(sync_status.synchronised_local_ns - clock.from_wall(start)) +
             " s after start";
    }
    log("clock sync: " + clock_sync_line(sync_status, clock) + "; " + when + "; " +
        std::to_string(sync_status.requests) + " requests (" + traffic + "/s), " +
        std::to_string(sync_status.replies) + " replies, " + std::to_string(sync_status.lost) + " lost, " +
        std::to_string(sync_status.rejected) + " rejected, " + std::to_string(sync_status.resets) +
        " resets; frames held " + std::to_string(publisher.held_total()) + ", unsynchronised " +
        std::to_string(publisher.unsynchronised()));
  }
  log("stopped after " + std::to_string(frames) + " frames (" + std::to_string(queue.drops()) +
      " dropped in the queue, " + std::to_string(guided_frames) + " with prediction-guided search; " +
      std::to_string(prediction_reader->received()) + " predictions received)");
  auto all = source.counters();
  for (const auto& [name, value] : counters.counts) all[name] += value;
  for (const auto& [name, value] : handler.counters()) all[name] += value;
  if (publisher.injected_losses() > 0) all["injected_losses"] = publisher.injected_losses();
  log("source counters: " + counters_line(all));
  if (const std::string error = source.last_error(); !error.empty()) log("source's last error: " + error);
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"camera_node: detects IR blobs in camera frames and publishes 2D features (Panoptes)",
               "camera_node"};
  app.add_option("--source", options.source,
                 "sim:<scene.yaml>#<camera id> | images:<dir or glob> | aravis:<ip or device id> | "
                 "v4l2:/dev/videoN | features:<file.jsonl>")
      ->required();
  app.add_option("--camera-id", options.camera_id, "camera id to publish under (default: the source's)");
  app.add_option("--config", options.config_file,
                 "YAML with `detector:` (threshold, masks, ...) and `source:` (exposure_us, gain_db, "
                 "frame_rate_hz, roi, pixel_format, ...) sections; see docs/camera_node.md");
  app.add_flag("--no-dds", options.no_dds, "offline: no DDS; requires --out-features");
  app.add_option("--out-features", options.out_features, "write every FeatureFrame to this JSONL file");
  app.add_option("--dds-profile", options.dds_profile,
                 "Fast DDS XML profile (default: deploy/dds/loopback.xml)");
  app.add_option("--sim-epoch-ns", options.sim_epoch_ns,
                 "sim: wall-clock ns of scene time 0 (default: now, rounded up to a whole second); features: "
                 "wall-clock ns of the recording's epoch (its first stamp rounded down to a second), so "
                 "several replaying nodes stay aligned (default: the replay starts now)");
  app.add_option("--duration", options.duration_s, "stop after this many seconds (0 = until the source ends)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-frames", options.max_frames, "stop after this many frames")
      ->check(CLI::PositiveNumber);
  app.add_flag("--unpaced", options.unpaced,
               "sim, features: produce frames as fast as possible instead of in real time");
  app.add_option("--rate-scale", options.rate_scale, "features: replay speed (2 = twice the recorded pace)")
      ->check(CLI::PositiveNumber);
  app.add_option("--prediction-max-age-ms", options.prediction_max_age_ms,
                 "use predicted windows (rt/panoptes/predictions) only if stamped within this many ms of the "
                 "frame; otherwise search the full frame")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--queue-capacity", options.queue_capacity,
                 "frames waiting for detection before the oldest is dropped")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--no-clock-sync", options.no_clock_sync,
               "do not synchronise with the estimator's time service: publish stamps as read (for hosts "
               "kept on the common time base by PTP or chrony)");
  app.add_option("--clock-sync-wait", options.clock_sync_wait_s,
                 "hold frames up to this many seconds after start until the clock is synchronised; "
                 "later, unsynchronised stamps are published as read (and counted)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--clock-skew", options.clock_skew,
                 "testing aid: <offset_ms>,<drift_ppm>; the node's clock runs off the host's by offset + "
                 "drift * (time since start), for its frame stamps and its clock-sync requests alike");
  app.add_option("--inject-loss", options.inject_loss,
                 "testing aid: drop this fraction of feature frames before sending (a lossy link where "
                 "tc netem is unavailable)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--inject-jitter-ms", options.inject_jitter_ms,
                 "testing aid: send each feature frame after a random delay, uniform in [0, 2 x this] ms")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag(
      "--latency-probe", options.latency_probe,
      "benchmark aid: after each feature frame, write a probe of the same size on "
      "rt/panoptes/latency_probe/request for estimator_node --latency-probe to echo (bench_latency)");
  app.add_flag("--quiet", options.quiet, "less output");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (options.no_dds && options.out_features.empty())
          throw CLI::ValidationError("--no-dds needs --out-features");
        parse_clock_skew(options);
        if (options.no_dds && !options.clock_skew.empty())
          throw CLI::ValidationError(
              "--clock-skew tests the clock synchronisation over DDS; not with --no-dds");
      })) {
    return *exit_code;
  }

  panoptes::install_stop_handlers();
  std::unique_ptr<cam::FrameSource> source;
  cam::DetectorConfig detector_config;
  cam::SourceOptions source_options;
  try {
    if (!options.config_file.empty()) {
      const panoptes::YamlReader config(options.config_file, panoptes::load_yaml_file(options.config_file));
      config.expect_only({"detector", "source"});
      if (config.has("detector")) detector_config = cam::DetectorConfig::from_yaml(config.child("detector"));
      if (config.has("source"))
        source_options.settings = cam::SourceSettings::from_yaml(config.child("source"));
    }
    source_options.camera_id = options.camera_id;
    source_options.sim_epoch_ns = options.sim_epoch_ns;
    source_options.paced = !options.unpaced;
    source_options.max_frames = options.max_frames;
    source_options.rate_scale = options.rate_scale;
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
