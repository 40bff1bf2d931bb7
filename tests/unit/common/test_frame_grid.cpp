// SPDX-License-Identifier: Apache-2.0
// The fixed-rate grid and its timecode (panoptes/frame_grid.h, docs/frames.md): the estimator's
// FrameClock and the client library's timecode share it.
#include <string>

#include <gtest/gtest.h>

#include "panoptes/frame_grid.h"

namespace panoptes {
namespace {

constexpr TimeNs kSecond = 1'000'000'000;

TEST(FrameGrid, InstantsAreWholeSecondsPlusFlooredPeriods) {
  const FrameGrid grid(120);
  EXPECT_EQ(grid.instant(0), 0);
  EXPECT_EQ(grid.instant(1), 8'333'333);
  EXPECT_EQ(grid.instant(2), 16'666'666);
  EXPECT_EQ(grid.instant(120), kSecond);
  EXPECT_EQ(grid.instant(-1), kSecond * -1 + 119 * kSecond / 120) << "before the epoch too";
  for (std::int64_t index :
       {std::int64_t{-241}, std::int64_t{0}, std::int64_t{7}, std::int64_t{204'000'000'007}}) {
    EXPECT_EQ(grid.index_at(grid.instant(index)), index);
    EXPECT_EQ(grid.index_at(grid.instant(index + 1) - 1), index) << "the last ns of its period";
  }
  EXPECT_THROW(FrameGrid(0), std::invalid_argument);
  EXPECT_THROW(FrameGrid(FrameGrid::kMaxRateHz + 1), std::invalid_argument);
}

TEST(FrameGrid, TimecodeOfTheDayAndItsText) {
  const FrameGrid grid(240);
  const TimeNs day = 86'400 * kSecond;
  const TimeNs at = 20'000 * day + (23 * 3600 + 59 * 60 + 59) * kSecond + grid.instant(239);
  const Timecode tc = grid.timecode(at);
  EXPECT_EQ(tc.hours, 23);
  EXPECT_EQ(tc.minutes, 59);
  EXPECT_EQ(tc.seconds, 59);
  EXPECT_EQ(tc.frames, 239);
  EXPECT_EQ(to_string(tc, 240), "23:59:59:239");
  const Timecode next = grid.timecode(at + 5'000'000);
  EXPECT_EQ(to_string(next, 240), "00:00:00:000") << "midnight: the next day begins";
  EXPECT_EQ(to_string(FrameGrid(25).timecode(day + 3 * kSecond + 40'000'000), 25), "00:00:03:01");
  EXPECT_EQ(to_string(FrameGrid(1000).timecode(999'000'000), 1000), "00:00:00:999");
}

}  // namespace
}  // namespace panoptes
