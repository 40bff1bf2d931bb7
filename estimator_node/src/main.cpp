// SPDX-License-Identifier: Apache-2.0
// estimator_node: fuses the asynchronous 2D features of every camera into 3D tracks.
//   live:    subscribes to rt/panoptes/features and camera_info, publishes rt/panoptes/tracks,
//            predictions and estimator_status, and serves rt/panoptes/time_sync
//   offline: --no-dds --in-features <files...> --out-tracks <file>   (architecture.md, Contracts)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/calib/calibrate_cli.h"
#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/estimator/frame_screen.h"
#include "panoptes/estimator/inbox.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/estimator/usage.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/jsonl.h"
#include "panoptes/time.h"

namespace {

using panoptes::TimeNs;
namespace est = panoptes::estimator;

struct Options {
  std::string calibration_file;
  std::string bodies_file;
  std::vector<std::string> in_features;
  bool no_dds = false;
  std::string out_tracks;
  std::string out_poses;
  std::string dds_profile;
  double latency_window_ms = 20.0;
  double rewind_horizon_ms = 500.0;
  bool replay_arrival = false;
  double duration_s = 0.0;
  double status_period_s = 1.0;
  bool quiet = false;
  bool predictions = true;
  double prediction_margin_px = 3.0;
  std::size_t inbox_capacity = 4096;
  double prediction_horizon_ms = 0.0;  // body poses are published this far ahead (seed 000 Ch. 5)
  double bodies_poll_s = 1.0;          // live: how often the bodies file is checked for changes
  bool latency_probe = false;          // live, benchmark aid: echo camera_node's latency probes
  est::TrackerOptions tracker;
  est::FrameScreenOptions screen;
};

void log(const std::string& message) {
  std::fprintf(stderr, "estimator_node: %s\n", message.c_str());
}

// Warns once per camera about frames the tracker cannot use.
class UnknownCameraWarnings {
 public:
  void note(const std::string& camera_id) {
    if (warned_.size() < 64 && warned_.insert(camera_id).second) {
      log("camera '" + camera_id + "' has no calibration (T_world_cam): its frames are counted and ignored");
    }
  }

 private:
  std::set<std::string> warned_;
};

// The bodies file: loaded at start (an error is fatal) and, live, reloaded when it changes (an
// error keeps the previous definitions). Warns about bodies identification cannot tell apart.
class BodyFile {
 public:
  explicit BodyFile(std::string path) : path_(std::move(path)) {}
  bool enabled() const { return !path_.empty(); }

  // Throws ConfigError naming the file and body.
  void load(est::Tracker& tracker) {
    stamp_ = modified();
    const auto bodies = panoptes::load_bodies(path_);
    tracker.set_bodies(bodies, path_);
    std::size_t led = 0;
    for (const auto& body : bodies) led += body.kind == panoptes::BodyKind::kLed7 ? 1 : 0;
    log("tracking " + std::to_string(bodies.size()) + " rigid bod" + (bodies.size() == 1 ? "y" : "ies") +
        (led ? " (" + std::to_string(led) + " monocular 7-LED)" : "") + " from " + path_);
    for (const auto& warning :
         est::distinguishability_warnings(bodies, tracker.options().bodies.identification))
      log(path_ + ": warning: " + warning);
  }

  // Reloads if the file changed since the last load; a bad file is reported and ignored.
  void reload_if_changed(est::Tracker& tracker) {
    if (!enabled()) return;
    const auto now = modified();
    if (!now || now == stamp_) return;
    try {
      load(tracker);
    } catch (const std::exception& error) {
      stamp_ = now;  // report a bad version once
      log(std::string(error.what()) + " (keeping the previous body definitions)");
    }
  }

 private:
  std::optional<std::filesystem::file_time_type> modified() const {
    std::error_code error;
    const auto time = std::filesystem::last_write_time(path_, error);
    if (error) return std::nullopt;
    return time;
  }

