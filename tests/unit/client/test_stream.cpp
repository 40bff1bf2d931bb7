// SPDX-License-Identifier: Apache-2.0
// The client's Stream (common/client/src/stream.h) without a bus: the bounded queue dropping its
// oldest item and counting the drop, the wait with a timeout, callbacks beside the queue, callback
// exceptions counted, handles unique across streams, and close() waking a waiting thread.
#include "stream.h"

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace panoptes::client::detail {
namespace {

using namespace std::chrono_literals;

struct Errors {
  std::vector<std::string> seen;
  CallbackGroup group{[this](const std::string& what) { seen.push_back(what); }};
};

TEST(Stream, QueueKeepsTheNewestAndCountsTheDroppedOldest) {
  Errors errors;
  Stream<int> stream(errors.group, 3);
  for (int i = 1; i <= 5; ++i) EXPECT_TRUE(stream.push(i));
  EXPECT_EQ(stream.counts().pushed, 5U);
  EXPECT_EQ(stream.counts().dropped, 2U);
  for (int expected = 3; expected <= 5; ++expected) {
    const auto pulled = stream.wait(0ms);
    ASSERT_EQ(pulled.status, Status::kOk);
    EXPECT_EQ(*pulled.item, expected);
  }
  EXPECT_EQ(stream.wait(0ms).status, Status::kTimeout);
}

TEST(Stream, DropsCountOnlyOncePulledWhenAsked) {
  Errors errors;
  Stream<int> stream(errors.group, 2, Stream<int>::DropCounting::kOncePulled);
  for (int i = 0; i < 4; ++i) stream.push(i);
  EXPECT_EQ(stream.counts().dropped, 0U) << "nobody pulls: an overflow is no loss";
  EXPECT_EQ(*stream.wait(0ms).item, 2) << "the oldest still went";
  stream.push(10);  // the queue: 3, 10
  EXPECT_EQ(stream.counts().dropped, 0U);
  stream.push(11);  // 3 goes, unread
  EXPECT_EQ(stream.counts().dropped, 1U);
}

TEST(Stream, WaitTimesOutEmptyAndReturnsAnItemPushedMeanwhile) {
  Errors errors;
  Stream<std::string> stream(errors.group, 4);
  const auto start = std::chrono::steady_clock::now();
  const auto empty = stream.wait(50ms);
  EXPECT_EQ(empty.status, Status::kTimeout);
  EXPECT_FALSE(empty.item.has_value());
  EXPECT_GE(std::chrono::steady_clock::now() - start, 50ms);

  auto waiter = std::async(std::launch::async, [&] { return stream.wait(10s); });
  std::this_thread::sleep_for(20ms);
  stream.push("one");
  stream.notify();
  const auto pulled = waiter.get();
  ASSERT_EQ(pulled.status, Status::kOk);
  EXPECT_EQ(*pulled.item, "one");
}

TEST(Stream, CloseWakesWaitersAndRefusesLaterItems) {
  Errors errors;
  Stream<int> stream(errors.group, 4);
  stream.push(1);
  auto first = std::async(std::launch::async, [&] {
    stream.wait(10s);  // takes the queued item
    return stream.wait(10s);
  });
  auto second = std::async(std::launch::async, [&] {
    std::this_thread::sleep_for(10ms);
    return stream.wait(10s);
  });
  std::this_thread::sleep_for(50ms);
  const auto start = std::chrono::steady_clock::now();
  stream.close();
  EXPECT_EQ(first.get().status, Status::kClosed);
  EXPECT_EQ(second.get().status, Status::kClosed);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 5s) << "close() did not wake the waiters";
  EXPECT_FALSE(stream.push(2));
  EXPECT_EQ(stream.wait(0ms).status, Status::kClosed);
  EXPECT_EQ(stream.counts().pushed, 1U);
}

TEST(Stream, CallbacksReceiveWhatTheQueueDoesNotHold) {
  Errors errors;
  Stream<int, std::vector<int>> stream(errors.group, 8);
  std::vector<int> seen;
  const int handle = stream.add_callback([&](const std::vector<int>& batch) { seen = batch; });
  const std::vector<int> batch = {7, 8};
  for (const int item : batch) stream.push(item);
  stream.dispatch(batch);
  EXPECT_EQ(seen, batch);
  EXPECT_EQ(*stream.wait(0ms).item, 7) << "the queue is fed beside the callbacks";

  stream.remove_callback(handle);
  seen.clear();
  stream.dispatch({1});
  EXPECT_TRUE(seen.empty()) << "a removed callback ran";
}

TEST(Stream, CallbackExceptionsAreCountedAndTheOthersStillRun) {
  Errors errors;
  Stream<int> stream(errors.group, 2);
  int ran = 0;
  stream.add_callback([](const int&) { throw std::runtime_error("bad callback"); });
  stream.add_callback([](const int&) { throw 42; });
  stream.add_callback([&](const int& value) { ran += value; });
  stream.dispatch(5);
  EXPECT_EQ(ran, 5);
  ASSERT_EQ(errors.seen.size(), 2U);
  EXPECT_EQ(errors.seen[0], "bad callback");
  EXPECT_EQ(errors.seen[1], "an exception that is not a std::exception");
}

TEST(Stream, HandlesAreUniqueAcrossTheStreamsOfAGroup) {
  Errors errors;
  Stream<int> frames(errors.group, 2);
  Stream<std::string> strokes(errors.group, 2);
  const int a = frames.add_callback([](const int&) {});
  const int b = strokes.add_callback([](const std::string&) {});
  const int c = frames.add_callback([](const int&) {});
  EXPECT_NE(a, b);
  EXPECT_NE(b, c);
  EXPECT_NE(a, c);
  strokes.remove_callback(a);  // another stream's handle: nothing happens
  int ran = 0;
  frames.add_callback([&](const int&) { ++ran; });
  frames.dispatch(1);
  EXPECT_EQ(ran, 1);
}

TEST(Stream, ACallbackMayChangeTheCallbacksAndKnowsItIsDispatching) {
  Errors errors;
  Stream<int> stream(errors.group, 2);
  EXPECT_FALSE(errors.group.dispatching_on_this_thread());
  int handle = 0;
  int calls = 0;
  bool dispatching_inside = false;
  handle = stream.add_callback([&](const int&) {
    ++calls;
    dispatching_inside = errors.group.dispatching_on_this_thread();
    stream.remove_callback(handle);  // from its own call: must not deadlock
  });
  stream.dispatch(1);
  stream.dispatch(2);
  EXPECT_EQ(calls, 1);
  EXPECT_TRUE(dispatching_inside);
  EXPECT_FALSE(errors.group.dispatching_on_this_thread());
}

TEST(Stream, RemoveReturnsOnlyWhenTheCallbackCannotRun) {
  Errors errors;
  Stream<int> stream(errors.group, 2);
  std::atomic<bool> inside{false};
  std::atomic<bool> finished{false};
  const int handle = stream.add_callback([&](const int&) {
    inside = true;
    std::this_thread::sleep_for(100ms);
    finished = true;
  });
  std::thread listener([&] { stream.dispatch(1); });
  while (!inside) std::this_thread::yield();
  stream.remove_callback(handle);
  EXPECT_TRUE(finished) << "remove_callback returned while its callback ran";
  listener.join();
}

}  // namespace
}  // namespace panoptes::client::detail
