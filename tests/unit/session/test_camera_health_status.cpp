// SPDX-License-Identifier: Apache-2.0
// Camera health through the session (issue 34, item 4): the configured lost threshold, arrival
// times from admitted frames, refused frames, and what the status message and status line carry.
#include <string>

#include <gtest/gtest.h>

#include "panoptes/estimator_app/status.h"
#include "panoptes/session/estimator_session.h"

namespace panoptes::session {
namespace {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kWall = 1'700'000'000'000'000'000LL;

FeatureFrame frame_at(const std::string& camera, std::int64_t number, TimeNs stamp_ns) {
  FeatureFrame frame;
  frame.camera_id = camera;
  frame.frame = number;
  frame.stamp_ns = stamp_ns;
  frame.received_ns = stamp_ns + 2 * kMs;  // as the live node sets it
  return frame;
}

// Four cameras at 100 Hz for 1 s from kWall; c3 stops at 0.4 s.
EstimatorSession& feed(EstimatorSession& session) {
  for (int k = 0; k < 100; ++k) {
    for (const char* id : {"c0", "c1", "c2", "c3"}) {
      if (std::string(id) == "c3" && k > 40) continue;
      session.offer(frame_at(id, k, kWall + 10 * kMs * k), kWall + 10 * kMs * k, false);
    }
  }
  return session;
}

TEST(CameraHealthStatus, TheConfiguredThresholdDecidesWhenACameraIsLost) {
  EstimatorConfig config;
  config.node.camera_lost_after_s = 0.25;
  EstimatorSession session{config};
  feed(session);
  // c3's last frame arrived at kWall + 402 ms, the others' at kWall + 992 ms.
  EXPECT_EQ(session.cameras_lost(kWall + 652 * kMs), 0U);
  EXPECT_EQ(session.cameras_lost(kWall + 653 * kMs), 1U);
  const TimeNs now = kWall + 1100 * kMs;
  const auto usage = session.usage(now, now);
  EXPECT_EQ(usage.cameras_live, 3U);
  EXPECT_EQ(usage.cameras_lost, 1U);
  ASSERT_EQ(usage.cameras.size(), 4U);
  EXPECT_EQ(usage.cameras[3].camera_id, "c3");
  EXPECT_EQ(usage.cameras[3].state, estimator::CameraState::kLost);
  EXPECT_NEAR(usage.cameras[3].since_last_frame_s, 0.698, 1e-9);
  EXPECT_NEAR(usage.cameras[0].since_last_frame_s, 0.108, 1e-9);
  // Without a wall time (offline summaries) health is unknown.
  EXPECT_EQ(session.usage(now).cameras[3].state, estimator::CameraState::kUnknown);
}

TEST(CameraHealthStatus, TheMessageCarriesStateAgeRefusalsAndCounts) {
  EstimatorSession session{EstimatorConfig{}};
  feed(session);
  session.note_refused("c0", true);
  for (int i = 0; i < 9; ++i) session.note_refused("c0", false);
  const TimeNs now = kWall + 1600 * kMs;  // c3 1.198 s silent, the others 0.608 s: all lost at 0.5 s
  const auto message = estimator_app::to_status_message(session.usage(now, now));
  EXPECT_EQ(message.cameras_live(), 0U);
  EXPECT_EQ(message.cameras_lost(), 4U);
  ASSERT_EQ(message.cameras().size(), 4U);
  EXPECT_EQ(message.cameras()[0].state(), 1);  // lost
  EXPECT_EQ(message.cameras()[0].refused_frames(), 10U);
  EXPECT_EQ(message.cameras()[0].refused_writers(), 1U);
  EXPECT_NEAR(message.cameras()[3].since_last_frame_s(), 1.198, 1e-9);
  bool counted = false;
  for (const auto& counter : message.counters())
    counted |= counter.name() == "camera_id_claimed_by_second_writer" && counter.value() == 10;
  EXPECT_TRUE(counted);
}

TEST(CameraHealthStatus, TheLineShowsLostCamerasTheirSilenceAndUnobservedTracks) {
  estimator::EstimatorUsage usage;
  usage.cameras_live = 3;
  usage.cameras_lost = 1;
  usage.tracks_confirmed = 3;
  for (const char* id : {"c0", "c1", "c2", "c3"}) {
    estimator::CameraUsage c;
    c.camera_id = id;
    c.utilisation = 1.0;
    c.state = estimator::CameraState::kLive;
    c.since_last_frame_s = 0.01;
    usage.cameras.push_back(c);
  }
  usage.cameras[3].state = estimator::CameraState::kLost;
  usage.cameras[3].since_last_frame_s = 1.24;
  usage.cameras[0].refused_frames = 812;
  usage.cameras[0].refused_writers = 1;
  estimator_app::StatusLineExtras extras;
  extras.elapsed_ns = 12'400 * kMs;
  extras.time_sync_answered = 52;
  EXPECT_EQ(estimator_app::status_line(usage, extras),
            "t=12s cameras 3/4 live: c0 100% (2nd writer refused: 812 frames from 1) c1 100% c2 100% "
            "c3 lost 1.2 s | tracks 3+0 coasting | replays 0 (0/s) | cpu 0% | time sync answered 52");
  // Every camera lost: the tracks held are predictions, and the line says so.
  usage.cameras_live = 0;
  usage.cameras_lost = 4;
  usage.tracks_unobserved = 3;
  for (auto& c : usage.cameras) c.state = estimator::CameraState::kLost;
  const std::string blind = estimator_app::status_line(usage, extras);
  EXPECT_NE(blind.find("cameras 0/4 live: c0 lost 0.0 s"), std::string::npos) << blind;
  EXPECT_NE(blind.find("| tracks 3+0 coasting (no camera live: 3 predicted only) |"), std::string::npos)
      << blind;
}

}  // namespace
}  // namespace panoptes::session

