// SPDX-License-Identifier: Apache-2.0
#include "device_clock.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <vector>

namespace panoptes::camera {

DeviceClockMapper::DeviceClockMapper(const Options& options) : options_(options) {
  assert(options_.window_frames >= 1 && options_.history_windows >= 1 && options_.jump_confirm_frames >= 1);
}

DeviceClockMapper::Point DeviceClockMapper::to_point(TimeNs device_ns, TimeNs host_ns) const {
  // Differences first, in integers: absolute stamps (~1.7e18) would lose ~256 ns as doubles.
  return Point{static_cast<double>(device_ns - reference_device_ns_),
               static_cast<double>((host_ns - device_ns) - reference_offset_ns_)};
}

void DeviceClockMapper::start(TimeNs device_ns, TimeNs host_ns) {
  started_ = true;
  reference_device_ns_ = device_ns;
  reference_offset_ns_ = host_ns - device_ns;
  last_device_ns_ = device_ns;
  minima_.clear();
  window_min_ = Point{};
  window_count_ = 1;
  late_in_a_row_ = 0;
  intercept_ = 0;
  slope_ = 0;
}

void DeviceClockMapper::reset() {
  started_ = false;
  minima_.clear();
  window_count_ = 0;
  late_in_a_row_ = 0;
  intercept_ = 0;
  slope_ = 0;
}

TimeNs DeviceClockMapper::add(TimeNs device_ns, TimeNs host_ns) {
  ++samples_;
  if (!started_) {
    start(device_ns, host_ns);
    return host_ns;
  }
  // A device clock runs forwards; going back means the camera restarted (its counter from 0).
  if (device_ns < last_device_ns_) {
    ++resets_;
    start(device_ns, host_ns);
    return host_ns;
  }
  last_device_ns_ = device_ns;
  const Point point = to_point(device_ns, host_ns);
  const double residual = point.offset - envelope_at(point.t);
  const auto threshold = static_cast<double>(options_.jump_threshold_ns);
  if (residual < -threshold) {
    ++resets_;
    start(device_ns, host_ns);
    return host_ns;
  }
  if (residual > threshold) {
    if (++late_in_a_row_ >= options_.jump_confirm_frames) {
      ++resets_;
      start(device_ns, host_ns);
      return host_ns;
    }
    // Probably one very late frame: it says nothing about the envelope.
    return *map(device_ns);
  }
  late_in_a_row_ = 0;

  if (window_count_ == 0 || point.offset < window_min_.offset) window_min_ = point;
  if (++window_count_ >= options_.window_frames) {
    minima_.push_back(window_min_);
    if (minima_.size() > options_.history_windows) minima_.pop_front();
    window_count_ = 0;
  }
  fit();
  return *map(device_ns);
}

// The line under all minima that is highest at their mean time, i.e. the one that minimises the
// summed gaps above it: the lower-convex-hull edge spanning that mean (a linear programme whose
// optimum lies on a hull edge). Points above the envelope, however many, cannot move it.
void DeviceClockMapper::fit() {
  std::vector<Point> points(minima_.begin(), minima_.end());
  if (window_count_ > 0) points.push_back(window_min_);
  if (points.size() == 1) {
    slope_ = 0;
    intercept_ = points.front().offset;
    return;
  }
  // Points are in device-time order: frames arrive in order and a window's minimum lies inside it.
  std::vector<Point> hull;
  for (const Point& point : points) {
    while (hull.size() >= 2) {
      const Point& a = hull[hull.size() - 2];
      const Point& b = hull.back();
      const double cross = (b.t - a.t) * (point.offset - a.offset) - (b.offset - a.offset) * (point.t - a.t);
      if (cross > 0) break;  // a left turn keeps b on the lower hull
      hull.pop_back();
    }
    hull.push_back(point);
  }
  double mean_t = 0;
  for (const Point& point : points) mean_t += point.t;
  mean_t /= static_cast<double>(points.size());

  slope_ = 0;
  const bool long_enough =
      points.back().t - points.front().t >= static_cast<double>(options_.min_drift_span_ns);
  for (std::size_t i = 0; long_enough && i + 1 < hull.size(); ++i) {
    if (hull[i + 1].t >= mean_t || i + 2 == hull.size()) {
      const double span = hull[i + 1].t - hull[i].t;
      slope_ = span > 0 ? (hull[i + 1].offset - hull[i].offset) / span : 0.0;
      break;
    }
  }
  const double max_slope = options_.max_drift_ppm * 1e-6;
  slope_ = std::clamp(slope_, -max_slope, max_slope);
  // With the slope fixed, the intercept is the highest that keeps every minimum above the line
  // (for an unclamped hull edge this is the edge itself).
  intercept_ = points.front().offset - slope_ * points.front().t;
  for (const Point& point : points) intercept_ = std::min(intercept_, point.offset - slope_ * point.t);
}

std::optional<TimeNs> DeviceClockMapper::map(TimeNs device_ns) const {
  if (!started_) return std::nullopt;
  const double t = static_cast<double>(device_ns - reference_device_ns_);
  return device_ns + reference_offset_ns_ + static_cast<TimeNs>(std::llround(envelope_at(t)));
}

}  // namespace panoptes::camera
