// SPDX-License-Identifier: Apache-2.0
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <thread>

#include <gtest/gtest.h>
#include <pthread.h>

#include "panoptes/time.h"

namespace panoptes {
namespace {

TEST(Time, WallClockIsAbsoluteRealtime) {
  const TimeNs ours = wall_now_ns();
  const TimeNs system = std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::system_clock::now().time_since_epoch())
                            .count();
  // Absolute epoch nanoseconds (~1.7e18), not a process-relative or monotonic count.
  EXPECT_GT(ours, 1'600'000'000 * kNsPerSecond);
  EXPECT_LT(std::abs(system - ours), kNsPerSecond);
}

TEST(Time, MonotonicClockNeverGoesBack) {
  TimeNs previous = monotonic_now_ns();
  for (int i = 0; i < 1000; ++i) {
    const TimeNs now = monotonic_now_ns();
    ASSERT_GE(now, previous);
    previous = now;
  }
}

TEST(Time, SecondsConversionRoundsToNearest) {
  EXPECT_EQ(seconds_to_ns(1.5), 1'500'000'000);
  EXPECT_EQ(seconds_to_ns(-0.25), -250'000'000);
  EXPECT_EQ(seconds_to_ns(1e-9 * 0.6), 1);
  EXPECT_DOUBLE_EQ(ns_to_seconds(2'500'000'000), 2.5);
}

TEST(Time, SleepUntilWallReachesDeadline) {
  const TimeNs deadline = wall_now_ns() + 30 * kNsPerMillisecond;
  sleep_until_wall_ns(deadline);
  EXPECT_GE(wall_now_ns(), deadline);
}

TEST(Time, SleepUntilPastDeadlineReturns) {
  const TimeNs start = monotonic_now_ns();
  sleep_until_wall_ns(wall_now_ns() - kNsPerSecond);
  // Generous bound: only catches a sleep that waits for the (past) deadline's full distance or more.
  EXPECT_LT(monotonic_now_ns() - start, kNsPerSecond / 2);
}

void ignore_signal(int) {}

TEST(Time, SleepUntilWallSurvivesSignals) {
  // A handler without SA_RESTART makes clock_nanosleep return EINTR early; the sleep must resume.
  struct sigaction action {};
  action.sa_handler = ignore_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  struct sigaction previous {};
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);

  const pthread_t sleeper = pthread_self();
  const TimeNs deadline = wall_now_ns() + 200 * kNsPerMillisecond;
  std::thread interrupter([sleeper] {
    for (int i = 0; i < 5; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      pthread_kill(sleeper, SIGUSR1);
    }
  });
  sleep_until_wall_ns(deadline);
  const TimeNs woke = wall_now_ns();
  interrupter.join();
  sigaction(SIGUSR1, &previous, nullptr);
  EXPECT_GE(woke, deadline);
}

}  // namespace
}  // namespace panoptes