  std::string path_;
  std::optional<std::filesystem::file_time_type> stamp_;
};

// Everything between a received frame and the tracker, shared by the offline and live modes:
// the screen for bad input, usage statistics, the tracker and its timing. admit() runs on DDS
// listener threads, process() on the estimator thread that owns the tracker; the lock covers only
// the screen and the statistics, so listeners never wait for a tracker update.
class Intake {
 public:
  Intake(est::Tracker& tracker, const Options& options)
      : tracker_(tracker), screen_(options.screen), options_(options) {}

  // Screens a frame that arrived at `frame.received_ns` (0: unknown). False: rejected, counted.
  // Live frames are also rejected when stamped ahead of the wall clock (`live`).
  bool admit(panoptes::FeatureFrame& frame, TimeNs reference_ns, bool live) {
    // In double: garbage stamps must not overflow.
    const double latency_ms =
        frame.received_ns != 0
            ? (static_cast<double>(frame.received_ns) - static_cast<double>(frame.stamp_ns)) * 1e-6
            : std::numeric_limits<double>::quiet_NaN();  // unknown
    std::lock_guard<std::mutex> lock(mutex_);
    monitor_.note_received(frame.camera_id, latency_ms);
    if (live ? screen_.screen_live(frame, reference_ns) : screen_.screen(frame, reference_ns)) return true;
    monitor_.note_dropped(frame.camera_id, "", 1);  // the reason is in the screen's counts
    return false;
  }

  est::FrameOutcome process(const panoptes::FeatureFrame& frame) {
    const auto start = std::chrono::steady_clock::now();
    const auto outcome = tracker_.process(frame);
    const double elapsed_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      monitor_.note_update_time(elapsed_ms);
    }
    if (outcome == est::FrameOutcome::kUnknownCamera) warnings_.note(frame.camera_id);
    return outcome;
  }

  // Estimator thread only (reads the tracker).
  est::EstimatorUsage usage(TimeNs stamp_ns, std::uint64_t inbox_drops) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto usage = monitor_.summarize(tracker_, stamp_ns, options_.latency_window_ms);
    for (const auto& [reason, n] : screen_.counts()) usage.counters[reason] += n;
    if (inbox_drops) usage.counters["inbox_overflow"] += inbox_drops;
    return usage;
  }

  void print_summary(std::uint64_t inbox_drops, std::size_t bad_lines) const {
    const auto& s = tracker_.stats();
    std::uint64_t rejected = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      rejected = screen_.stats().frames_rejected;
    }
    log("processed " + std::to_string(s.frames) + " frames (" + std::to_string(s.frames_late) +
        " late and replayed, " + std::to_string(s.frames_too_late) + " too late, " +
        std::to_string(s.frames_unknown_camera) + " from uncalibrated cameras, " + std::to_string(rejected) +
        " rejected, " + std::to_string(bad_lines) + " malformed lines); tracks created " +
        std::to_string(s.tracks_created) + ", confirmed " + std::to_string(s.tracks_confirmed) +
        ", ghosts removed " + std::to_string(s.ghosts_deleted));
    for (const auto& line : usage(tracker_.last_stamp_ns(), inbox_drops).lines()) log(line);
    if (tracker_.body_count() > 0) {
      const auto& b = tracker_.body_stats();
      log("bodies: identified " + std::to_string(b.identified) + ", acquired by one camera " +
          std::to_string(b.acquired_monocular) + ", re-identified " + std::to_string(b.reidentified) +
          ", lost " + std::to_string(b.lost) + ", marker updates " + std::to_string(b.marker_updates) +
          "; tracked now " + std::to_string(tracker_.current_poses().size()) + "/" +
          std::to_string(tracker_.body_count()));
    }
  }

 private:
  est::Tracker& tracker_;
  est::FrameScreen screen_;
  est::UsageMonitor monitor_;
  UnknownCameraWarnings warnings_;
  const Options& options_;
  mutable std::mutex mutex_;  // screen_ and monitor_
};

