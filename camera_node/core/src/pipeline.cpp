// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera/pipeline.h"

#include <chrono>
#include <cstdio>
#include <utility>

#include "node_control.h"
#include "panoptes/process.h"

namespace panoptes::camera {

namespace {

constexpr auto kPassTimeout = std::chrono::milliseconds(50);

// Blobs found in a region of interest, moved to full-sensor pixels (the calibration's).
void shift_to_sensor(std::vector<Blob>& blobs, const SourceInfo& info) {
  if (info.offset_x == 0 && info.offset_y == 0) return;
  for (Blob& blob : blobs) {
    blob.x += info.offset_x;
    blob.y += info.offset_y;
    blob.x0 += info.offset_x;
    blob.x1 += info.offset_x;
    blob.y0 += info.offset_y;
    blob.y1 += info.offset_y;
  }
}

}  // namespace

std::optional<FeatureFrame> detect_frame(Detector& detector, const CapturedFrame& captured,
                                         const std::string& camera_id, std::span<const SearchWindow> windows,
                                         NodeCounters& counters, const SourceInfo& info) {
  const TimeNs begin = monotonic_now_ns();
  FeatureFrame frame;
  if (captured.blobs) {
    frame.blobs = *captured.blobs;
  } else {
    const Image& image = captured.image;
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
    shift_to_sensor(frame.blobs, info);
  }
  frame.processing_ns = monotonic_now_ns() - begin;
  frame.camera_id = camera_id;
  frame.frame = captured.sequence;
  // Image files carry no capture time: stamp them when they were read.
  frame.stamp_ns = captured.stamp_ns != 0 ? captured.stamp_ns : captured.arrival_ns;
  frame.arrival_ns = captured.arrival_ns;
  return frame;
}

JsonlFeatureSink::JsonlFeatureSink(const std::filesystem::path& path, bool quiet, const NodeLog& log)
    : out_(path), quiet_(quiet), log_(log) {}

void JsonlFeatureSink::add(FeatureFrame&& frame) {
  blobs_ += frame.blobs.size();
  out_.write(frame);
  ++frames_;
  if (!quiet_ && frames_ % 100 == 0) std::fprintf(stderr, "\r%s: %zu frames", log_.name().c_str(), frames_);
}

void JsonlFeatureSink::finish() {
  if (!quiet_ && frames_ >= 100) std::fprintf(stderr, "\n");
}

CameraPipeline::CameraPipeline(CameraPipelineOptions options, FrameSource& source, Detector& detector,
                               const StampCorrection& stamps, FeatureSink& sink, const NodeLog& log)
    : options_(std::move(options)),
      source_(source),
      detector_(detector),
      stamps_(stamps),
      sink_(sink),
      log_(log),
      queue_(options_.queue_capacity),
      counters_(log),
      handler_(std::make_unique<CommandHandler>(options_.camera_id, detector, source)) {
  if (options_.lossless) {
    room_ = std::make_unique<std::counting_semaphore<>>(static_cast<std::ptrdiff_t>(queue_.capacity()));
  }
}

CameraPipeline::~CameraPipeline() {
  if (capture_.joinable()) {
    stop();
    queue_.close();
    capture_.join();
  }
}

const CounterMap& CameraPipeline::command_counters() const {
  return handler_->counters();
}

void CameraPipeline::stop() {
  stop_.store(true);
  // next() may block for long (a camera that is gone is retried until stop()).
  source_.stop();
}

bool CameraPipeline::stopping() {
  if (options_.stop_on_signal && !stop_.load() && stop_requested()) stop();
  return stop_.load();
}

void CameraPipeline::capture_loop() {
  while (!stop_.load()) {
    std::optional<CapturedFrame> captured;
    try {
      captured = source_.next();
    } catch (const std::exception& error) {
      // Sources recover by themselves; one that throws has no way back, so the stream ends
      // instead of taking the process down.
      source_failure_ = error.what();
      break;
    }
    if (!captured) break;
    if (captured->arrival_ns == 0) captured->arrival_ns = wall_now_ns();
    if (room_) {
      while (!room_->try_acquire_for(kPassTimeout)) {
        if (stop_.load()) break;
      }
      if (stop_.load()) break;
    }
    queue_.push(std::move(*captured));
  }
  source_ended_.store(true);
  queue_.close();
}

void CameraPipeline::run() {
  capture_ = std::thread([this] { capture_loop(); });
  const TimeNs start = wall_now_ns();
  if (observer_ != nullptr) observer_->on_start(start);
  while (!stopping()) {
    apply_commands();
    auto captured = queue_.pop(kPassTimeout);
    const TimeNs now = wall_now_ns();
    if (captured) {
      if (room_) room_->release();
      process(*captured);
    } else if (source_ended_.load() && queue_.size() == 0) {
      break;
    }
    sink_.poll();
    if (observer_ != nullptr) observer_->on_pass(now);
    if (options_.duration_ns > 0 && now - start >= options_.duration_ns) break;
  }
  shut_down();
}

void CameraPipeline::shut_down() {
  stop();
  queue_.close();
  capture_.join();
  // Frames already captured are detected and delivered (the queue is drained, not dropped).
  while (auto captured = queue_.pop(std::chrono::milliseconds(0))) process(*captured);
  if (!source_failure_.empty()) {
    if (options_.count_source_failure) {
      counters_.count("source_error", source_failure_);
    } else {
      log_("source failed: " + source_failure_);
    }
  }
  sink_.finish();
}

// Commands apply between frames, so each one governs the very next frame.
void CameraPipeline::apply_commands() {
  if (commands_ == nullptr) return;
  for (const Command& command : commands_->take_all()) {
    if (!handler_->addressed_to_me(command)) continue;
    const std::string error = handler_->apply(command, effects_);
    if (error.empty()) {
      awaiting_frame_.push_back("command " + command.command + " #" + std::to_string(command.seq));
    } else {
      counters_.set_last_error(error);
      // A flood of bad commands must not flood the log: the first few, then one in 1000.
      constexpr std::uint64_t kLoggedInFull = 20;
      constexpr std::uint64_t kLogEvery = 1000;
      ++commands_rejected_;
      if (commands_rejected_ <= kLoggedInFull || commands_rejected_ % kLogEvery == 0) {
        log_("command #" + std::to_string(command.seq) + " rejected: " + error + " (" +
             std::to_string(commands_rejected_) + " rejected so far)");
      }
    }
  }
}

void CameraPipeline::process(const CapturedFrame& captured) {
  // On the node's clock; predictions are on the common time base, like published stamps.
  const NodeClock& clock = stamps_.clock();
  const TimeNs local_stamp =
      clock.from_source(captured.stamp_ns != 0 ? captured.stamp_ns : captured.arrival_ns);
  const TimeNs stamp = stamps_.to_common(local_stamp);
  if (predictions_ != nullptr) predictions_->fresh_for(stamp, options_.prediction_max_age_ns, windows_);
  auto frame = detect_frame(detector_, captured, options_.camera_id, windows_, counters_, source_.info());
  for (const std::string& applied : awaiting_frame_) {
    log_(applied + " applied from frame " + std::to_string(captured.sequence));
  }
  awaiting_frame_.clear();
  if (frame) {
    detect_ms_.add(static_cast<double>(frame->processing_ns) * 1e-6);
    ++frames_;
    if (!windows_.empty() && !captured.blobs) ++guided_frames_;
    frame->stamp_ns = local_stamp;
    frame->arrival_ns = clock.from_wall(frame->arrival_ns);
    sink_.add(std::move(*frame));
  }
  if (effects_.preview_requests > 0 && captured.image.width > 0) {
    if (observer_ != nullptr)
      observer_->on_preview(make_preview(captured.image, effects_.preview_max_width), stamp);
    --effects_.preview_requests;
  }
}

int run_offline(const OfflineOptions& options, FrameSource& source, Detector& detector,
                const std::string& camera_id, const NodeLog& log) {
  JsonlFeatureSink sink(options.out_features, options.quiet, log);
  const NodeClock identity;  // offline stamps are written as read
  const StampCorrection stamps(identity, nullptr);
  CameraPipelineOptions pipeline_options;
  pipeline_options.camera_id = camera_id;
  pipeline_options.queue_capacity = options.queue_capacity;
  pipeline_options.lossless = true;
  pipeline_options.count_source_failure = true;
  CameraPipeline pipeline(pipeline_options, source, detector, stamps, sink, log);
  pipeline.run();
  log("wrote " + std::to_string(sink.frames()) + " frames with " + std::to_string(sink.blobs()) +
      " blobs to " + options.out_features);
  log("source counters: " + counters_line(final_counters(source.counters(), pipeline.counters().counts(),
                                                         pipeline.command_counters(), 0)));
  if (const std::string error = source.last_error(); !error.empty()) log("source's last error: " + error);
  return kExitOk;
}

}  // namespace panoptes::camera
