// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/node_log.h"
#include "panoptes/camera/sync_hold.h"
#include "panoptes/records.h"

namespace panoptes::camera {
namespace {

// A time service whose estimate is a constant offset (local − server) once synchronised.
class FakeSync final : public ClockSyncView {
 public:
  bool synced = false;
  double offset_ns = 0;
  bool synchronised() const override { return synced; }
  ClockEstimate estimate() const override {
    ClockEstimate estimate;
    estimate.synchronised = synced;
    estimate.offset_ns = offset_ns;
    estimate.samples = 10;
    return estimate;
  }
  std::optional<TimeNs> to_server(TimeNs local_ns) const override {
    if (!synced) return std::nullopt;
    return estimate().to_server(local_ns);
  }
};

struct Emitted {
  std::int64_t frame = 0;
  TimeNs stamp_ns = 0;
  TimeNs arrival_ns = 0;
  bool synchronised = false;
};

class SyncHoldTest : public ::testing::Test {
 protected:
  FeatureFrame frame(std::int64_t number) {
    FeatureFrame frame;
    frame.frame = number;
    frame.stamp_ns = 1'000'000 + number;
    frame.arrival_ns = 2'000'000 + number;
    return frame;
  }
  auto collector() {
    return [this](const FeatureFrame& frame, const ClockEstimate* estimate) {
      emitted.push_back({frame.frame, frame.stamp_ns, frame.arrival_ns, estimate != nullptr});
    };
  }

  NodeLog log{"test_sync_hold"};
  FakeSync sync;
  std::vector<Emitted> emitted;
};

TEST_F(SyncHoldTest, WithoutClockSyncFramesPassAsRead) {
  SyncHold hold(nullptr, log);
  hold.set_deadline(1'000);
  hold.add(frame(1), 0, collector());
  ASSERT_EQ(emitted.size(), 1u);
  EXPECT_EQ(emitted[0].stamp_ns, 1'000'001);
  EXPECT_FALSE(emitted[0].synchronised);
  EXPECT_EQ(hold.held_total(), 0u);
  EXPECT_EQ(hold.unsynchronised(), 0u);  // not synchronising is not "unsynchronised"
}

TEST_F(SyncHoldTest, HoldsUntilSynchronisedThenReleasesInOrderWithCommonStamps) {
  SyncHold hold(&sync, log);
  hold.set_deadline(1'000);
  hold.add(frame(1), 10, collector());
  hold.add(frame(2), 20, collector());
  hold.release(false, 30, collector());
  EXPECT_TRUE(emitted.empty());
  EXPECT_EQ(hold.held_total(), 2u);
  sync.synced = true;
  sync.offset_ns = 500;
  hold.release(false, 40, collector());
  ASSERT_EQ(emitted.size(), 2u);
  EXPECT_EQ(emitted[0].frame, 1);
  EXPECT_EQ(emitted[1].frame, 2);
  EXPECT_EQ(emitted[0].stamp_ns, 1'000'001 - 500);
  EXPECT_EQ(emitted[0].arrival_ns, 2'000'001 - 500);
  EXPECT_TRUE(emitted[1].synchronised);
  EXPECT_EQ(hold.unsynchronised(), 0u);
  EXPECT_FALSE(hold.warned());
  // Once synchronised a frame goes straight through.
  hold.add(frame(3), 50, collector());
  EXPECT_EQ(emitted.size(), 3u);
  EXPECT_EQ(hold.held_total(), 2u);
}

TEST_F(SyncHoldTest, AfterTheDeadlineFramesGoOutUnsynchronisedAndCounted) {
  SyncHold hold(&sync, log);
  hold.set_deadline(1'000);
  hold.add(frame(1), 999, collector());
  EXPECT_TRUE(emitted.empty());
  hold.add(frame(2), 1'000, collector());  // the deadline has come: both go out as read
  ASSERT_EQ(emitted.size(), 2u);
  EXPECT_EQ(emitted[0].stamp_ns, 1'000'001);
  EXPECT_FALSE(emitted[0].synchronised);
  EXPECT_EQ(hold.unsynchronised(), 2u);
  EXPECT_TRUE(hold.warned());
  sync.synced = true;
  sync.offset_ns = -7;
  hold.add(frame(3), 2'000, collector());
  ASSERT_EQ(emitted.size(), 3u);
  EXPECT_EQ(emitted[2].stamp_ns, 1'000'003 + 7);
  EXPECT_EQ(hold.unsynchronised(), 2u);
}

TEST_F(SyncHoldTest, ForcedReleaseEmptiesTheHold) {
  SyncHold hold(&sync, log);
  hold.set_deadline(1'000);
  hold.add(frame(1), 0, collector());
  hold.release(true, 0, collector());
  ASSERT_EQ(emitted.size(), 1u);
  EXPECT_EQ(hold.held_now(), 0u);
  EXPECT_EQ(hold.unsynchronised(), 1u);
}

TEST_F(SyncHoldTest, AFullHoldDropsTheOldestAndCountsIt) {
  SyncHold hold(&sync, log);
  hold.set_deadline(1'000);
  const auto total = static_cast<std::int64_t>(SyncHold::kHoldCapacity) + 5;
  for (std::int64_t n = 0; n < total; ++n) hold.add(frame(n), 0, collector());
  EXPECT_EQ(hold.held_now(), SyncHold::kHoldCapacity);
  EXPECT_EQ(hold.hold_overflow(), 5u);
  EXPECT_EQ(hold.held_total(), static_cast<std::uint64_t>(total));
  sync.synced = true;
  hold.release(false, 0, collector());
  ASSERT_EQ(emitted.size(), SyncHold::kHoldCapacity);
  EXPECT_EQ(emitted.front().frame, 5);  // the five oldest were dropped
  EXPECT_EQ(emitted.back().frame, total - 1);
}

}  // namespace
}  // namespace panoptes::camera
