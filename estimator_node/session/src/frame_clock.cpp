// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/frame_clock.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace panoptes::session {

FrameClock::FrameClock(int rate_hz) : grid_(rate_hz) {}

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

void FixedRateStats::add(TimeNs data_age, TimeNs publish_delay) {
  ++frames;
  if (data_age >= 0 && data_age_ns.size() < kMaxSamples) data_age_ns.push_back(data_age);
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
