// SPDX-License-Identifier: Apache-2.0
// Maps a camera's own clock (device timestamps in ns) onto the common wall-clock time base from
// pairs (device time, host arrival time). Pure arithmetic, no camera library: unit-tested alone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>

#include "panoptes/time.h"

namespace panoptes::camera {

// A frame stamped by the device at d arrives at the host at h = d + offset(d) + delay, where
// offset drifts slowly (crystal error, tens to hundreds of ppm) and delay > 0 is the transfer and
// scheduling latency, which has a hard floor and a long tail upwards. The minimum of h - d over a
// window of frames is therefore a close, upper-biased-only sample of offset + floor; a line under
// those minima (the lower envelope) estimates offset and drift, and the tail never pulls it up.
//
// What it cannot know is the latency floor itself (microseconds on GigE Vision, the time to send
// one frame at most): mapped times are late by that constant.
class DeviceClockMapper {
 public:
  struct Options {
    std::size_t window_frames = 16;    // frames per minimum
    std::size_t history_windows = 64;  // minima kept for the fit (window_frames * this = frames)
    // Drift is fitted once the minima span this long; before, a slope from a short span would be
    // mostly latency noise (1 ms over 1 s is 1000 ppm) and the offset is held constant instead.
    TimeNs min_drift_span_ns = 5 * kNsPerSecond;
    double max_drift_ppm = 500;  // crystals stay within about 100 ppm: a steeper fit is noise
    // A sample further than this from the fitted envelope means the device clock restarted or a
    // clock was stepped: below at once (a frame cannot arrive before it was taken), above after
    // `jump_confirm_frames` in a row (a single frame may be that late).
    TimeNs jump_threshold_ns = 250 * kNsPerMillisecond;
    std::size_t jump_confirm_frames = 5;
  };

  DeviceClockMapper() : DeviceClockMapper(Options{}) {}
  explicit DeviceClockMapper(const Options& options);

  // Adds one frame's (device stamp, host arrival) and returns its device stamp mapped to host
  // time. The first frame after construction or a reset maps to its own arrival.
  TimeNs add(TimeNs device_ns, TimeNs host_ns);
  // Host time of a device stamp with the current estimate; nullopt before the first add().
  std::optional<TimeNs> map(TimeNs device_ns) const;

  void reset();
  std::size_t resets() const { return resets_; }  // automatic resets after jumps (not reset() calls)
  double drift_ppm() const { return slope_ * 1e6; }
  std::size_t samples() const { return samples_; }

 private:
  struct Point {
    double t = 0;       // device time - reference device time, ns
    double offset = 0;  // (host - device) - reference offset, ns
  };

  Point to_point(TimeNs device_ns, TimeNs host_ns) const;
  double envelope_at(double t) const { return intercept_ + slope_ * t; }
  void fit();
  void start(TimeNs device_ns, TimeNs host_ns);

  Options options_;
  bool started_ = false;
  TimeNs reference_device_ns_ = 0;
  TimeNs reference_offset_ns_ = 0;
  TimeNs last_device_ns_ = 0;
  std::deque<Point> minima_;  // one per completed window, oldest first
  Point window_min_;
  std::size_t window_count_ = 0;
  std::size_t samples_ = 0;
  std::size_t late_in_a_row_ = 0;
  std::size_t resets_ = 0;
  double intercept_ = 0;
  double slope_ = 0;
};

}  // namespace panoptes::camera
