// SPDX-License-Identifier: Apache-2.0
// Live surface mode: DDS listener threads screen frames and queue them in a time-ordered inbox;
// one thread runs the SurfaceTracker and writes every frame's stroke events as one StrokeEvents
// sample (rt/panoptes/strokes), the counters in estimator_status, and serves the time service.
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/estimator/inbox.h"
#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/session/log.h"
#include "panoptes/surface_app/surface_mode.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/surface.h"

namespace panoptes::surface_app {
namespace {

using session::log;

// With no frame at all for this long, strokes are ended by the clock (cameras normally send frames
// without spots, which end them in the tracker).
constexpr TimeNs kSilenceNs = 200 * kNsPerMillisecond;

std::unique_ptr<dds::Bus> open_bus(const SurfaceLiveOptions& options) {
  dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.security = options.security;
  bus_options.participant_name = "estimator_node";
  auto bus = std::make_unique<dds::Bus>(bus_options);
  if (!options.quiet) log("DDS profile " + bus->profile_file().string() + " (surface mode)");
  return bus;
}

msg::StrokeEvent to_message(const surface::StrokeEvent& event) {
  msg::StrokeEvent m;
  m.phase(static_cast<std::uint8_t>(event.phase));
  m.stroke_id(event.stroke_id);
  m.stamp_ns(event.stamp_ns);
  m.position({event.position.x(), event.position.y()});
  m.velocity({event.velocity.x(), event.velocity.y()});
  m.acceleration({event.acceleration.x(), event.acceleration.y()});
  m.cameras(static_cast<std::uint16_t>(event.cameras));
  return m;
}

class SurfaceLive {
 public:
  SurfaceLive(const SurfaceLiveOptions& options, SurfaceSetup& setup, session::EstimatorSession& session)
      : options_(options),
        setup_(setup),
        session_(session),
        inbox_(session.config().node.inbox_capacity,
               static_cast<TimeNs>(options.latency_window_ms * static_cast<double>(kNsPerMillisecond))),
        bus_(open_bus(options)),
        time_service_(*bus_),
        stroke_writer_(bus_->make_writer<msg::StrokeEvents>()),
        status_writer_(bus_->make_writer<msg::EstimatorStatus>()),
        feature_reader_(bus_->make_reader<msg::FeatureFrame>([this](msg::FeatureFrame&& message) {
          auto frame = dds::from_message(message);
          frame.received_ns = wall_now_ns();
          if (session_.admit(frame, frame.received_ns, true)) inbox_.push(std::move(frame));
        })) {
    if (!options_.out_strokes.empty()) strokes_file_.emplace(options_.out_strokes);
  }
  SurfaceLive(const SurfaceLive&) = delete;
  SurfaceLive& operator=(const SurfaceLive&) = delete;
  ~SurfaceLive() { feature_reader_.reset(); }  // no listener may push into a dying inbox

  int run();

 private:
  void process(const FeatureFrame& frame);
  void publish(const std::vector<surface::StrokeEvent>& events, const std::string& camera, std::int64_t frame,
               TimeNs stamp_ns);
  void publish_status(TimeNs now, TimeNs start);