int run_offline(const Options& options, est::Tracker& tracker) {
  std::vector<panoptes::FeatureFrame> frames;
  std::size_t bad_lines = 0;
  for (const auto& file : options.in_features) {
    std::vector<std::string> errors;
    std::vector<panoptes::FeatureFrame> part;
    try {
      part = panoptes::read_feature_frames(file, &errors);
    } catch (const std::exception& error) {
      log(error.what());
      return panoptes::kExitBadInput;
    }
    for (std::size_t i = 0; i < errors.size() && i < 5; ++i) log("skipped " + errors[i]);
    if (errors.size() > 5) log("... and " + std::to_string(errors.size() - 5) + " more malformed lines");
    bad_lines += errors.size();
    frames.insert(frames.end(), std::make_move_iterator(part.begin()), std::make_move_iterator(part.end()));
  }
  // Timestamp order; ties broken by camera and frame so the run is deterministic.
  std::stable_sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) {
    return std::tie(a.stamp_ns, a.camera_id, a.frame) < std::tie(b.stamp_ns, b.camera_id, b.frame);
  });
  // Offline there is no wall clock: each stamp is judged against its neighbours'.
  const auto references = est::offline_reference_stamps(frames);

  // Order of delivery: by stamp, or (--replay-arrival) by the time each frame reached the
  // estimator, through the same time-ordered inbox as live mode, with simulated time.
  std::vector<std::size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  const auto received = [&](std::size_t i) {
    return frames[i].received_ns != 0 ? frames[i].received_ns : frames[i].stamp_ns;
  };
  if (options.replay_arrival) {
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return received(a) < received(b); });
  }

  std::optional<panoptes::JsonlWriter> out;
  if (!options.out_tracks.empty()) out.emplace(options.out_tracks);
  std::optional<panoptes::JsonlWriter> out_poses;
  if (!options.out_poses.empty()) out_poses.emplace(options.out_poses);
  const TimeNs horizon = panoptes::seconds_to_ns(options.prediction_horizon_ms * 1e-3);
  Intake intake(tracker, options);
  std::size_t records = 0, pose_records = 0;
  auto handle = [&](const panoptes::FeatureFrame& frame) {
    // Tracks and poses are written when the newest stamp advances; a replayed late frame refines
    // the state that the next frame's output shows.
    if (intake.process(frame) != est::FrameOutcome::kProcessed) return;
    if (out) {
      for (const auto& track : tracker.current_tracks()) {
        out->write(track);
        ++records;
      }
    }
    if (out_poses) {
      for (const auto& pose : tracker.current_poses(horizon)) {
        out_poses->write(pose);
        ++pose_records;
      }
    }
  };
  est::FrameInbox inbox(options.inbox_capacity, panoptes::seconds_to_ns(options.latency_window_ms * 1e-3));
  const std::size_t progress_every = std::max<std::size_t>(frames.size() / 10, 1);
  for (std::size_t n = 0; n < order.size(); ++n) {
    const std::size_t i = order[n];
    panoptes::FeatureFrame& frame = frames[i];
    if (options.replay_arrival && frame.received_ns == 0) frame.received_ns = frame.stamp_ns;
    if (intake.admit(frame, references[i], false)) {
      if (options.replay_arrival) {
        const TimeNs now = frame.received_ns;
        inbox.push(std::move(frame));
        for (const auto& due : inbox.pop_due(now)) handle(due);
      } else {
        handle(frame);
      }
    }
    if (!options.quiet && (n + 1) % progress_every == 0) {
      std::fprintf(stderr, "\restimator_node: %3zu%% (%zu/%zu frames, %zu live tracks)",
                   (n + 1) * 100 / frames.size(), n + 1, frames.size(), tracker.live_track_count());
    }
  }
  for (const auto& due : inbox.drain()) handle(due);
  if (!options.quiet && !frames.empty()) std::fprintf(stderr, "\n");
  intake.print_summary(inbox.drops(), bad_lines);
  log("wrote " + std::to_string(records) + " track records" +
      (out_poses ? ", " + std::to_string(pose_records) + " pose records" : ""));
  return panoptes::kExitOk;
}

