// SPDX-License-Identifier: Apache-2.0
// Offline replay ordering: by stamp with a deterministic tie-break, or by arrival through the
// latency window of the session's inbox.
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/session/offline_replay.h"

namespace panoptes::session {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;
constexpr TimeNs kMs = 1'000'000;

FeatureFrame frame(const std::string& camera, std::int64_t number, TimeNs stamp_ns, TimeNs received_ns = 0) {
  FeatureFrame f;
  f.camera_id = camera;
  f.frame = number;
  f.stamp_ns = stamp_ns;
  f.received_ns = received_ns;
  return f;
}

std::vector<std::pair<std::string, std::int64_t>> names(const std::vector<FeatureFrame>& frames) {
  std::vector<std::pair<std::string, std::int64_t>> out;
  out.reserve(frames.size());
  for (const auto& f : frames) out.emplace_back(f.camera_id, f.frame);
  return out;
}

using Names = std::vector<std::pair<std::string, std::int64_t>>;

TEST(OfflineReplayOrder, SortsByStampThenCameraThenFrame) {
  std::vector<FeatureFrame> frames = {frame("cam1", 5, kEpoch + 2 * kMs), frame("cam1", 2, kEpoch + kMs),
                                      frame("cam0", 9, kEpoch + kMs), frame("cam1", 1, kEpoch + kMs),
                                      frame("cam0", 1, kEpoch)};
  sort_by_stamp(frames);
  EXPECT_EQ(names(frames), (Names{{"cam0", 1}, {"cam0", 9}, {"cam1", 1}, {"cam1", 2}, {"cam1", 5}}));
}

TEST(OfflineReplayOrder, ByStampDeliversInPlace) {
  const std::vector<FeatureFrame> frames = {frame("a", 1, kEpoch, kEpoch + 9 * kMs),
                                            frame("b", 1, kEpoch + kMs)};
  EXPECT_EQ(delivery_order(frames, false), (std::vector<std::size_t>{0, 1}));
}

TEST(OfflineReplayOrder, ByArrivalIsStableAndUsesTheStampWithoutAnArrival) {
  const std::vector<FeatureFrame> frames = {
      frame("a", 1, kEpoch, kEpoch + 9 * kMs),        // arrives last
      frame("b", 1, kEpoch + kMs, kEpoch + 3 * kMs),  // ties with c: keeps stamp order
      frame("c", 1, kEpoch + 2 * kMs, kEpoch + 3 * kMs),
      frame("d", 1, kEpoch + 2 * kMs),  // no arrival: at its stamp
  };
  EXPECT_EQ(delivery_order(frames, true), (std::vector<std::size_t>{3, 1, 2, 0}));
}

Names replay(std::vector<FeatureFrame> frames, bool by_arrival, double latency_window_ms) {
  EstimatorConfig config;
  config.node.latency_window_ms = latency_window_ms;
  EstimatorSession session(config);
  sort_by_stamp(frames);
  Names delivered;
  replay_frames(session, frames, {by_arrival, false}, [&](const FeatureFrame& f, estimator::FrameOutcome) {
    delivered.emplace_back(f.camera_id, f.frame);
  });
  return delivered;
}

TEST(OfflineReplay, ArrivalOrderPassesThroughTheLatencyWindow) {
  // cam1's frame 1 (stamp 1 ms) arrives 6 ms late, after cam0's frames 2 and 3.
  const std::vector<FeatureFrame> frames = {
      frame("cam0", 1, kEpoch, kEpoch + kMs),
      frame("cam1", 1, kEpoch + kMs, kEpoch + 7 * kMs),
      frame("cam0", 2, kEpoch + 2 * kMs, kEpoch + 3 * kMs),
      frame("cam0", 3, kEpoch + 4 * kMs, kEpoch + 5 * kMs),
      frame("cam0", 4, kEpoch + 30 * kMs, kEpoch + 31 * kMs),
  };
  // A 10 ms window holds the early frames until the late one is in: stamp order.
  EXPECT_EQ(replay(frames, true, 10.0),
            (Names{{"cam0", 1}, {"cam1", 1}, {"cam0", 2}, {"cam0", 3}, {"cam0", 4}}));
  // Without a window every frame goes on arrival: the late frame comes after newer ones.
  EXPECT_EQ(replay(frames, true, 0.0),
            (Names{{"cam0", 1}, {"cam0", 2}, {"cam0", 3}, {"cam1", 1}, {"cam0", 4}}));
  // By stamp the arrival does not matter.
  EXPECT_EQ(replay(frames, false, 0.0),
            (Names{{"cam0", 1}, {"cam1", 1}, {"cam0", 2}, {"cam0", 3}, {"cam0", 4}}));
}

TEST(OfflineReplay, ScreenedOutFramesAreNotDelivered) {
  const std::vector<FeatureFrame> frames = {frame("cam0", 1, kEpoch), frame("", 2, kEpoch + kMs),
                                            frame("cam0", 3, kEpoch + 2 * kMs)};
  EXPECT_EQ(replay(frames, false, 20.0), (Names{{"cam0", 1}, {"cam0", 3}}));
}

}  // namespace
}  // namespace panoptes::session
