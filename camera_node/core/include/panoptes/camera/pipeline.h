// SPDX-License-Identifier: Apache-2.0
// camera_node's pipeline: source → bounded queue → detector → stamp correction → feature sink
// (docs/camera_node.md, "Inside camera_node: the pipeline"). A capture thread reads the source into
// the queue; run() detects and hands frames to the sink on the calling thread, applying commands
// between frames. The same object runs the offline mode (a JSONL sink) and the live mode (the DDS
// sink of panoptes_camera_app).
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <semaphore>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "panoptes/bounded_queue.h"
#include "panoptes/camera/camera_status.h"
#include "panoptes/camera/command.h"
#include "panoptes/camera/detector.h"
#include "panoptes/camera/mailbox.h"
#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/node_log.h"
#include "panoptes/camera/sources.h"
#include "panoptes/jsonl.h"

namespace panoptes::camera {

class CommandHandler;

// Where detected frames go.
class FeatureSink {
 public:
  virtual ~FeatureSink() = default;
  // A detected frame with its stamps on the node's clock.
  virtual void add(FeatureFrame&& frame) = 0;
  // Once per pass of the processing loop (at most ~50 ms apart): time-driven work.
  virtual void poll() {}
  // The stream ended or the pipeline stopped: deliver what is still held.
  virtual void finish() {}
};

// Writes every frame to a FeatureFrame JSONL file (offline: --no-dds --out-features).
class JsonlFeatureSink final : public FeatureSink {
 public:
  JsonlFeatureSink(const std::filesystem::path& path, bool quiet, const NodeLog& log);
  void add(FeatureFrame&& frame) override;
  void finish() override;
  std::size_t frames() const { return frames_; }
  std::size_t blobs() const { return blobs_; }

 private:
  JsonlWriter out_;
  bool quiet_;
  const NodeLog& log_;
  std::size_t frames_ = 0;
  std::size_t blobs_ = 0;
};

// Hooks of the live node into the processing loop (all called on the thread running run()).
class PipelineObserver {
 public:
  virtual ~PipelineObserver() = default;
  // The capture thread has started; `start_wall_ns` is the pipeline's start.
  virtual void on_start(TimeNs /*start_wall_ns*/) {}
  // After each pass of the loop (a frame or a 50 ms wait) and the sink's poll().
  virtual void on_pass(TimeNs /*wall_now_ns*/) {}
  // A preview requested by a command, of the frame stamped `stamp_ns` (common time base).
  virtual void on_preview(const Image& /*preview*/, TimeNs /*stamp_ns*/) {}
};

struct CameraPipelineOptions {
  std::string camera_id;
  std::size_t queue_capacity = 4;  // frames waiting for detection
  // false: a full queue drops its oldest frame (live: fresh frames matter more); true: the
  // capture thread waits for room (offline: every frame is processed).
  bool lossless = false;
  TimeNs prediction_max_age_ns = 0;  // predicted windows older than this are not used
  TimeNs duration_ns = 0;            // stop after this long (0 = until the source ends)
  bool stop_on_signal = true;        // SIGINT/SIGTERM (panoptes/process.h) stop the pipeline
  // A source that throws ends the stream; its message is logged ("source failed: ...") or
  // counted as `source_error` (offline).
  bool count_source_failure = false;
};

class CameraPipeline {
 public:
  CameraPipeline(CameraPipelineOptions options, FrameSource& source, Detector& detector,
                 const StampCorrection& stamps, FeatureSink& sink, const NodeLog& log);
  ~CameraPipeline();
  CameraPipeline(const CameraPipeline&) = delete;
  CameraPipeline& operator=(const CameraPipeline&) = delete;

  // Optional inputs and hooks; set before run().
  void set_commands(Mailbox<Command>* commands) { commands_ = commands; }
  void set_predictions(const PredictionBox* predictions) { predictions_ = predictions; }
  void set_observer(PipelineObserver* observer) { observer_ = observer; }

  // Runs until the source ends, the duration has passed or stop() is called; then stops the
  // source, drains the queue into the sink and finishes the sink.
  void run();
  // From any thread.
  void stop();

  // For the observer, on the thread running run().
  std::uint64_t frames() const { return frames_; }
  std::uint64_t guided_frames() const { return guided_frames_; }
  Percentiles& detect_times_ms() { return detect_ms_; }
  const NodeCounters& counters() const { return counters_; }
  const CounterMap& command_counters() const;
  std::uint64_t queue_drops() const { return queue_.drops(); }
  std::size_t queue_depth() const { return queue_.size(); }

 private:
  void capture_loop();
  bool stopping();
  void apply_commands();
  void process(const CapturedFrame& captured);
  void shut_down();

  const CameraPipelineOptions options_;
  FrameSource& source_;
  Detector& detector_;
  const StampCorrection& stamps_;
  FeatureSink& sink_;
  const NodeLog& log_;
  Mailbox<Command>* commands_ = nullptr;
  const PredictionBox* predictions_ = nullptr;
  PipelineObserver* observer_ = nullptr;

  BoundedQueue<CapturedFrame> queue_;
  std::unique_ptr<std::counting_semaphore<>> room_;  // lossless: free places in the queue
  std::atomic<bool> stop_{false};
  std::atomic<bool> source_ended_{false};
  std::string source_failure_;  // written by the capture thread before source_ended_
  std::thread capture_;

  NodeCounters counters_;
  std::unique_ptr<CommandHandler> handler_;
  CommandEffects effects_;
  std::vector<SearchWindow> windows_;        // reused: no allocation per frame
  std::vector<std::string> awaiting_frame_;  // commands applied, logged with the first frame they govern
  std::uint64_t frames_ = 0;
  std::uint64_t guided_frames_ = 0;
  std::uint64_t commands_rejected_ = 0;
  Percentiles detect_ms_;
};

// Detects blobs in a captured frame (or takes the blobs a feature source delivered), stamped as
// read. nullopt when the frame is unusable; the reason is counted.
std::optional<FeatureFrame> detect_frame(Detector& detector, const CapturedFrame& captured,
                                         const std::string& camera_id, std::span<const SearchWindow> windows,
                                         NodeCounters& counters, const SourceInfo& info);

struct OfflineOptions {
  std::string out_features;
  std::size_t queue_capacity = 4;
  bool quiet = false;
};

// --no-dds --out-features: every frame of the source through the pipeline into a JSONL file;
// logs what was written and the counters. Returns the exit code.
int run_offline(const OfflineOptions& options, FrameSource& source, Detector& detector,
                const std::string& camera_id, const NodeLog& log);

}  // namespace panoptes::camera