panoptes::msg::EstimatorStatus to_message(const est::EstimatorUsage& usage) {
  panoptes::msg::EstimatorStatus message;
  message.stamp_ns(usage.stamp_ns);
  message.tracks_confirmed(static_cast<uint32_t>(usage.tracks_confirmed));
  message.tracks_tentative(static_cast<uint32_t>(usage.tracks_tentative));
  message.tracks_coasting(static_cast<uint32_t>(usage.tracks_coasting));
  message.frames(usage.frames);
  message.replays(usage.replays);
  message.update_p50_ms(usage.update_p50_ms);
  message.update_p99_ms(usage.update_p99_ms);
  message.latency_window_ms(usage.latency_window_ms);
  for (const auto& c : usage.cameras) {
    panoptes::msg::CameraUsage m;
    m.camera_id(c.camera_id);
    m.frames(c.frames);
    m.used(c.used);
    m.late(c.late);
    m.dropped(c.dropped);
    m.blobs(c.blobs);
    m.blobs_associated(c.associated);
    m.utilisation(c.utilisation);
    m.latency_p50_ms(c.latency_p50_ms);
    m.latency_p99_ms(c.latency_p99_ms);
    m.last_stamp_ns(c.last_stamp_ns);
    message.cameras().push_back(std::move(m));
  }
  for (const auto& [name, value] : usage.counters) {
    panoptes::msg::Counter counter;
    counter.name(name);
    counter.value(value);
    message.counters().push_back(std::move(counter));
  }
  return message;
}

// Frame period of each camera, to predict where its next frame will show the tracks.
class FramePeriods {
 public:
  // Returns the expected stamp of the camera's next frame.
  TimeNs next_stamp(const std::string& camera_id, TimeNs stamp_ns) {
    auto& p = periods_[camera_id];
    const TimeNs gap = stamp_ns - p.last_ns;
    if (p.last_ns != 0 && gap > 0 && gap < panoptes::kNsPerSecond)
      p.period_ns =
          p.period_ns == 0 ? static_cast<double>(gap) : 0.9 * p.period_ns + 0.1 * static_cast<double>(gap);
    p.last_ns = stamp_ns;
    return stamp_ns + static_cast<TimeNs>(p.period_ns);
  }

 private:
  struct Period {
    TimeNs last_ns = 0;
    double period_ns = 0;
  };
  std::map<std::string, Period> periods_;
};

// --latency-probe (tests/bench/bench_latency.cpp; docs/protocol.md, "Latency probes"). Echoes each
// LatencyProbe of camera_node --latency-probe at once, as a message of a BodyPose's serialized
// size, and traces when each processed frame arrived and when its output was written.
// The echo is written from the DDS listener thread that received the probe, not handed to the
// estimator thread: that hand-over (inbox, wake-up) is part of what the benchmark measures against
// the raw DDS floor, so the floor must not include it. Probes and feature frames reach this
// process on the same receive thread, so the probe after a frame is echoed once that frame is in
// the inbox, while the estimator thread works on it: both see the same contention.
class LatencyProbeEchoer {
 public:
  explicit LatencyProbeEchoer(panoptes::dds::Bus& bus)
      : echo_writer_(bus.make_writer<panoptes::msg::LatencyProbeEcho>()),
        trace_writer_(bus.make_writer<panoptes::msg::LatencyTraces>()),
        pose_size_(panoptes::msg::BodyPose::getCdrSerializedSize(panoptes::msg::BodyPose())),
        probe_reader_(bus.make_reader<panoptes::msg::LatencyProbe>(
            [this](panoptes::msg::LatencyProbe&& probe) { echo(std::move(probe)); })) {}

  // Estimator thread: echoes take the size of the BodyPose last written.
  void note_pose(const panoptes::msg::BodyPose& pose) {
    pose_size_.store(panoptes::msg::BodyPose::getCdrSerializedSize(pose), std::memory_order_relaxed);
  }

  // When the estimator thread took a frame, had updated the tracker with it and wrote its poses.
  struct Stamps {
    TimeNs dequeued_ns = 0;
    TimeNs updated_ns = 0;
    TimeNs poses_published_ns = 0;
    TimeNs pose_stamp_ns = 0;
    std::uint32_t poses = 0;
  };

