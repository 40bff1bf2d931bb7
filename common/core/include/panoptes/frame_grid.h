// SPDX-License-Identifier: Apache-2.0
// The grid of fixed-rate frame instants (docs/frames.md, "The output clock"): `rate_hz` periods
// aligned to whole seconds of the capture clock, period k of second s starting at
// s * 1e9 + floor(k * 1e9 / rate_hz) ns, so that every estimator and client agrees on them and a
// timecode follows from an instant alone. Integer maths only; the estimator's FrameClock and the
// client library's timecode both use it.
#pragma once

#include <cstdint>
#include <string>

#include "panoptes/time.h"

namespace panoptes {

// SMPTE-style timecode: hours:minutes:seconds:frames of the capture clock's day (UTC when the
// capture clock is the system clock), frames counting 0 .. rate - 1 within each second. For rates
// up to 30 it reads as non-drop-frame SMPTE timecode; above, as a high-rate timecode.
struct Timecode {
  int hours = 0, minutes = 0, seconds = 0, frames = 0;
};

// "HH:MM:SS:FF" (frames with as many digits as rate - 1 has, at least two).
std::string to_string(const Timecode& timecode, int rate_hz);

class FrameGrid {
 public:
  static constexpr int kMaxRateHz = 10000;
  // Throws std::invalid_argument (naming the rate) unless 1 <= rate_hz <= kMaxRateHz.
  explicit FrameGrid(int rate_hz);

  int rate_hz() const { return rate_hz_; }
  // The index of the newest instant at or before `t_ns`, and the instant of an index.
  std::int64_t index_at(TimeNs t_ns) const;
  TimeNs instant(std::int64_t index) const;
  // The timecode of the instant at or before `t_ns`.
  Timecode timecode(TimeNs t_ns) const;

 private:
  int rate_hz_;
};

}  // namespace panoptes
