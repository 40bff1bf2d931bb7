// SPDX-License-Identifier: Apache-2.0
#include "clock_sync_report.h"

#include <cstdio>

namespace panoptes::camera_app {

namespace {

std::string formatted(const char* format, double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

std::string format_ms(double ns) {
  return formatted("%.3f", ns * 1e-6);
}
std::string format_us(double ns) {
  return formatted("%+.1f", ns * 1e-3);
}
std::string format_ppm(double ppm) {
  return formatted("%.2f", ppm);
}

}  // namespace

std::string format_seconds(TimeNs ns) {
  return formatted("%.2f", ns_to_seconds(ns));
}

std::string clock_sync_line(const dds::TimeSyncClientStatus& status, const camera::NodeClock& clock) {
  const ClockEstimate& estimate = status.estimate;
  if (!estimate.synchronised) {
    return "not synchronised (" + std::to_string(status.requests) + " requests, " +
           std::to_string(status.replies) + " replies)";
  }
  const TimeNs wall = wall_now_ns();
  const TimeNs local = clock.from_wall(wall);
  const auto offset = static_cast<double>(estimate.offset_at(local));
  std::string line = "offset " + format_ms(offset) + " ms";
  if (clock.skewed()) {
    const auto truth = static_cast<double>(local - wall);
    line += " (true " + format_ms(truth) + " ms, error " + format_us(offset - truth) + " us)";
  }
  line += ", drift " + format_ppm(estimate.drift_ppm()) + " ppm";
  if (clock.skewed()) line += " (true " + format_ppm(clock.drift_ppm()) + ")";
  line += ", sigma " + formatted("%.1f", estimate.offset_sigma_ns * 1e-3) +
          " us, round trip min/median/max " + std::to_string(status.round_trip_min_ns / 1000) + "/" +
          std::to_string(status.round_trip_median_ns / 1000) + "/" +
          std::to_string(status.round_trip_max_ns / 1000) + " us, " + std::to_string(estimate.samples) +
          " samples fitted";
  return line;
}

}  // namespace panoptes::camera_app
