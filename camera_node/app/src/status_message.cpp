// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera_app/status_message.h"

namespace panoptes::camera_app {

msg::CameraStatus to_message(const camera::CameraStatusReport& report) {
  msg::CameraStatus status;
  status.camera_id(report.camera_id);
  status.stamp_ns(report.stamp_ns);
  status.fps(report.fps);
  status.frames(report.frames);
  status.drops_queue(report.drops_queue);
  status.drops_source(report.drops_source);
  status.detect_p50_ms(report.detect_p50_ms);
  status.detect_p99_ms(report.detect_p99_ms);
  status.queue_depth(report.queue_depth);
  status.threshold(report.threshold);
  status.exposure_us(report.exposure_us);
  status.gain_db(report.gain_db);
  status.clock_offset_ns(report.clock_offset_ns);
  status.clock_drift_ppm(report.clock_drift_ppm);
  status.last_error(report.last_error);
  for (const auto& [name, value] : report.counters) {
    msg::Counter counter;
    counter.name(name);
    counter.value(value);
    status.counters().push_back(counter);
  }
  return status;
}

}  // namespace panoptes::camera_app
