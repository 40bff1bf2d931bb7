// SPDX-License-Identifier: Apache-2.0
#include "panoptes/time.h"

#include <cerrno>
#include <ctime>

namespace panoptes {

namespace {

TimeNs read_clock(clockid_t clock) {
  timespec now{};
  clock_gettime(clock, &now);
  return static_cast<TimeNs>(now.tv_sec) * kNsPerSecond + now.tv_nsec;
}

}  // namespace

TimeNs wall_now_ns() {
  return read_clock(CLOCK_REALTIME);
}

TimeNs monotonic_now_ns() {
  return read_clock(CLOCK_MONOTONIC);
}

void sleep_until_wall_ns(TimeNs wall_ns) {
  if (wall_ns <= 0) return;
  timespec deadline{};
  deadline.tv_sec = static_cast<time_t>(wall_ns / kNsPerSecond);
  deadline.tv_nsec = static_cast<long>(wall_ns % kNsPerSecond);
  // An absolute deadline on CLOCK_REALTIME keeps the wake-up correct across signals and clock
  // steps (chrony, the time-sync client); a relative sleep would drift by the interruption.
  while (clock_nanosleep(CLOCK_REALTIME, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
}

}  // namespace panoptes
