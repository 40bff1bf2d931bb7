// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera_app/live_camera.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string_view>
#include <utility>

#include "clock_sync_report.h"
#include "panoptes/camera_app/status_message.h"
#include "panoptes/dds/convert.h"
#include "panoptes/process.h"

namespace panoptes::camera_app {

namespace {

dds::Bus make_bus(const LiveOptions& options, const std::string& camera_id) {
  dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.security = options.security;
  bus_options.participant_name = "camera_node/" + camera_id;
  return dds::Bus(bus_options);
}

// Started first: the estimate converges while the rest starts up.
std::unique_ptr<dds::TimeSyncClient> make_time_sync(dds::Bus& bus, const LiveOptions& options,
                                                    const camera::SourceInfo& info,
                                                    const std::string& camera_id,
                                                    const camera::NodeClock& clock) {
  if (!uses_clock_sync(options, info)) return nullptr;
  dds::TimeSyncClientOptions sync_options;
  sync_options.client_id = camera_id;
  sync_options.local_clock = [clock] { return clock.now(); };
  return std::make_unique<dds::TimeSyncClient>(bus, std::move(sync_options));
}

// Why predicted windows cannot be used ("" if they can): the detector turns them into pixel
// ranges, so NaN, infinite or absurd sizes are dropped here.
std::string_view predictions_problem(const msg::Predictions& message) {
  constexpr std::size_t kMaxWindows = 4096;
  constexpr float kMaxPx = 1e5F;
  if (message.windows().size() > kMaxWindows) return "prediction_too_many_windows";
  for (const msg::PredictedWindow& w : message.windows()) {
    for (const float v : {w.x(), w.y(), w.half_width(), w.half_height()}) {
      if (!std::isfinite(v)) return "prediction_non_finite";
      if (std::fabs(v) > kMaxPx) return "prediction_out_of_range";
    }
    if (w.half_width() < 0 || w.half_height() < 0) return "prediction_out_of_range";
  }
  return {};
}

// Why a command is dropped before it is queued ("" if it is not): sizes no real command has, which
// would let a command storm hold much memory in the queue. Its meaning is judged when applied.
std::string_view command_problem(const msg::CameraCommand& message) {
  constexpr std::size_t kMaxArguments = 256;
  constexpr std::size_t kMaxTextBytes = 65536;
  if (message.arguments().size() > kMaxArguments) return "command_too_large";
  std::size_t text = message.target().size() + message.command().size();
  for (const std::string& argument : message.arguments()) text += argument.size();
  return text > kMaxTextBytes ? "command_too_large" : "";
}

std::unique_ptr<dds::Reader<msg::Predictions>> make_prediction_reader(dds::Bus& bus,
                                                                      camera::PredictionBox& predictions,
                                                                      dds::ReceiveCounters& rejections,
                                                                      const std::string& camera_id) {
  // Only this camera's predictions: the estimator writes them through a writer in this camera's
  // partition, so per-camera traffic does not grow with the number of cameras.
  return bus.make_reader<msg::Predictions>(
      [&predictions, &rejections, &camera_id](msg::Predictions&& message) {
        if (message.camera_id() != camera_id) return;
        if (const std::string_view problem = predictions_problem(message); !problem.empty()) {
          rejections.note(problem);
          return;
        }
        std::vector<camera::SearchWindow> windows;
        windows.reserve(message.windows().size());
        for (const msg::PredictedWindow& w : message.windows()) {
          windows.push_back({w.x(), w.y(), w.half_width(), w.half_height()});
        }
        predictions.store(message.stamp_ns(), std::move(windows));
      },
      dds::Qos::kDefault, camera_id);
}

camera::CameraPipelineOptions pipeline_options(const LiveOptions& options, const std::string& camera_id) {
  camera::CameraPipelineOptions pipeline;
  pipeline.camera_id = camera_id;
  pipeline.queue_capacity = options.queue_capacity;
  pipeline.prediction_max_age_ns = static_cast<TimeNs>(options.prediction_max_age_ms * 1e6);
  pipeline.duration_ns = seconds_to_ns(options.duration_s);
  return pipeline;
}

}  // namespace

bool uses_clock_sync(const LiveOptions& options, const camera::SourceInfo& info) {
  return !options.no_clock_sync && !info.ptp_timed;
}

LiveCamera::LiveCamera(LiveOptions options, camera::FrameSource& source, camera::Detector& detector,
                       std::string camera_id, const camera::NodeLog& log)
    : options_(std::move(options)),
      source_(source),
      detector_(detector),
      camera_id_(std::move(camera_id)),
      log_(log),
      clock_(wall_now_ns(), camera::source_clock_offset_ns(options_.source_spec), options_.clock_skew),
      bus_(make_bus(options_, camera_id_)),
      time_sync_(make_time_sync(bus_, options_, source_.info(), camera_id_, clock_)),
      sync_view_(time_sync_ ? std::make_unique<TimeSyncClockView>(*time_sync_) : nullptr),
      stamps_(clock_, sync_view_.get()),
      // In this camera's DDS partition: what its permissions grant when secured (docs/security.md).
      info_writer_(bus_.make_writer<msg::CameraInfo>(dds::Qos::kDefault, {}, camera_id_)),
      feature_writer_(bus_.make_writer<msg::FeatureFrame>(dds::Qos::kDefault, {}, camera_id_)),
      status_writer_(bus_.make_writer<msg::CameraStatus>(dds::Qos::kDefault, {}, camera_id_)),
      preview_writer_(bus_.make_writer<msg::CameraPreview>(dds::Qos::kDefault, {}, camera_id_)),
      command_reader_(bus_.make_reader<msg::CameraCommand>(
          [this](msg::CameraCommand&& message) {
            if (const std::string_view problem = command_problem(message); !problem.empty()) {
              rejections_.note(problem);
              return;
            }
            camera::Command command{message.target(), message.seq(), message.command(), {}};
            command.arguments.assign(message.arguments().begin(), message.arguments().end());
            commands_.push(std::move(command));
          },
          dds::Qos::kDefault, camera_id_)),
      prediction_reader_(make_prediction_reader(bus_, predictions_, rejections_, camera_id_)),
      out_(options_.out_features.empty() ? nullptr : std::make_unique<JsonlWriter>(options_.out_features)),
      sink_(stamps_, *feature_writer_, out_.get(), log_),
      pipeline_(pipeline_options(options_, camera_id_), source_, detector_, stamps_, sink_, log_) {
  publish_camera_info();
  if (!options_.quiet) log_("publishing on DDS (profile " + bus_.profile_file().string() + ")");
  if (source_.info().ptp_timed && !options_.no_clock_sync) {
    log_("PTP-timed camera: its PTP stamps are published as capture times; software clock sync skipped");
  }
  if (options_.inject_loss > 0 || options_.inject_jitter_ms > 0) {
    sink_.inject_faults(camera::FaultInjector(options_.inject_loss, options_.inject_jitter_ms,
                                              std::hash<std::string>{}(camera_id_)));
    log_("testing aid: dropping " + std::to_string(options_.inject_loss) +
         " of the feature frames, delaying " + "the rest by 0.." +
         std::to_string(2 * options_.inject_jitter_ms) + " ms");
  }
  if (options_.latency_probe) {
    latency_probe_.emplace(bus_);
    sink_.enable_latency_probe(&*latency_probe_);
    log_("benchmark aid: a latency probe follows each feature frame (rt/panoptes/latency_probe/request)");
  }
  pipeline_.set_commands(&commands_);
  pipeline_.set_predictions(&predictions_);
  pipeline_.set_observer(this);
}

LiveCamera::~LiveCamera() = default;

void LiveCamera::publish_camera_info() {
  const camera::SourceInfo& info = source_.info();
  msg::CameraInfo camera_info;
  if (info.calibration) {
    camera_info = dds::to_camera_info(camera_id_, info.calibration->intrinsics, info.calibration->T_world_cam,
                                      info.calibration->moving);
  } else {
    camera_info.camera_id(camera_id_);
    camera_info.width(static_cast<uint32_t>(info.width));
    camera_info.height(static_cast<uint32_t>(info.height));
  }
  camera_info.model(info.model);
  camera_info.serial(info.serial);
  camera_info.backend(info.backend);
  camera_info.nominal_rate_hz(info.nominal_rate_hz);
  camera_info.stamp_ns(wall_now_ns());
  info_writer_->write(camera_info);
}

void LiveCamera::on_start(TimeNs start_wall_ns) {
  start_ = start_wall_ns;
  next_status_ = start_ + kNsPerSecond;
  sink_.set_hold_deadline(start_ + seconds_to_ns(options_.clock_sync_wait_s));
}

void LiveCamera::on_pass(TimeNs wall_now_ns) {
  if (time_sync_ && !logged_synchronised_ && time_sync_->synchronised()) {
    logged_synchronised_ = true;
    const auto sync_status = time_sync_->status();
    log_("clock synchronised after " + format_seconds(wall_now_ns - start_) +
         " s: " + clock_sync_line(sync_status, clock_));
  }
  if (wall_now_ns >= next_status_) publish_status(wall_now_ns);
}

void LiveCamera::on_preview(const Image& preview, TimeNs stamp_ns) {
  msg::CameraPreview message;
  message.camera_id(camera_id_);
  message.stamp_ns(stamp_ns);  // common time base once synchronised
  message.width(static_cast<uint32_t>(preview.width));
  message.height(static_cast<uint32_t>(preview.height));
  message.pixels(preview.data);
  preview_writer_->write(message);
}

void LiveCamera::publish_status(TimeNs wall_now_ns) {
  camera::StatusInputs inputs;
  inputs.period_s = ns_to_seconds(wall_now_ns - next_status_) + 1.0;
  inputs.source_counters = source_.counters();
  inputs.node_counters = pipeline_.counters().counts();
  // Samples dropped on receipt (docs/hostile_input.md).
  for (const auto& [reason, n] : bus_.receive_rejections()) inputs.node_counters[reason] += n;
  for (const auto& [reason, n] : rejections_.snapshot()) inputs.node_counters[reason] += n;
  if (const std::uint64_t overflow = commands_.dropped())
    inputs.node_counters["command_overflow"] += overflow;
  inputs.command_counters = pipeline_.command_counters();
  inputs.queue_drops = pipeline_.queue_drops();
  inputs.guided_frames = pipeline_.guided_frames();
  inputs.injected_losses = sink_.injected_losses();
  if (time_sync_) {
    const auto sync_status = time_sync_->status();
    camera::ClockSyncFigures sync;
    sync.synchronised = sync_status.estimate.synchronised;
    if (sync.synchronised) {
      sync.offset_ns = sync_status.estimate.offset_at(clock_.from_wall(wall_now_ns));
      sync.drift_ppm = sync_status.estimate.drift_ppm();
    }
    sync.held = sink_.hold().held_total();
    sync.unsynchronised = sink_.hold().unsynchronised();
    sync.hold_overflow = sink_.hold().hold_overflow();
    sync.lost = sync_status.lost;
    sync.rejected = sync_status.rejected;
    sync.unmatched = sync_status.unmatched;
    sync.resets = sync_status.resets;
    inputs.clock_sync = sync;
    // A simulated skew is a test: its truth is known, so the error is logged every second.
    if (clock_.skewed()) {
      log_("clock sync at " + format_seconds(wall_now_ns - start_) +
           " s: " + clock_sync_line(sync_status, clock_));
    }
  }
  inputs.ptp_timed = source_.info().ptp_timed;
  inputs.camera_id = camera_id_;
  inputs.stamp_ns = stamps_.to_common(clock_.from_wall(wall_now_ns));
  inputs.frames = pipeline_.frames();
  inputs.frames_in_period = pipeline_.frames() - frames_at_status_;
  camera::Percentiles& detect_ms = pipeline_.detect_times_ms();
  inputs.detect_p50_ms = detect_ms.at(0.5);
  inputs.detect_p99_ms = detect_ms.at(0.99);
  inputs.queue_depth = static_cast<std::uint32_t>(pipeline_.queue_depth());
  inputs.threshold = detector_.config().threshold_for_bits(source_.info().bits);
  inputs.exposure_us = source_.control(camera::Control::kExposureUs).value_or(0.0);
  inputs.gain_db = source_.control(camera::Control::kGainDb).value_or(0.0);
  inputs.node_last_error = pipeline_.counters().last_error();
  inputs.source_last_error = source_.last_error();
  status_writer_->write(to_message(camera::assemble_status(inputs)));
  frames_at_status_ = pipeline_.frames();
  detect_ms.clear();
  next_status_ = wall_now_ns + kNsPerSecond;
}

int LiveCamera::run() {
  pipeline_.run();
  // A reliable reader (a calibration capture) may still be owed repairs of the last frames.
  if (!feature_writer_->wait_for_acknowledgments(std::chrono::seconds(1))) {
    log_("some reliable readers did not acknowledge the last frames within 1 s");
  }
  log_summary();
  return kExitOk;
}

void LiveCamera::log_summary() {
  const camera::SyncHold& hold = sink_.hold();
  if (time_sync_) {
    const auto sync_status = time_sync_->status();
    const double elapsed_s = ns_to_seconds(wall_now_ns() - start_);
    char traffic[64];
    std::snprintf(traffic, sizeof traffic, "%.1f", static_cast<double>(sync_status.requests) / elapsed_s);
    std::string when = "never synchronised";
    if (sync_status.synchronised_local_ns != 0) {
      when = "synchronised " + format_seconds(sync_status.synchronised_local_ns - clock_.from_wall(start_)) +
             " s after start";
    }
    log_("clock sync: " + clock_sync_line(sync_status, clock_) + "; " + when + "; " +
         std::to_string(sync_status.requests) + " requests (" + traffic + "/s), " +
         std::to_string(sync_status.replies) + " replies, " + std::to_string(sync_status.lost) + " lost, " +
         std::to_string(sync_status.rejected) + " rejected, " + std::to_string(sync_status.resets) +
         " resets; frames held " + std::to_string(hold.held_total()) + ", unsynchronised " +
         std::to_string(hold.unsynchronised()));
  }
  log_("stopped after " + std::to_string(pipeline_.frames()) + " frames (" +
       std::to_string(pipeline_.queue_drops()) + " dropped in the queue, " +
       std::to_string(pipeline_.guided_frames()) + " with prediction-guided search; " +
       std::to_string(prediction_reader_->received()) + " predictions received)");
  const camera::CounterMap all =
      camera::final_counters(source_.counters(), pipeline_.counters().counts(), pipeline_.command_counters(),
                             sink_.injected_losses());
  log_("source counters: " + camera::counters_line(all));
  if (const std::string error = source_.last_error(); !error.empty()) log_("source's last error: " + error);
}

}  // namespace panoptes::camera_app
