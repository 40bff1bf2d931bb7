// SPDX-License-Identifier: Apache-2.0
#include "panoptes/frame_grid.h"

#include <cstdio>
#include <stdexcept>

namespace panoptes {
namespace {

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

}  // namespace

std::string to_string(const Timecode& timecode, int rate_hz) {
  int digits = 2;
  for (int most = rate_hz - 1; most >= 100; most /= 10) ++digits;
  char text[48];
  std::snprintf(text, sizeof text, "%02d:%02d:%02d:%0*d", timecode.hours, timecode.minutes, timecode.seconds,
                digits, timecode.frames);
  return text;
}

FrameGrid::FrameGrid(int rate_hz) : rate_hz_(rate_hz) {
  if (rate_hz < 1 || rate_hz > kMaxRateHz)
    throw std::invalid_argument("frame rate " + std::to_string(rate_hz) + " Hz: must be 1.." +
                                std::to_string(kMaxRateHz));
}

std::int64_t FrameGrid::index_at(TimeNs t_ns) const {
  const std::int64_t second = floor_div(t_ns, kNsPerSecond);
  const std::int64_t within = t_ns - second * kNsPerSecond;  // 0 .. 1e9 - 1
  // The largest k with floor(k * 1e9 / rate) <= within: k < (within + 1) * rate / 1e9.
  const std::int64_t k = ((within + 1) * rate_hz_ - 1) / kNsPerSecond;
  return second * rate_hz_ + k;
}

TimeNs FrameGrid::instant(std::int64_t index) const {
  const std::int64_t second = floor_div(index, rate_hz_);
  const std::int64_t k = index - second * rate_hz_;
  return second * kNsPerSecond + k * kNsPerSecond / rate_hz_;
}

Timecode FrameGrid::timecode(TimeNs t_ns) const {
  const std::int64_t index = index_at(t_ns);
  constexpr std::int64_t kDayS = 86'400;
  const std::int64_t second = floor_div(index, rate_hz_);
  const std::int64_t of_day = second - floor_div(second, kDayS) * kDayS;
  Timecode tc;
  tc.frames = static_cast<int>(index - second * rate_hz_);
  tc.hours = static_cast<int>(of_day / 3600);
  tc.minutes = static_cast<int>(of_day / 60 % 60);
  tc.seconds = static_cast<int>(of_day % 60);
  return tc;
}

}  // namespace panoptes
