// SPDX-License-Identifier: Apache-2.0
// What camera_node reports about itself once a second (rt/panoptes/camera_status; the DDS adapter
// converts the plain report below into the message) and in its last log lines.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/camera/sources.h"
#include "panoptes/time.h"

namespace panoptes::camera {

// Detection-time percentiles over the last status period.
class Percentiles {
 public:
  void add(double value) { values_.push_back(value); }
  // The value at quantile `q` in [0, 1] (nearest rank, rounded down); 0 when empty.
  double at(double q);
  void clear() { values_.clear(); }
  std::size_t size() const { return values_.size(); }

 private:
  std::vector<double> values_;
};

using CounterMap = std::map<std::string, std::uint64_t>;

// The clock synchronisation's part of a status (only with a time-sync client).
struct ClockSyncFigures {
  bool synchronised = false;
  TimeNs offset_ns = 0;  // node clock minus common clock, now
  double drift_ppm = 0;
  std::uint64_t held = 0;            // frames held until synchronised, in total
  std::uint64_t unsynchronised = 0;  // frames published with the node's own stamps
  std::uint64_t hold_overflow = 0;   // held frames dropped because the hold was full
  std::uint64_t lost = 0;            // time-sync requests unanswered
  std::uint64_t rejected = 0;
  std::uint64_t unmatched = 0;  // replies echoing no pending request (late, or forged)
  std::uint64_t resets = 0;
};

// Everything a status is assembled from, gathered by the processing loop.
struct StatusInputs {
  std::string camera_id;
  TimeNs stamp_ns = 0;  // common time base
  double period_s = 1;  // since the last status
  std::uint64_t frames = 0;
  std::uint64_t frames_in_period = 0;
  std::uint64_t guided_frames = 0;
  std::uint64_t queue_drops = 0;
  std::uint32_t queue_depth = 0;
  std::uint64_t injected_losses = 0;
  SourceCounters source_counters;
  CounterMap node_counters;
  CounterMap command_counters;
  std::optional<ClockSyncFigures> clock_sync;
  bool ptp_timed = false;  // stamps are the camera's PTP time: no software clock sync (counter ptp_timed = 1)
  double detect_p50_ms = 0;
  double detect_p99_ms = 0;
  int threshold = 0;
  double exposure_us = 0;
  double gain_db = 0;
  std::string node_last_error;
  std::string source_last_error;
};

// The status as published (field for field the CameraStatus message).
struct CameraStatusReport {
  std::string camera_id;
  TimeNs stamp_ns = 0;
  double fps = 0;
  std::uint64_t frames = 0;
  std::uint64_t drops_queue = 0;
  std::uint64_t drops_source = 0;  // sum of the source's own counters
  double detect_p50_ms = 0;
  double detect_p99_ms = 0;
  std::uint32_t queue_depth = 0;
  int threshold = 0;
  double exposure_us = 0;
  double gain_db = 0;
  TimeNs clock_offset_ns = 0;  // 0 until synchronised
  double clock_drift_ppm = 0;
  std::string last_error;  // the node's own last error, else the source's
  CounterMap counters;     // by name: source, node, command, queue, clock-sync counters
};

CameraStatusReport assemble_status(const StatusInputs& inputs);

// The counters of the last "source counters:" log line: source, node and command counters, and
// injected losses when there were any.
CounterMap final_counters(const SourceCounters& source, const CounterMap& node, const CounterMap& commands,
                          std::uint64_t injected_losses);

// "a=1 b=2", or "none".
std::string counters_line(const CounterMap& counters);

}  // namespace panoptes::camera
