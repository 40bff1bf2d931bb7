// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/status.h"

namespace panoptes::estimator_app {

msg::EstimatorStatus to_status_message(const estimator::EstimatorUsage& usage) {
  msg::EstimatorStatus message;
  message.stamp_ns(usage.stamp_ns);
  message.tracks_confirmed(static_cast<uint32_t>(usage.tracks_confirmed));
  message.tracks_tentative(static_cast<uint32_t>(usage.tracks_tentative));
  message.tracks_coasting(static_cast<uint32_t>(usage.tracks_coasting));
  message.frames(usage.frames);
  message.replays(usage.replays);
  message.replayed_frames(usage.replayed_frames);
  message.replays_per_s(usage.replays_per_s);
  message.replayed_frames_per_s(usage.replayed_frames_per_s);
  message.cpu_percent(usage.cpu_percent);
  message.update_p50_ms(usage.update_p50_ms);
  message.update_p99_ms(usage.update_p99_ms);
  message.latency_window_ms(usage.latency_window_ms);
  for (const auto& c : usage.cameras) {
    msg::CameraUsage m;
    m.camera_id(c.camera_id);
    m.frames(c.frames);
    m.used(c.used);
    m.late(c.late);
    m.dropped(c.dropped);
    m.too_late(c.too_late);
    m.blobs(c.blobs);
    m.blobs_associated(c.associated);
    m.utilisation(c.utilisation);
    m.latency_p50_ms(c.latency_p50_ms);
    m.latency_p99_ms(c.latency_p99_ms);
    m.last_stamp_ns(c.last_stamp_ns);
    message.cameras().push_back(std::move(m));
  }
  for (const auto& [name, value] : usage.counters) {
    msg::Counter counter;
    counter.name(name);
    counter.value(value);
    message.counters().push_back(std::move(counter));
  }
  return message;
}

}  // namespace panoptes::estimator_app