  const SurfaceLiveOptions& options_;
  SurfaceSetup& setup_;
  session::EstimatorSession& session_;
  estimator::FrameInbox inbox_;
  std::unique_ptr<dds::Bus> bus_;
  dds::TimeSyncServer time_service_;
  std::unique_ptr<dds::Writer<msg::StrokeEvents>> stroke_writer_;
  std::unique_ptr<dds::Writer<msg::EstimatorStatus>> status_writer_;
  std::unique_ptr<dds::Reader<msg::FeatureFrame>> feature_reader_;
  std::optional<JsonlWriter> strokes_file_;
  std::uint64_t unknown_camera_frames_ = 0;
  std::uint64_t events_published_ = 0;
  TimeNs last_stamp_ns_ = 0;  // of the newest processed frame
  TimeNs last_frame_wall_ns_ = 0;
};

void SurfaceLive::publish(const std::vector<surface::StrokeEvent>& events, const std::string& camera,
                          std::int64_t frame, TimeNs stamp_ns) {
  if (events.empty()) return;
  msg::StrokeEvents message;
  message.source_camera(camera);
  message.source_frame(frame);
  message.stamp_ns(stamp_ns);
  const auto& size = setup_.tracker->surface().size;
  message.surface_size({size.x(), size.y()});
  for (const auto& event : events) {
    message.events().push_back(to_message(event));
    if (strokes_file_)
      strokes_file_->write_line(stroke_json_line(
          event, event.camera >= 0 ? setup_.camera_ids[static_cast<std::size_t>(event.camera)] : ""));
  }
  message.publish_ns(wall_now_ns());
  stroke_writer_->write(message);
  events_published_ += events.size();
}

void SurfaceLive::process(const FeatureFrame& frame) {
  const int camera = setup_.camera_index(frame.camera_id);
  if (camera < 0) {
    ++unknown_camera_frames_;
    return;
  }
  const auto pixels = spot_pixels(frame);
  publish(setup_.tracker->add_frame(camera, frame.stamp_ns, pixels), frame.camera_id, frame.frame,
          frame.stamp_ns);
  last_stamp_ns_ = std::max(last_stamp_ns_, frame.stamp_ns);
  last_frame_wall_ns_ = wall_now_ns();
}

void SurfaceLive::publish_status(TimeNs now, TimeNs start) {
  auto usage = session_.usage(now);  // the screen's drop reasons
  msg::EstimatorStatus message;
  message.stamp_ns(now);
  message.frames(setup_.tracker->counters().frames);
  message.latency_window_ms(options_.latency_window_ms);
  auto counters = surface_counters(setup_.tracker->counters());
  counters["surface_unknown_camera"] += unknown_camera_frames_;
  counters["inbox_overflow"] += inbox_.drops();
  for (const auto& [reason, n] : bus_->receive_rejections()) usage.counters[reason] += n;
  for (const auto& [name, value] : usage.counters) counters[name] += value;
  for (const auto& [name, value] : counters) {
    msg::Counter counter;
    counter.name(name);
    counter.value(value);
    message.counters().push_back(std::move(counter));
  }
  status_writer_->write(message);
  if (options_.quiet) return;
  const auto& c = setup_.tracker->counters();
  log("t=" + std::to_string(static_cast<int>(ns_to_seconds(now - start))) + "s | strokes " +
      std::to_string(setup_.tracker->active_strokes()) + " active, " + std::to_string(c.strokes_begun) +
      " begun | frames " + std::to_string(c.frames) + " | spots off the surface " +
      std::to_string(c.off_surface) + " | late frames " + std::to_string(c.late_frames) +
      " | time sync answered " + std::to_string(time_service_.answered()));
}

int SurfaceLive::run() {
  const TimeNs start = wall_now_ns();
  const TimeNs status_period = seconds_to_ns(session_.config().node.status_period_s);
  TimeNs next_status = start + status_period;
  while (!stop_requested()) {
    const TimeNs now = wall_now_ns();
    for (const FeatureFrame& frame : inbox_.pop_due(now)) process(frame);
    if (last_frame_wall_ns_ != 0 && now - last_frame_wall_ns_ > kSilenceNs &&
        setup_.tracker->active_strokes() > 0)
      publish(setup_.tracker->end_silent(last_stamp_ns_ + (now - last_frame_wall_ns_)), "", 0,
              last_stamp_ns_);
    if (now >= next_status) {
      next_status += status_period;
      publish_status(now, start);
    }
    if (options_.duration_s > 0 && now - start >= seconds_to_ns(options_.duration_s)) break;
    inbox_.wait(wall_now_ns(), std::chrono::milliseconds(5));
  }
  for (const FeatureFrame& frame : inbox_.drain()) process(frame);
  publish(setup_.tracker->end_silent(last_stamp_ns_ + 2 * setup_.tracker->options().end_after_ns), "", 0,
          last_stamp_ns_);
  publish_status(wall_now_ns(), start);
  if (strokes_file_) strokes_file_->flush();
  if (!options_.quiet)
    log("surface mode: " + std::to_string(events_published_) + " stroke events published, " +
        std::to_string(setup_.tracker->counters().strokes_begun) + " strokes");
  return kExitOk;
}

}  // namespace

int run_surface_live(const SurfaceLiveOptions& options, SurfaceSetup& setup,
                     session::EstimatorSession& session) {
  SurfaceLive live(options, setup, session);
  return live.run();
}

}  // namespace panoptes::surface_app
