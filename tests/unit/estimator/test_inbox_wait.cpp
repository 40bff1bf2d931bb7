// SPDX-License-Identifier: Apache-2.0
// FrameInbox::wait: the live estimator loop sleeps in it and must wake when a frame arrives or
// falls due, not only when the maximum wait has passed; has_due lets a waiting frame go before
// the less urgent output of earlier ones (issue 7, end-to-end latency).
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "panoptes/estimator/inbox.h"

namespace panoptes::estimator {
namespace {

using Clock = std::chrono::steady_clock;

FeatureFrame frame_at(TimeNs stamp_ns) {
  FeatureFrame frame;
  frame.camera_id = "cam0";
  frame.stamp_ns = stamp_ns;
  return frame;
}

TEST(FrameInboxWait, WakesWhenAFrameIsPushed) {
  FrameInbox inbox(16, 0);
  std::thread pusher([&inbox] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    inbox.push(frame_at(1000));
  });
  const auto begin = Clock::now();
  inbox.wait(0, std::chrono::seconds(20));
  const auto waited = Clock::now() - begin;
  pusher.join();
  EXPECT_LT(waited, std::chrono::seconds(10));  // woken by the push, not by the 20 s limit
  EXPECT_EQ(inbox.pop_due(1000).size(), 1u);
}

TEST(FrameInboxWait, ReturnsAtOnceWhenTheOldestFrameIsDue) {
  FrameInbox inbox(16, 5'000'000);
  inbox.push(frame_at(1'000'000'000));
  const auto begin = Clock::now();
  inbox.wait(1'006'000'000, std::chrono::seconds(20));  // due since 1.005 s
  EXPECT_LT(Clock::now() - begin, std::chrono::seconds(10));
}

TEST(FrameInboxWait, WaitsUntilTheOldestFrameFallsDue) {
  FrameInbox inbox(16, 5'000'000);
  inbox.push(frame_at(1'000'000'000));
  const auto begin = Clock::now();
  inbox.wait(1'000'000'000, std::chrono::seconds(20));  // due in 5 ms
  const auto waited = Clock::now() - begin;
  EXPECT_GE(waited, std::chrono::milliseconds(4));
  EXPECT_LT(waited, std::chrono::seconds(10));
}

TEST(FrameInboxHasDue, TellsWhetherPopDueWouldReturnAFrame) {
  FrameInbox inbox(16, 5'000'000);
  EXPECT_FALSE(inbox.has_due(2'000'000'000));  // empty
  inbox.push(frame_at(1'000'000'000));
  EXPECT_FALSE(inbox.has_due(1'004'000'000));  // within the window
  EXPECT_TRUE(inbox.has_due(1'005'000'000));
  EXPECT_EQ(inbox.pop_due(1'005'000'000).size(), 1u);
  EXPECT_FALSE(inbox.has_due(1'005'000'000));  // taken
}

}  // namespace
}  // namespace panoptes::estimator
