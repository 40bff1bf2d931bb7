// SPDX-License-Identifier: Apache-2.0
// Intake screening and usage, and the status message assembled from the usage.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/estimator_app/status.h"
#include "panoptes/session/estimator_session.h"

namespace panoptes::session {
namespace {

constexpr TimeNs kNow = 1'700'000'000'000'000'000LL;

FeatureFrame frame_at(const std::string& camera, std::int64_t number, TimeNs stamp_ns, int blobs = 2) {
  FeatureFrame frame;
  frame.camera_id = camera;
  frame.frame = number;
  frame.stamp_ns = stamp_ns;
  for (int i = 0; i < blobs; ++i) {
    Blob blob;
    blob.x = 100 + 10 * i;
    blob.y = 200;
    blob.area = 9;
    blob.sum = 900;
    blob.peak = 200;
    frame.blobs.push_back(blob);
  }
  return frame;
}

TEST(Intake, AdmitsGoodFramesAndCountsRejectedOnesByReason) {
  EstimatorSession session{EstimatorConfig{}};
  FeatureFrame good = frame_at("cam0", 1, kNow);
  EXPECT_TRUE(session.admit(good, kNow, false));
  FeatureFrame zero_stamp = frame_at("cam0", 2, 0);
  EXPECT_FALSE(session.admit(zero_stamp, kNow, false));
  FeatureFrame far = frame_at("cam1", 3, kNow + 20 * kNsPerSecond);
  EXPECT_FALSE(session.admit(far, kNow, false));
  FeatureFrame future = frame_at("cam1", 4, kNow + kNsPerSecond);  // 1 s ahead of the wall clock
  EXPECT_FALSE(session.admit(future, kNow, true));
  EXPECT_TRUE(session.admit(future, kNow, false)) << "offline, 1 s is within the stamp skew";

  const auto usage = session.usage(kNow);
  EXPECT_EQ(usage.counters.at("non_positive_stamp"), 1u);
  EXPECT_EQ(usage.counters.at("stamp_out_of_range"), 1u);
  EXPECT_EQ(usage.counters.at("stamp_in_future"), 1u);
  EXPECT_EQ(usage.counters.count("inbox_overflow"), 0u);
  ASSERT_EQ(usage.cameras.size(), 2u);
  EXPECT_EQ(usage.cameras[0].camera_id, "cam0");
  EXPECT_EQ(usage.cameras[0].frames, 2u);
  EXPECT_EQ(usage.cameras[0].dropped, 1u);
  EXPECT_EQ(usage.cameras[1].frames, 3u);
  EXPECT_EQ(usage.cameras[1].dropped, 2u);
}

TEST(Intake, ScreenSettingsComeFromTheConfiguration) {
  EstimatorConfig config;
  config.screen.max_blobs = 3;
  EstimatorSession session(config);
  FeatureFrame small = frame_at("cam0", 1, kNow, 3);
  FeatureFrame large = frame_at("cam0", 2, kNow, 4);
  EXPECT_TRUE(session.admit(small, kNow, false));
  EXPECT_FALSE(session.admit(large, kNow, false));
  EXPECT_EQ(session.usage(kNow).counters.at("too_many_blobs"), 1u);
}

TEST(Intake, InboxOverflowIsCountedInTheUsage) {
  EstimatorConfig config;
  config.node.inbox_capacity = 2;
  EstimatorSession session(config);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(session.offer(frame_at("cam0", i, kNow + i), kNow, false));
  EXPECT_EQ(session.inbox().size(), 2u);
  EXPECT_EQ(session.usage(kNow).counters.at("inbox_overflow"), 3u);
}

TEST(Intake, UncalibratedCameraFramesAreCountedNotTracked) {
  EstimatorSession session{EstimatorConfig{}};
  const FeatureFrame frame = frame_at("cam7", 1, kNow);
  EXPECT_EQ(session.process(frame), estimator::FrameOutcome::kUnknownCamera);
  EXPECT_EQ(session.tracker().stats().frames_unknown_camera, 1u);
}

TEST(StatusAssembly, CarriesEveryUsageValueIntoTheMessage) {
  estimator::EstimatorUsage usage;
  usage.stamp_ns = kNow;
  usage.tracks_tentative = 2;
  usage.tracks_confirmed = 5;
  usage.tracks_coasting = 1;
  usage.frames = 1000;
  usage.replays = 7;
  usage.replayed_frames = 19;
  usage.replays_per_s = 3.5;
  usage.replayed_frames_per_s = 9.5;
  usage.cpu_percent = 42.5;
  usage.update_p50_ms = 0.25;
  usage.update_p99_ms = 1.5;
  usage.latency_window_ms = 20;
  estimator::CameraUsage camera;
  camera.camera_id = "cam3";
  camera.frames = 500;
  camera.used = 490;
  camera.late = 4;
  camera.dropped = 10;
  camera.too_late = 6;
  camera.blobs = 4000;
  camera.associated = 3900;
  camera.utilisation = 0.98;
  camera.latency_p50_ms = 2.5;
  camera.latency_p99_ms = 6.0;
  camera.last_stamp_ns = kNow - 5;
  usage.cameras.push_back(camera);
  usage.counters["inbox_overflow"] = 3;
  usage.counters["non_finite_blob"] = 9;

  const auto message = estimator_app::to_status_message(usage);
  EXPECT_EQ(message.stamp_ns(), kNow);
  EXPECT_EQ(message.tracks_tentative(), 2u);
  EXPECT_EQ(message.tracks_confirmed(), 5u);
  EXPECT_EQ(message.tracks_coasting(), 1u);
  EXPECT_EQ(message.frames(), 1000u);
  EXPECT_EQ(message.replays(), 7u);
  EXPECT_EQ(message.replayed_frames(), 19u);
  EXPECT_DOUBLE_EQ(message.replays_per_s(), 3.5);
  EXPECT_DOUBLE_EQ(message.replayed_frames_per_s(), 9.5);
  EXPECT_DOUBLE_EQ(message.cpu_percent(), 42.5);
  EXPECT_DOUBLE_EQ(message.update_p50_ms(), 0.25);
  EXPECT_DOUBLE_EQ(message.update_p99_ms(), 1.5);
  EXPECT_DOUBLE_EQ(message.latency_window_ms(), 20);
  ASSERT_EQ(message.cameras().size(), 1u);
  const auto& m = message.cameras()[0];
  EXPECT_EQ(m.camera_id(), "cam3");
  EXPECT_EQ(m.frames(), 500u);
  EXPECT_EQ(m.used(), 490u);
  EXPECT_EQ(m.late(), 4u);
  EXPECT_EQ(m.dropped(), 10u);
  EXPECT_EQ(m.too_late(), 6u);
  EXPECT_EQ(m.blobs(), 4000u);
  EXPECT_EQ(m.blobs_associated(), 3900u);
  EXPECT_DOUBLE_EQ(m.utilisation(), 0.98);
  EXPECT_DOUBLE_EQ(m.latency_p50_ms(), 2.5);
  EXPECT_DOUBLE_EQ(m.latency_p99_ms(), 6.0);
  EXPECT_EQ(m.last_stamp_ns(), kNow - 5);
  ASSERT_EQ(message.counters().size(), 2u);
  EXPECT_EQ(message.counters()[0].name(), "inbox_overflow");
  EXPECT_EQ(message.counters()[0].value(), 3u);
  EXPECT_EQ(message.counters()[1].name(), "non_finite_blob");
  EXPECT_EQ(message.counters()[1].value(), 9u);
}

TEST(StatusAssembly, SessionUsageReachesTheMessage) {
  EstimatorSession session{EstimatorConfig{}};
  FeatureFrame bad = frame_at("cam0", 1, -5);
  EXPECT_FALSE(session.admit(bad, kNow, false));
  const auto message = estimator_app::to_status_message(session.usage(kNow));
  EXPECT_EQ(message.stamp_ns(), kNow);
  EXPECT_DOUBLE_EQ(message.latency_window_ms(), 0.0);  // the default: no frame waits
  ASSERT_EQ(message.cameras().size(), 1u);
  EXPECT_EQ(message.cameras()[0].dropped(), 1u);
  bool found = false;
  for (const auto& counter : message.counters()) {
    if (counter.name() == "non_positive_stamp") {
      EXPECT_EQ(counter.value(), 1u);
      found = true;
    }
  }
  EXPECT_TRUE(found) << "the screen's reason reaches the status counters";
}

}  // namespace
}  // namespace panoptes::session