namespace panoptes::session {
namespace {

// Continuous calibration (issue 36): a quarantined camera's health on the wire and in the line.
TEST(CameraHealthStatus, CalibrationHealthIsInTheMessageAndTheLine) {
  estimator::EstimatorUsage usage;
  usage.stamp_ns = kWall + 3000 * kMs;
  estimator::CameraCalibrationHealth ok;
  ok.camera_id = "c0";
  ok.state = estimator::CalibrationState::kOk;
  ok.whole.samples = 50;
  estimator::CameraCalibrationHealth bumped;
  bumped.camera_id = "c3";
  bumped.state = estimator::CalibrationState::kQuarantined;
  bumped.reason = "quarantined: whole image: bias (-8.33, +4.71) px = 9.57 px over 45 residuals";
  bumped.quarantined_since_ns = kWall + 1500 * kMs;
  bumped.whole.samples = 45;
  bumped.whole.bias = {-8.33, 4.71};
  bumped.regions[4].samples = 12;
  bumped.quarantines = 1;
  bumped.blobs_withheld = 900;
  usage.calibration = {ok, bumped};
  const msg::EstimatorStatus message = estimator_app::to_status_message(usage);
  ASSERT_EQ(message.calibration().size(), 2u);
  const auto& m = message.calibration()[1];
  EXPECT_EQ(m.camera_id(), "c3");
  EXPECT_EQ(m.state(), 3);
  EXPECT_EQ(m.reason(), bumped.reason);
  EXPECT_DOUBLE_EQ(m.whole().bias_px()[0], -8.33);
  ASSERT_EQ(m.regions().size(), 9u);
  EXPECT_EQ(m.regions()[4].samples(), 12u);
  EXPECT_NEAR(m.quarantined_for_s(), 1.5, 1e-9);
  EXPECT_EQ(m.blobs_withheld(), 900u);
  EXPECT_EQ(message.calibration()[0].quarantined_for_s(), 0.0);
  const std::string line = estimator_app::status_line(usage, {});
  EXPECT_NE(line.find("| c3 quarantined 1.5 s: whole image: bias (-8.33, +4.71) px"), std::string::npos)
      << line;
  EXPECT_EQ(line.find("c0 quarantined"), std::string::npos) << line;
}

}  // namespace
}  // namespace panoptes::session
