// SPDX-License-Identifier: Apache-2.0
// Time on the common base: int64 nanoseconds everywhere (architecture.md, "Time").
#pragma once

#include <cstdint>

namespace panoptes {

using TimeNs = std::int64_t;

inline constexpr TimeNs kNsPerSecond = 1'000'000'000;
inline constexpr TimeNs kNsPerMillisecond = 1'000'000;

constexpr double ns_to_seconds(TimeNs ns) {
  return static_cast<double>(ns) * 1e-9;
}
constexpr TimeNs seconds_to_ns(double s) {
  return static_cast<TimeNs>(s * 1e9 + (s >= 0 ? 0.5 : -0.5));
}

// Wall clock (CLOCK_REALTIME): the common time base of a Panoptes system. Stamps in files
// and messages are absolute values of this clock (around 1.7e18).
TimeNs wall_now_ns();
// Monotonic clock for measuring durations inside one process.
TimeNs monotonic_now_ns();
// Sleeps until the wall clock reaches `wall_ns` (returns at once if it already has).
void sleep_until_wall_ns(TimeNs wall_ns);

}  // namespace panoptes