  // Estimator thread, once everything `frame` caused was written. Sent in batches by flush().
  void trace(const panoptes::FeatureFrame& frame, const Stamps& stamps, TimeNs tracks_published_ns) {
    panoptes::msg::LatencyTrace trace;
    trace.camera_id(frame.camera_id);
    trace.frame(frame.frame);
    trace.stamp_ns(frame.stamp_ns);
    trace.arrival_ns(frame.arrival_ns);
    trace.processing_ns(frame.processing_ns);
    trace.received_ns(frame.received_ns);
    trace.dequeued_ns(stamps.dequeued_ns);
    trace.updated_ns(stamps.updated_ns);
    trace.poses_published_ns(stamps.poses_published_ns);
    trace.pose_stamp_ns(stamps.pose_stamp_ns);
    trace.poses(stamps.poses);
    trace.tracks_published_ns(tracks_published_ns);
    traces_.frames().push_back(std::move(trace));
  }

  // Estimator thread, when it has nothing more urgent to do: sends the traces every 20 ms (or all,
  // with `force`).
  void flush(TimeNs now_ns, bool force) {
    if (traces_.frames().empty() || (!force && now_ns - flushed_ns_ < kFlushPeriodNs)) return;
    trace_writer_->write(traces_);
    traces_.frames().clear();
    flushed_ns_ = now_ns;
  }

 private:
  // Listener thread (one at a time: the reader's listener is serialised).
  void echo(panoptes::msg::LatencyProbe&& probe) {
    const TimeNs received_ns = panoptes::wall_now_ns();
    echo_.probe(std::move(probe));
    echo_.probe().padding().clear();
    echo_.received_ns(received_ns);
    echo_.padding().clear();
    const std::size_t size = pose_size_.load(std::memory_order_relaxed);
    const std::size_t bare = panoptes::msg::LatencyProbeEcho::getCdrSerializedSize(echo_);
    echo_.padding().resize(size > bare ? size - bare : 0);  // last member: one byte per octet
    echo_.publish_ns(panoptes::wall_now_ns());
    echo_writer_->write(echo_);
  }

  static constexpr TimeNs kFlushPeriodNs = 20'000'000;

  std::unique_ptr<panoptes::dds::Writer<panoptes::msg::LatencyProbeEcho>> echo_writer_;
  std::unique_ptr<panoptes::dds::Writer<panoptes::msg::LatencyTraces>> trace_writer_;
  std::atomic<std::size_t> pose_size_;
  panoptes::msg::LatencyProbeEcho echo_;  // listener thread
  panoptes::msg::LatencyTraces traces_;   // estimator thread
  TimeNs flushed_ns_ = 0;
  // Last: destroyed first, so no echo runs while the rest goes.
  std::unique_ptr<panoptes::dds::Reader<panoptes::msg::LatencyProbe>> probe_reader_;
};

