// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/frame_clock.h"

#include <stdexcept>
#include <string>

namespace panoptes::session {

namespace {
constexpr std::int64_t kSecondNs = 1'000'000'000;

// Floor division (stamps before the epoch still map to the grid).
std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}
}  // namespace

FrameClock::FrameClock(int rate_hz) : rate_hz_(rate_hz) {
  if (rate_hz < 1 || rate_hz > kMaxRateHz)
    throw std::invalid_argument("frame rate " + std::to_string(rate_hz) + " Hz: must be 1.." +
                                std::to_string(kMaxRateHz));
}

std::int64_t FrameClock::index_at(TimeNs t_ns) const {
  const std::int64_t second = floor_div(t_ns, kSecondNs);
  const std::int64_t within = t_ns - second * kSecondNs;  // 0 .. 1e9 - 1
  // The largest k with floor(k * 1e9 / rate) <= within: k < (within + 1) * rate / 1e9.
  const std::int64_t k = ((within + 1) * rate_hz_ - 1) / kSecondNs;
  return second * rate_hz_ + k;
}

TimeNs FrameClock::instant(std::int64_t index) const {
  const std::int64_t second = floor_div(index, rate_hz_);
  const std::int64_t k = index - second * rate_hz_;
  return second * kSecondNs + k * kSecondNs / rate_hz_;
}

FrameTick FrameClock::emit(std::int64_t index) {
  if (!first_index_) first_index_ = index;
  last_index_ = index;
  ++published_;
  return {static_cast<std::uint64_t>(index - *first_index_) + 1, instant(index)};
}

std::optional<FrameTick> FrameClock::latest_due(TimeNs now_ns) {
  const std::int64_t index = index_at(now_ns);
  if (first_index_ && index <= last_index_) return std::nullopt;
  if (first_index_) skipped_ += static_cast<std::uint64_t>(index - last_index_ - 1);
  return emit(index);
}

std::optional<FrameTick> FrameClock::next_due(TimeNs now_ns) {
  const std::int64_t newest = index_at(now_ns);
  if (!first_index_) return emit(newest);
  if (last_index_ + 1 > newest) return std::nullopt;
  return emit(last_index_ + 1);
}

TimeNs FrameClock::next_instant() const {
  return first_index_ ? instant(last_index_ + 1) : 0;
}

Timecode FrameClock::timecode(TimeNs instant_ns) const {
  const std::int64_t index = index_at(instant_ns);
  const std::int64_t day_s = 86'400;
  const std::int64_t second = floor_div(index, rate_hz_);
  const std::int64_t of_day = second - floor_div(second, day_s) * day_s;
  Timecode tc;
  tc.frames = static_cast<int>(index - second * rate_hz_);
  tc.hours = static_cast<int>(of_day / 3600);
  tc.minutes = static_cast<int>(of_day / 60 % 60);
  tc.seconds = static_cast<int>(of_day % 60);
  return tc;
}

}  // namespace panoptes::session
