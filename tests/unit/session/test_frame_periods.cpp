// SPDX-License-Identifier: Apache-2.0
// FramePeriods: where each camera's next frame is expected (live predictions).
#include <gtest/gtest.h>

#include "panoptes/estimator_app/frame_periods.h"

namespace panoptes::estimator_app {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;
constexpr TimeNs kPeriod = 10'000'000;  // 100 Hz

TEST(FramePeriods, UnknownUntilASecondFrameThenFollowsThePeriodPerCamera) {
  FramePeriods periods;
  EXPECT_EQ(periods.next_stamp("cam0", kEpoch), kEpoch) << "no period yet: no prediction";
  EXPECT_EQ(periods.next_stamp("cam0", kEpoch + kPeriod), kEpoch + 2 * kPeriod);
  EXPECT_EQ(periods.next_stamp("cam1", kEpoch + 5), kEpoch + 5) << "each camera has its own period";
  // A changed gap moves the estimate by a tenth of the difference (smoothing).
  EXPECT_EQ(periods.next_stamp("cam0", kEpoch + 3 * kPeriod), kEpoch + 3 * kPeriod + kPeriod + kPeriod / 10);
}

TEST(FramePeriods, IgnoresGapsOfASecondOrMoreAndBackwardStamps) {
  FramePeriods periods;
  periods.next_stamp("cam0", kEpoch);
  EXPECT_EQ(periods.next_stamp("cam0", kEpoch + 2 * kNsPerSecond), kEpoch + 2 * kNsPerSecond);
  EXPECT_EQ(periods.next_stamp("cam0", kEpoch + 2 * kNsPerSecond - kPeriod),
            kEpoch + 2 * kNsPerSecond - kPeriod);
}

}  // namespace
}  // namespace panoptes::estimator_app