int run_live(const Options& options, est::Tracker& tracker, BodyFile& body_file) {
  namespace msg = panoptes::msg;
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.participant_name = "estimator_node";
  panoptes::dds::Bus bus(bus_options);
  if (!options.quiet) log("DDS profile " + bus.profile_file().string());

  // The common time base is this process's clock: camera nodes synchronise to it (architecture.md "Time").
  panoptes::dds::TimeSyncServer time_service(bus);

  est::FrameInbox inbox(options.inbox_capacity, panoptes::seconds_to_ns(options.latency_window_ms * 1e-3));
  std::mutex info_mutex;
  std::vector<panoptes::CameraCalibration> announced;  // from CameraInfo, applied on the estimator thread
  // DDS listener threads screen and count frames; the estimator thread owns the tracker.
  Intake intake(tracker, options);

  auto info_reader = bus.make_reader<msg::CameraInfo>([&](msg::CameraInfo&& info) {
    if (auto calibration = panoptes::dds::calibration_from(info); calibration && calibration->T_world_cam) {
      std::lock_guard<std::mutex> lock(info_mutex);
      announced.push_back(*calibration);
    }
  });
  auto feature_reader = bus.make_reader<msg::FeatureFrame>([&](msg::FeatureFrame&& message) {
    auto frame = panoptes::dds::from_message(message);
    frame.received_ns = panoptes::wall_now_ns();
    if (intake.admit(frame, frame.received_ns, true)) inbox.push(std::move(frame));
  });
  auto track_writer = bus.make_writer<msg::TrackFrame>();
  auto prediction_writer = bus.make_writer<msg::Predictions>();
  auto status_writer = bus.make_writer<msg::EstimatorStatus>();
  auto body_writer = bus.make_writer<msg::BodyPose>();
  std::optional<LatencyProbeEchoer> latency_probe;
  if (options.latency_probe) {
    latency_probe.emplace(bus);
    log("benchmark aid: echoing latency probes (rt/panoptes/latency_probe/...)");
  }

  std::optional<panoptes::JsonlWriter> out;
  if (!options.out_tracks.empty()) out.emplace(options.out_tracks);
  std::optional<panoptes::JsonlWriter> out_poses;
  if (!options.out_poses.empty()) out_poses.emplace(options.out_poses);
  const TimeNs horizon = panoptes::seconds_to_ns(options.prediction_horizon_ms * 1e-3);
  std::set<std::string> from_file;
  if (!options.calibration_file.empty()) {
    for (const auto& camera : panoptes::load_calibration(options.calibration_file).cameras)
      from_file.insert(camera.id);
  }

  FramePeriods periods;
  auto publish_predictions = [&](const panoptes::FeatureFrame& frame) {
    const TimeNs next = periods.next_stamp(frame.camera_id, frame.stamp_ns);
    if (!options.predictions || next == frame.stamp_ns) return;
    msg::Predictions message;
    message.camera_id(frame.camera_id);
    message.stamp_ns(next);
    for (const auto& w : tracker.predicted_windows(frame.camera_id, next, options.prediction_margin_px)) {
      msg::PredictedWindow window;
      window.track_id(w.track_id);
      window.x(static_cast<float>(w.x));
      window.y(static_cast<float>(w.y));
      window.half_width(static_cast<float>(w.half_width));
      window.half_height(static_cast<float>(w.half_height));
      message.windows().push_back(window);
    }
    prediction_writer->write(message);
  };
  // A frame's output in order of urgency: its poses right after the update (what applications
  // wait for); then, once no other frame is due, its TrackFrame, the predictions for its camera's
  // next frame, the files and the latency trace. So a frame that arrives while the previous one is
  // being processed waits for that update only, not for its housekeeping (issue 7, bench_latency).
  struct Processed {
    panoptes::FeatureFrame frame;
    std::vector<panoptes::TrackRecord> tracks;  // at its update
    std::vector<panoptes::PoseRecord> poses;
    LatencyProbeEchoer::Stamps stamps;  // --latency-probe
  };
  std::vector<Processed> processed;  // finished from the front; cleared (capacity kept) when all are
  std::size_t finished = 0;
  auto update = [&](panoptes::FeatureFrame&& frame) {
    const TimeNs dequeued_ns = latency_probe ? panoptes::wall_now_ns() : 0;
    if (intake.process(frame) != est::FrameOutcome::kProcessed) return;
    const TimeNs updated_ns = latency_probe ? panoptes::wall_now_ns() : 0;
    auto poses = tracker.current_poses(horizon);
    // Stamped before writing, like every publish_ns: delivery may complete within write().
    const TimeNs poses_published_ns = latency_probe && !poses.empty() ? panoptes::wall_now_ns() : 0;
    for (const auto& pose : poses) {
      const msg::BodyPose pose_message = panoptes::dds::to_message(pose);
      body_writer->write(pose_message);
      if (latency_probe) latency_probe->note_pose(pose_message);
    }
    const LatencyProbeEchoer::Stamps stamps{dequeued_ns, updated_ns, poses_published_ns,
                                            poses.empty() ? 0 : poses.front().stamp_ns,
                                            static_cast<std::uint32_t>(poses.size())};
    processed.push_back({std::move(frame), tracker.current_tracks(), std::move(poses), stamps});
  };
  auto finish = [&](Processed& done) {
    msg::TrackFrame message;
    message.stamp_ns(done.frame.stamp_ns);
    message.source_camera(done.frame.camera_id);
    message.source_frame(done.frame.frame);
    for (const auto& track : done.tracks) message.tracks().push_back(panoptes::dds::to_message(track));
    message.publish_ns(panoptes::wall_now_ns());
    track_writer->write(message);
    publish_predictions(done.frame);
    if (out) {
      for (const auto& track : done.tracks) out->write(track);
    }
    if (out_poses) {
      for (const auto& pose : done.poses) out_poses->write(pose);
    }
    if (latency_probe) {
      latency_probe->trace(done.frame, done.stamps, message.publish_ns());
    }
  };
  // Finishes processed frames while no other frame is due (all of them with `force`). True when
  // all are finished.
  auto finish_processed = [&](bool force) {
    while (finished < processed.size() && (force || !inbox.has_due(panoptes::wall_now_ns())))
      finish(processed[finished++]);
    if (finished < processed.size()) return false;
    processed.clear();
    finished = 0;
    return true;
  };

  const TimeNs start = panoptes::wall_now_ns();
  TimeNs next_status = start + panoptes::seconds_to_ns(options.status_period_s);
  TimeNs next_body_poll = start + panoptes::seconds_to_ns(options.bodies_poll_s);
  while (!panoptes::stop_requested()) {
    {
      std::lock_guard<std::mutex> lock(info_mutex);
      for (const auto& camera : announced) {
        // The calibration file wins over what a camera announces about itself.
        if (from_file.count(camera.id) == 0 && !tracker.has_camera(camera.id)) {
          tracker.set_camera(camera);
          log("camera '" + camera.id + "' calibrated from its CameraInfo");
        }
      }
      announced.clear();
    }
    const TimeNs now = panoptes::wall_now_ns();
    for (auto& frame : inbox.pop_due(now)) update(std::move(frame));
    if (!finish_processed(false)) continue;  // a frame is due: its update first
    if (latency_probe) latency_probe->flush(now, false);
    if (now >= next_body_poll) {
      next_body_poll = now + panoptes::seconds_to_ns(options.bodies_poll_s);
      body_file.reload_if_changed(tracker);
    }
    if (now >= next_status) {
      next_status += panoptes::seconds_to_ns(options.status_period_s);
      const est::EstimatorUsage usage = intake.usage(now, inbox.drops());
      status_writer->write(to_message(usage));
      if (!options.quiet) {
        std::string line =
            "t=" + std::to_string(static_cast<int>(panoptes::ns_to_seconds(now - start))) + "s";
        for (const auto& c : usage.cameras) {
          char buffer[96];
          std::snprintf(buffer, sizeof buffer, " %s %.0f%%", c.camera_id.c_str(), 100.0 * c.utilisation);
          line += buffer;
        }
        line += " | tracks " + std::to_string(usage.tracks_confirmed) + "+" +
                std::to_string(usage.tracks_coasting) + " coasting" +
                (tracker.body_count() ? " | bodies " + std::to_string(tracker.current_poses().size()) + "/" +
                                            std::to_string(tracker.body_count())
                                      : "") +
                " | replays " + std::to_string(usage.replays) + " | time sync answered " +
                std::to_string(time_service.answered());
        log(line);
      }
    }
    if (options.duration_s > 0 && now - start >= panoptes::seconds_to_ns(options.duration_s)) break;
    inbox.wait(panoptes::wall_now_ns(), std::chrono::milliseconds(1));  // wakes as frames arrive (issue 7)
  }
  for (auto& frame : inbox.drain()) update(std::move(frame));
  finish_processed(true);
  if (latency_probe) latency_probe->flush(panoptes::wall_now_ns(), true);
  intake.print_summary(inbox.drops(), 0);
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string_view(argv[1]) == "calibrate")
    return panoptes::calib::run_calibrate(argc - 1, argv + 1);
  Options options;
  CLI::App app{"estimator_node: fuses asynchronous camera features into 3D tracks (Panoptes)",
               "estimator_node"};
  app.add_option("--calibration", options.calibration_file, "calibration YAML (cameras with T_world_cam)");
  app.add_option("--bodies", options.bodies_file,
                 "rigid-body definitions YAML (docs/bodies.md); live, reloaded when the file changes");
  app.add_option("--in-features", options.in_features, "offline: FeatureFrame JSONL files (one per camera)")
      ->expected(1, -1);
  app.add_flag("--no-dds", options.no_dds, "offline: do not use DDS; requires --in-features");
  app.add_option("--out-tracks", options.out_tracks, "write every published TrackFrame as Track JSONL");
  app.add_option("--out-poses", options.out_poses, "write body poses as Pose JSONL (needs --bodies)");
  app.add_option("--prediction-horizon-ms", options.prediction_horizon_ms,
                 "publish body poses predicted this far ahead of the newest frame (seed 000 Ch. 5)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--dds-profile", options.dds_profile,
                 "Fast DDS XML profile (default: deploy/dds/loopback.xml)");
  app.add_option("--latency-window-ms", options.latency_window_ms,
                 "live: how long frames wait to be ordered by stamp")
      ->check(CLI::Range(0.0, 10000.0));
  app.add_flag("--replay-arrival", options.replay_arrival,
               "offline: deliver frames in the order they reached the estimator (received_ns), through the "
               "latency window, as live mode would");
  app.add_flag("!--no-predictions", options.predictions, "live: do not publish predicted windows");
  app.add_option("--prediction-margin-px", options.prediction_margin_px,
                 "live: pixels added around each predicted gate")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--rewind-horizon-ms", options.rewind_horizon_ms,
                 "late frames up to this much older than the newest are replayed, older ones dropped")
      ->check(CLI::Range(0.0, 60000.0));
  app.add_option("--duration", options.duration_s, "live: stop after this many seconds (0 = until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--status-period", options.status_period_s, "live: seconds between progress lines")
      ->check(CLI::PositiveNumber);
  app.add_flag("--latency-probe", options.latency_probe,
               "live, benchmark aid: echo camera_node --latency-probe probes at once and trace when each "
               "frame's output is written (rt/panoptes/latency_probe/..., bench_latency)");
  app.add_flag("--quiet", options.quiet, "no progress output");
  app.add_option("--process-noise", options.tracker.process_noise,
                 "σ² of white acceleration, m²/s³ (seed 003 A.48)")
      ->check(CLI::PositiveNumber);
  app.add_option("--measurement-noise-px", options.tracker.measurement_noise_px, "σ of a centroid, px")
      ->check(CLI::PositiveNumber);
  app.add_option("--confirm-cameras", options.tracker.confirm_cameras,
                 "distinct cameras that must see a new track before it is published")
      ->check(CLI::Range(2, 64));
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (options.no_dds && options.in_features.empty())
          throw CLI::ValidationError("--no-dds needs --in-features");
        if (!options.in_features.empty() && !options.no_dds) {
          throw CLI::ValidationError(
              "--in-features runs offline: add --no-dds (replaying onto DDS is camera_node's job)");
        }
        if (options.no_dds && options.calibration_file.empty()) {
          throw CLI::ValidationError("offline mode needs --calibration");
        }
        if (!options.out_poses.empty() && options.bodies_file.empty())
          throw CLI::ValidationError("--out-poses needs --bodies");
      })) {
    return *exit_code;
  }

  panoptes::install_stop_handlers();
  options.tracker.rewind_horizon_ns = panoptes::seconds_to_ns(options.rewind_horizon_ms * 1e-3);
  est::Tracker tracker(options.tracker);
  BodyFile body_file(options.bodies_file);
  try {
    if (!options.calibration_file.empty()) {
      const auto calibration = panoptes::load_calibration(options.calibration_file);
      tracker.set_calibration(calibration);
      for (const auto& camera : calibration.cameras) {
        if (!camera.T_world_cam)
          log("camera '" + camera.id + "' in " + options.calibration_file + " has no T_world_cam: ignored");
      }
    }
    if (body_file.enabled()) body_file.load(tracker);
    if (!options.quiet) {
      std::ostringstream printed;
      options.tracker.print(printed);
      std::fprintf(stderr, "%s", printed.str().c_str());
    }
  } catch (const panoptes::ConfigError& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  }

  try {
    return options.no_dds ? run_offline(options, tracker) : run_live(options, tracker, body_file);
  } catch (const panoptes::ConfigError& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitFailure;
  }
}
