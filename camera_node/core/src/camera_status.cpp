// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera/camera_status.h"

#include <algorithm>

namespace panoptes::camera {

double Percentiles::at(double q) {
  if (values_.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values_.size() - 1));
  std::nth_element(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(k), values_.end());
  return values_[k];
}

namespace {

void add_counters(CounterMap& into, const CounterMap& counters) {
  for (const auto& [name, value] : counters) into[name] += value;
}

}  // namespace

CameraStatusReport assemble_status(const StatusInputs& inputs) {
  CameraStatusReport report;
  CounterMap& all = report.counters;
  all = inputs.source_counters;
  for (const auto& [name, value] : inputs.source_counters) report.drops_source += value;
  add_counters(all, inputs.node_counters);
  add_counters(all, inputs.command_counters);
  all["drops_queue"] = inputs.queue_drops;
  all["guided_frames"] = inputs.guided_frames;
  if (inputs.injected_losses > 0) all["injected_losses"] = inputs.injected_losses;
  if (inputs.ptp_timed) all["ptp_timed"] = 1;
  if (inputs.clock_sync) {
    const ClockSyncFigures& sync = *inputs.clock_sync;
    if (sync.synchronised) {
      report.clock_offset_ns = sync.offset_ns;
      report.clock_drift_ppm = sync.drift_ppm;
    }
    all["sync_held"] = sync.held;
    all["unsynchronised"] = sync.unsynchronised;
    all["sync_lost"] = sync.lost;
    all["sync_rejected"] = sync.rejected;
    all["sync_resets"] = sync.resets;
    if (sync.hold_overflow > 0) all["sync_hold_overflow"] = sync.hold_overflow;
    if (sync.unmatched > 0) all["sync_unmatched_reply"] = sync.unmatched;
  }
  report.camera_id = inputs.camera_id;
  report.stamp_ns = inputs.stamp_ns;
  report.fps = static_cast<double>(inputs.frames_in_period) / inputs.period_s;
  report.frames = inputs.frames;
  report.drops_queue = inputs.queue_drops;
  report.detect_p50_ms = inputs.detect_p50_ms;
  report.detect_p99_ms = inputs.detect_p99_ms;
  report.queue_depth = inputs.queue_depth;
  report.threshold = inputs.threshold;
  report.exposure_us = inputs.exposure_us;
  report.gain_db = inputs.gain_db;
  report.last_error = inputs.node_last_error.empty() ? inputs.source_last_error : inputs.node_last_error;
  return report;
}

CounterMap final_counters(const SourceCounters& source, const CounterMap& node, const CounterMap& commands,
                          std::uint64_t injected_losses) {
  CounterMap all = source;
  add_counters(all, node);
  add_counters(all, commands);
  if (injected_losses > 0) all["injected_losses"] = injected_losses;
  return all;
}

std::string counters_line(const CounterMap& counters) {
  std::string line;
  for (const auto& [name, value] : counters)
    line += (line.empty() ? "" : " ") + name + "=" + std::to_string(value);
  return line.empty() ? "none" : line;
}

}  // namespace panoptes::camera
