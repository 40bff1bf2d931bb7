// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/frame_clock.h"

#include <algorithm>
#include <cstdio>
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

void FrameClock::idle_until(TimeNs now_ns) {
  if (!first_index_) return;
  const std::int64_t index = index_at(now_ns);
  if (index <= last_index_) return;
  idle_ += static_cast<std::uint64_t>(index - last_index_);
  last_index_ = index;
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

void FixedRateStats::add(TimeNs data_age, TimeNs publish_delay) {
  ++frames;
  if (data_age_ns.size() < kMaxSamples) data_age_ns.push_back(data_age);
  if (publish_delay >= 0 && publish_delay_ns.size() < kMaxSamples) publish_delay_ns.push_back(publish_delay);
}

namespace {
// "<what>: mean .. ms, p99 .. ms, max .. ms" of `samples` (sorted here).
std::string distribution(const char* what, std::vector<TimeNs> samples) {
  std::sort(samples.begin(), samples.end());
  double mean = 0;
  for (const TimeNs sample : samples) mean += static_cast<double>(sample);
  mean = samples.empty() ? 0.0 : mean / static_cast<double>(samples.size());
  const TimeNs p99 = samples.empty() ? 0 : samples[std::min(samples.size() - 1, samples.size() * 99 / 100)];
  char line[160];
  std::snprintf(line, sizeof line, "%s: mean %.3f ms, p99 %.3f ms, max %.3f ms", what, mean * 1e-6,
                static_cast<double>(p99) * 1e-6,
                samples.empty() ? 0.0 : static_cast<double>(samples.back()) * 1e-6);
  return line;
}
}  // namespace

std::string FixedRateStats::summary() const {
  std::string line = "fixed-rate: " + std::to_string(frames) + " frames; " +
                     distribution("instant - newest stamp", data_age_ns);
  if (!publish_delay_ns.empty()) line += "; " + distribution("publish - instant", publish_delay_ns);
  return line;
}

}  // namespace panoptes::session
