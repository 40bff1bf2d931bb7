// SPDX-License-Identifier: Apache-2.0
// FrameClock (docs/frames.md): the grid of instants, frame numbers + 1 per period, skips counted
// and never sent late, the timecode; and fixed-rate frames over a real run of the clients scene:
// every body in every frame, predictions at the instant equal the tracker's, and accuracy against
// the simulator's truth side by side with the per-camera frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/jsonl.h"
#include "panoptes/session/estimator_config.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/frame_clock.h"
#include "panoptes/session/frame_output.h"
#include "panoptes/session/offline_replay.h"
#include "panoptes/simulator.h"
#include "scene_frames.h"

namespace panoptes::session {
namespace {

constexpr TimeNs kSecond = 1'000'000'000;

TEST(FrameClock, RefusesRatesOutOfRangeNamingThem) {
  EXPECT_THROW(FrameClock(0), std::invalid_argument);
  EXPECT_THROW(FrameClock(FrameClock::kMaxRateHz + 1), std::invalid_argument);
  try {
    FrameClock clock(-3);
    FAIL();
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("-3 Hz"), std::string::npos) << error.what();
  }
}

TEST(FrameClock, GridIsAlignedToWholeSecondsAndEveryTimeMapsToItsPeriod) {
  for (const int rate : {60, 120, 240, 7}) {
    const FrameClock clock(rate);
    const TimeNs base = 1'764'000'000 * kSecond;  // an absolute capture-clock second
    const std::int64_t first = clock.index_at(base);
    EXPECT_EQ(clock.instant(first), base) << rate;
    EXPECT_EQ(clock.instant(first + rate), base + kSecond) << rate;
    const std::int64_t span = 2LL * rate;
    for (std::int64_t k = first - span; k < first + span; ++k) {
      const TimeNs a = clock.instant(k), b = clock.instant(k + 1);
      // Periods are the nominal one rounded down or up: exactly one period apart at the ns.
      EXPECT_LE(std::abs(static_cast<double>(b - a) - clock.period_ns()), 1.0) << rate << " " << k;
      EXPECT_EQ(clock.index_at(a), k);
      EXPECT_EQ(clock.index_at(b - 1), k);
    }
  }
}

TEST(FrameClock, OfflinePublishesEveryPeriodWithFrameNumbersPlusOne) {
  FrameClock clock(240);
  const TimeNs start = 5 * kSecond + 123'456;
  std::vector<FrameTick> ticks;
  // A replay clock that jumps irregularly (camera frames 0.03 .. 23 ms apart).
  for (TimeNs now = start; now < start + kSecond;
       now += (now % 7 == 0 ? 23'000'000 : 30'000 + now % 3'000'000))
    while (const auto tick = clock.next_due(now)) ticks.push_back(*tick);
  ASSERT_GT(ticks.size(), 230u);
  for (std::size_t i = 1; i < ticks.size(); ++i) {
    EXPECT_EQ(ticks[i].frame_number, ticks[i - 1].frame_number + 1);
    const TimeNs interval = ticks[i].instant_ns - ticks[i - 1].instant_ns;
    EXPECT_TRUE(interval == 4'166'666 || interval == 4'166'667) << interval;
  }
  EXPECT_EQ(ticks.front().frame_number, 1u);
  EXPECT_EQ(clock.skipped(), 0u);
}

TEST(FrameClock, LiveSkipsPeriodsWhenBehindAndNeverBursts) {
  FrameClock clock(100);  // 10 ms
  const TimeNs start = 7 * kSecond;
  auto tick = clock.latest_due(start + 2'000'000);
  ASSERT_TRUE(tick);
  EXPECT_EQ(tick->frame_number, 1u);
  EXPECT_EQ(tick->instant_ns, start);
  EXPECT_FALSE(clock.latest_due(start + 9'999'999)) << "one frame per period";
  EXPECT_EQ(clock.next_instant(), start + 10'000'000);
  tick = clock.latest_due(start + 10'000'000);
  ASSERT_TRUE(tick);
  EXPECT_EQ(tick->frame_number, 2u);
  // The estimator was busy for 35 ms: periods 3, 4 and 5 pass; only the newest (5) is published.
  tick = clock.latest_due(start + 45'000'000);
  ASSERT_TRUE(tick);
  EXPECT_EQ(tick->frame_number, 5u);
  EXPECT_EQ(tick->instant_ns, start + 40'000'000);
  EXPECT_EQ(clock.skipped(), 2u);
  EXPECT_FALSE(clock.latest_due(start + 45'000'001));
  EXPECT_EQ(clock.published(), 3u);
}

TEST(FrameClock, IdlePeriodsAreNeitherPublishedNorSkippedAndFrameNumbersStayOnTheGrid) {
  FrameClock clock(100);  // 10 ms
  const TimeNs start = 3 * kSecond;
  clock.idle_until(start + 50'000'000);
  EXPECT_EQ(clock.idle(), 0u) << "nothing to be idle about before the first frame";
  ASSERT_TRUE(clock.latest_due(start));
  // Every camera silent for 1 s: 100 instants go by unpublished, and none counts as skipped.
  for (TimeNs t = start + 5'000'000; t <= start + kSecond; t += 5'000'000) clock.idle_until(t);
  EXPECT_EQ(clock.idle(), 100u);
  EXPECT_FALSE(clock.latest_due(start + kSecond + 1)) << "the instant at 1 s went by idle";
  const auto tick = clock.latest_due(start + kSecond + 10'000'000);
  ASSERT_TRUE(tick);
  EXPECT_EQ(tick->frame_number, 102u) << "frame numbers count grid periods, idle ones included";
  EXPECT_EQ(clock.skipped(), 0u);
  EXPECT_EQ(clock.published(), 2u);
}

// The timecode's maths is the grid's (panoptes/frame_grid.h, tests/unit/common/test_frame_grid.cpp).
TEST(FrameClock, TimecodeIsTheGrids) {
  const FrameClock clock(120);
  const TimeNs instant =
      TimeNs{20'000} * 86'400 * kSecond + (13 * 3600 + 7 * 60 + 42) * kSecond + clock.instant(119);
  EXPECT_EQ(to_string(clock.timecode(instant), 120), "13:07:42:119");
  EXPECT_EQ(to_string(clock.timecode(instant + 10'000'000), 120), "13:07:43:000") << "next second";
}

TEST(FrameClock, TheDefaultIsFixedRateLiveAndPerCameraRecordsOffline) {
  NodeSettings node;
  EXPECT_EQ(node.frames, "auto");
  EXPECT_TRUE(node.fixed_rate_live());
  EXPECT_FALSE(node.fixed_rate_offline());
  node.frames = "per-camera";
  EXPECT_FALSE(node.fixed_rate_live());
  EXPECT_FALSE(node.fixed_rate_offline());
  node.frames = "fixed";
  EXPECT_TRUE(node.fixed_rate_live());
  EXPECT_TRUE(node.fixed_rate_offline());
  EXPECT_EQ(check_frames_mode("auto"), "");
  EXPECT_NE(check_frames_mode("sometimes").find("must be auto, per-camera or fixed"), std::string::npos);
}

TEST(FixedRateStats, SummarisesDataAgeAndPublishDelay) {
  FixedRateStats stats;
  for (int i = 1; i <= 100; ++i) stats.add(TimeNs{i} * 10'000, i == 100 ? 900'000 : 40'000);
  stats.add(2'000'000);   // offline: no publish delay
  stats.add(-1, 40'000);  // live, after the cameras stopped: no data age
  const std::string line = stats.summary();
  EXPECT_EQ(stats.frames, 102u);
  EXPECT_NE(
      line.find("fixed-rate: 102 frames; instant - newest stamp: mean 0.520 ms, p99 1.000 ms, max 2.000 ms"),
      std::string::npos)
      << line;
  EXPECT_NE(line.find("publish - instant: mean 0.049 ms, p99 0.040 ms, max 0.900 ms"), std::string::npos)
      << line;
}

using testing::simulate;

struct ErrorSum {
  double sum_sq = 0;
  std::size_t n = 0;
  void add(const PoseRecord& pose, const std::vector<BodyTruth>& truth) {
    for (const auto& body : truth) {
      if (body.name != pose.body) continue;
      sum_sq += (pose.p - body.T_world_body.t).squaredNorm();
      ++n;
    }
  }
  double rmse_mm() const { return n == 0 ? 0.0 : 1e3 * std::sqrt(sum_sq / static_cast<double>(n)); }
};

TEST(FixedRateFrames, EveryBodyInEveryFrameAtTheTrackersPredictionAndAccurate) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/clients.yaml");
  const std::vector<FeatureFrame> frames = simulate(scene, 4.0);
  EstimatorConfig config;
  EstimatorSession session(config);
  session.tracker().set_calibration(scene.calibration());
  session.tracker().set_bodies(scene.body_definitions());
  const std::size_t body_count = scene.body_definitions().size();
  ASSERT_GE(body_count, 2u);

  FrameClock clock(120);
  const FrameOutputBuilder builder;
  ErrorSum per_camera, fixed;
  std::uint64_t previous_number = 0, fixed_frames = 0;
  for (const FeatureFrame& frame : frames) {
    const bool warm = frame.stamp_ns > kSecond;
    while (session.tracker().last_stamp_ns() != 0) {
      const auto tick = clock.next_due(frame.stamp_ns - 1);
      if (!tick) break;
      const auto tracks = session.tracker().tracks_at(tick->instant_ns);
      const auto poses = session.poses_at(tick->instant_ns);
      const FrameOutput out =
          builder.build_at(session.tracker(), tick->frame_number, tick->instant_ns, {}, poses, tracks);
      ASSERT_EQ(out.frame_number, previous_number + 1);
      previous_number = out.frame_number;
      ASSERT_EQ(out.bodies.size(), body_count) << "every body in every frame";
      ASSERT_EQ(out.markers.size(), tracks.size());
      for (std::size_t i = 0; i < tracks.size(); ++i) {
        EXPECT_EQ(out.markers[i].track.stamp_ns, tick->instant_ns);
        EXPECT_EQ(out.markers[i].track.p, tracks[i].p) << "the tracker's prediction at the instant";
      }
      for (const auto& pose : poses) EXPECT_EQ(pose.stamp_ns, tick->instant_ns);
      if (!warm) continue;
      ++fixed_frames;
      const auto truth = scene.bodies_at(tick->instant_ns);
      for (const auto& body : out.bodies)
        if (body.tracking_valid) fixed.add(body.pose, truth);
    }
    if (session.process(frame) != estimator::FrameOutcome::kProcessed || !warm) continue;
    const auto truth = scene.bodies_at(frame.stamp_ns);
    for (const auto& pose : session.current_poses()) per_camera.add(pose, truth);
  }
  std::printf(
      "body position RMSE over 3 s: per-camera %.3f mm (%zu poses), fixed 120 Hz %.3f mm (%zu poses)\n",
      per_camera.rmse_mm(), per_camera.n, fixed.rmse_mm(), fixed.n);
  EXPECT_NEAR(static_cast<double>(fixed_frames), 3.0 * 120, 2.0);
  EXPECT_GT(fixed.n, static_cast<std::size_t>(0.95 * 3 * 120 * static_cast<double>(body_count)));
  EXPECT_LT(fixed.rmse_mm(), 2.0 * per_camera.rmse_mm() + 0.2) << "prediction over < one camera gap";
}

TEST(FixedRateFrames, OfflineRunWritesOneRecordSetPerInstantOnTheGrid) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/clients.yaml");
  EstimatorConfig config;
  config.node.frames = "fixed";
  config.node.frame_rate_hz = 240;
  EstimatorSession session(config);
  session.tracker().set_calibration(scene.calibration());
  session.tracker().set_bodies(scene.body_definitions());
  FeatureFiles input;
  input.frames = simulate(scene, 2.0);
  const std::string poses_path = ::testing::TempDir() + "fixed_rate_poses.jsonl";
  const std::string tracks_path = ::testing::TempDir() + "fixed_rate_tracks.jsonl";
  OfflineReplayOptions options;
  options.show_progress = false;
  ASSERT_EQ(run_offline(session, std::move(input), options, tracks_path, poses_path), 0);

  std::map<TimeNs, int> bodies_at;
  for (const auto& pose : read_poses(poses_path)) ++bodies_at[pose.stamp_ns];
  std::map<TimeNs, int> tracks_at;
  for (const auto& track : read_tracks(tracks_path)) ++tracks_at[track.stamp_ns];
  ASSERT_GT(bodies_at.size(), 450u) << "about 2 s at 240 Hz";
  const FrameClock clock(240);
  TimeNs previous = 0;
  for (const auto& [stamp, count] : bodies_at) {
    EXPECT_EQ(clock.instant(clock.index_at(stamp)), stamp) << "on the grid";
    if (previous != 0) {
      EXPECT_LE(std::abs(static_cast<double>(stamp - previous) - clock.period_ns()), 1.0);
    }
    previous = stamp;
    if (stamp > kSecond / 2) {
      EXPECT_EQ(count, 2) << "both bodies at every instant once identified";
    }
  }
  ASSERT_GE(tracks_at.size(), bodies_at.size());
  for (const auto& entry : tracks_at) EXPECT_EQ(clock.instant(clock.index_at(entry.first)), entry.first);
}

}  // namespace
}  // namespace panoptes::session
