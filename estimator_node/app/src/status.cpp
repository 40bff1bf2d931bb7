// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/status.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

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
  message.cameras_live(static_cast<uint32_t>(usage.cameras_live));
  message.cameras_lost(static_cast<uint32_t>(usage.cameras_lost));
  message.tracks_unobserved(static_cast<uint32_t>(usage.tracks_unobserved));
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
    m.state(static_cast<uint8_t>(c.state));
    m.since_last_frame_s(c.since_last_frame_s);
    m.refused_frames(c.refused_frames);
    m.refused_writers(c.refused_writers);
    message.cameras().push_back(std::move(m));
  }
  for (const auto& [name, value] : usage.counters) {
    msg::Counter counter;
    counter.name(name);
    counter.value(value);
    message.counters().push_back(std::move(counter));
  }
  for (const auto& health : usage.calibration)
    message.calibration().push_back(to_message(health, usage.stamp_ns));
  return message;
}

namespace {

msg::ResidualRegion to_message(const estimator::ResidualStats& stats) {
  msg::ResidualRegion region;
  region.samples(static_cast<uint32_t>(stats.samples));
  region.bias_px({stats.bias.x(), stats.bias.y()});
  region.spread_px(stats.spread_px);
  region.p_value(stats.p_value);
  return region;
}

}  // namespace

msg::CameraCalibrationHealth to_message(const estimator::CameraCalibrationHealth& health, TimeNs stamp_ns) {
  msg::CameraCalibrationHealth m;
  m.camera_id(health.camera_id);
  m.state(static_cast<uint8_t>(health.state));
  m.reason(health.reason);
  m.whole(to_message(health.whole));
  for (const auto& region : health.regions) m.regions().push_back(to_message(region));
  const bool quarantined = health.state == estimator::CalibrationState::kQuarantined;
  m.quarantined_for_s(quarantined ? std::max(0.0, ns_to_seconds(stamp_ns - health.quarantined_since_ns))
                                  : 0.0);
  m.residuals(health.residuals);
  m.quarantines(static_cast<uint32_t>(health.quarantines));
  m.releases(static_cast<uint32_t>(health.releases));
  m.blobs_withheld(health.blobs_withheld);
  return m;
}

namespace {

// " c0 100%", " c3 lost 1.2 s", and what a second writer for the camera had refused.
std::string camera_field(const estimator::CameraUsage& c) {
  char buffer[160];
  if (c.state == estimator::CameraState::kLost)
    std::snprintf(buffer, sizeof buffer, " %s lost %.1f s", c.camera_id.c_str(), c.since_last_frame_s);
  else
    std::snprintf(buffer, sizeof buffer, " %s %.0f%%", c.camera_id.c_str(), 100.0 * c.utilisation);
  std::string field = buffer;
  if (c.refused_frames > 0) {
    field += " (2nd writer refused: " + std::to_string(c.refused_frames) + " frames from " +
             std::to_string(c.refused_writers) + ")";
  }
  return field;
}

}  // namespace

std::string status_line(const estimator::EstimatorUsage& usage, const StatusLineExtras& extras) {
  std::string line = "t=" + std::to_string(static_cast<long long>(ns_to_seconds(extras.elapsed_ns))) + "s";
  if (usage.cameras_live + usage.cameras_lost > 0) {
    line += " cameras " + std::to_string(usage.cameras_live) + "/" +
            std::to_string(usage.cameras_live + usage.cameras_lost) + " live:";
  }
  for (const auto& c : usage.cameras) line += camera_field(c);
  // A quarantined camera with the reason; one with a small significant bias by name only.
  for (const auto& h : usage.calibration) {
    if (h.state == estimator::CalibrationState::kQuarantined) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, " %.1f s",
                    std::max(0.0, ns_to_seconds(usage.stamp_ns - h.quarantined_since_ns)));
      line += " | " + h.camera_id + " " + h.reason.substr(0, h.reason.find(':')) + seconds +
              h.reason.substr(h.reason.find(':'));
    } else if (h.state == estimator::CalibrationState::kSmallBias) {
      line += " | " + h.camera_id + " small calibration bias";
    }
  }
  line += " | tracks " + std::to_string(usage.tracks_confirmed) + "+" +
          std::to_string(usage.tracks_coasting) + " coasting";
  if (usage.tracks_unobserved > 0)
    line += " (no camera live: " + std::to_string(usage.tracks_unobserved) + " predicted only)";
  if (extras.bodies > 0)
    line += " | bodies " + std::to_string(extras.bodies_tracked) + "/" + std::to_string(extras.bodies);
  line += " | replays " + std::to_string(usage.replays) + " (" +
          std::to_string(std::lround(usage.replays_per_s)) + "/s) | cpu " +
          std::to_string(std::lround(usage.cpu_percent)) + "% | time sync answered " +
          std::to_string(extras.time_sync_answered);
  return line;
}

}  // namespace panoptes::estimator_app
