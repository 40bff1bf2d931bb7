// SPDX-License-Identifier: Apache-2.0
// Honest camera health (issue 34, item 4): a camera whose frames stop is lost once the lost
// threshold has passed in wall time, the tracks held while every camera is lost are reported as
// unobserved, and a second writer claiming a camera id is refused while the owner keeps sending.
#include <gtest/gtest.h>

#include <string>

#include "panoptes/estimator/camera_ownership.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/estimator/usage.h"
#include "panoptes/simulator.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kWall = 1'800'000'000'000'000'000;  // a wall time, unrelated to the stamps

const CameraUsage& camera(const EstimatorUsage& usage, const std::string& id) {
  for (const auto& c : usage.cameras)
    if (c.camera_id == id) return c;
  throw std::runtime_error("no camera " + id + " in the usage");
}

TEST(CameraHealth, ACameraIsLostOnceItsLastFrameIsOlderThanTheThreshold) {
  const Tracker tracker;
  UsageMonitor monitor;
  monitor.set_lost_after(500 * kMs);
  for (int k = 0; k <= 100; ++k) {  // 100 Hz for 1 s; c3 stops after 0.5 s
    monitor.note_received("c0", 2.0, kWall + 10 * kMs * k);
    if (k <= 50) monitor.note_received("c3", 2.0, kWall + 10 * kMs * k);
  }
  // 0.99 s after c3's last frame (at kWall + 0.5 s): c3 lost, c0 live (its last frame 0.49 s ago).
  const TimeNs now = kWall + 1490 * kMs;
  const auto usage = monitor.summarize(tracker, now, 0, {}, now);
  EXPECT_EQ(camera(usage, "c0").state, CameraState::kLive);
  EXPECT_NEAR(camera(usage, "c0").since_last_frame_s, 0.49, 1e-9);
  EXPECT_EQ(camera(usage, "c3").state, CameraState::kLost);
  EXPECT_NEAR(camera(usage, "c3").since_last_frame_s, 0.99, 1e-9);
  EXPECT_EQ(usage.cameras_live, 1U);
  EXPECT_EQ(usage.cameras_lost, 1U);
  EXPECT_EQ(monitor.cameras_lost(now), 1U);
  // Exactly at the threshold a camera is still live; 1 ns beyond, lost.
  EXPECT_EQ(monitor.cameras_lost(kWall + 1000 * kMs), 0U);
  EXPECT_EQ(monitor.cameras_lost(kWall + 1000 * kMs + 1), 1U);
  EXPECT_STREQ(to_string(CameraState::kLost), "lost");
}

TEST(CameraHealth, WithoutArrivalTimesOrNowHealthIsUnknown) {
  const Tracker tracker;
  UsageMonitor monitor;
  monitor.note_received("c0", 2.0);  // offline: no arrival time
  monitor.note_received("c1", 2.0, kWall);
  const auto offline = monitor.summarize(tracker, 0, 0, {}, kWall + 10 * kMs);
  EXPECT_EQ(camera(offline, "c0").state, CameraState::kUnknown);
  EXPECT_EQ(camera(offline, "c0").since_last_frame_s, -1);
  EXPECT_EQ(camera(offline, "c1").state, CameraState::kLive);
  const auto no_now = monitor.summarize(tracker, 0, 0);
  EXPECT_EQ(camera(no_now, "c1").state, CameraState::kUnknown);
  EXPECT_EQ(no_now.cameras_live + no_now.cameras_lost, 0U);
}

TEST(CameraHealth, TracksHeldWhileEveryCameraIsLostAreUnobserved) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  Tracker tracker;
  tracker.set_calibration(scene.calibration());
  UsageMonitor monitor;
  monitor.set_lost_after(500 * kMs);
  TimeNs last_arrival = 0;
  for (const auto& c : scene.cameras()) {
    const CameraSimulator simulator(scene, c.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < 1'000 * kMs; ++k) {
      const TimeNs arrival = kWall + simulator.frame_time_ns(k) + 2 * kMs;
      monitor.note_received(c.calibration.id, 2.0, arrival);
      last_arrival = std::max(last_arrival, arrival);
    }
  }
  // The tracker gets the frames in stamp order.
  std::vector<FeatureFrame> frames;
  for (const auto& c : scene.cameras()) {
    const CameraSimulator simulator(scene, c.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < 1'000 * kMs; ++k)
      frames.push_back(simulator.features(k));
  }
  std::stable_sort(frames.begin(), frames.end(),
                   [](const FeatureFrame& a, const FeatureFrame& b) { return a.stamp_ns < b.stamp_ns; });
  for (const auto& frame : frames) tracker.process(frame);

  const auto seen = monitor.summarize(tracker, 0, 0, {}, last_arrival + 100 * kMs);
  const std::size_t tracks = seen.tracks_confirmed + seen.tracks_tentative + seen.tracks_coasting;
  ASSERT_GT(tracks, 0U);
  EXPECT_EQ(seen.cameras_live, scene.cameras().size());
  EXPECT_EQ(seen.tracks_unobserved, 0U);  // cameras live: the tracks are observed

  const auto blind = monitor.summarize(tracker, 0, 0, {}, last_arrival + 600 * kMs);
  EXPECT_EQ(blind.cameras_live, 0U);
  EXPECT_EQ(blind.cameras_lost, scene.cameras().size());
  EXPECT_EQ(blind.tracks_unobserved, tracks);
}

TEST(CameraOwnership, ASecondWriterIsRefusedWhileTheOwnerSends) {
  CameraOwnership ownership(500 * kMs);
  EXPECT_EQ(ownership.claim("c0", "A", kWall).verdict, CameraOwnership::Verdict::kOwner);
  EXPECT_EQ(ownership.claim("c1", "B", kWall).verdict, CameraOwnership::Verdict::kOwner);
  // B claims c0 10 ms later: refused, the first time reported as such, naming the owner.
  auto refused = ownership.claim("c0", "B", kWall + 10 * kMs);
  EXPECT_EQ(refused.verdict, CameraOwnership::Verdict::kRefused);
  EXPECT_TRUE(refused.first_refusal);
  EXPECT_EQ(refused.owner, "A");
  // 100 frames each, interleaved at 100 Hz for 1 s: A's all accepted, B's all refused.
  int accepted = 0;
  int refusals_reported = 0;
  for (int k = 1; k <= 100; ++k) {
    const TimeNs t = kWall + 10 * kMs * k;
    accepted += ownership.claim("c0", "A", t).verdict == CameraOwnership::Verdict::kOwner;
    const auto b = ownership.claim("c0", "B", t + 5 * kMs);
    EXPECT_EQ(b.verdict, CameraOwnership::Verdict::kRefused);
    refusals_reported += b.first_refusal;
  }
  EXPECT_EQ(accepted, 100);
  EXPECT_EQ(refusals_reported, 0);  // reported once, above
  EXPECT_EQ(ownership.refused_frames(), 101U);
  EXPECT_EQ(ownership.owner("c0"), "A");
  EXPECT_EQ(ownership.owner("c1"), "B");  // its own camera is untouched
  // An unknown writer (offline, no GUID) is not checked.
  EXPECT_EQ(ownership.claim("c0", "", kWall).verdict, CameraOwnership::Verdict::kOwner);
}

TEST(CameraOwnership, ASilentOwnerHandsTheIdOverToANewWriter) {
  CameraOwnership ownership(500 * kMs);
  ownership.claim("c0", "A", kWall);
  // The camera node restarts: its new writer C, 500 ms after A's last frame, is still refused...
  EXPECT_EQ(ownership.claim("c0", "C", kWall + 500 * kMs).verdict, CameraOwnership::Verdict::kRefused);
  // ...and takes over just after.
  EXPECT_EQ(ownership.claim("c0", "C", kWall + 500 * kMs + 1).verdict, CameraOwnership::Verdict::kHandedOver);
  EXPECT_EQ(ownership.owner("c0"), "C");
  EXPECT_EQ(ownership.claim("c0", "C", kWall + 510 * kMs).verdict, CameraOwnership::Verdict::kOwner);
  // The old writer, back, is now the newcomer.
  EXPECT_EQ(ownership.claim("c0", "A", kWall + 520 * kMs).verdict, CameraOwnership::Verdict::kRefused);
}

TEST(CameraHealth, RefusedFramesAreCountedPerCameraAndByReason) {
  const Tracker tracker;
  UsageMonitor monitor;
  monitor.note_received("c0", 2.0, kWall);
  monitor.note_refused("c0", true);
  for (int i = 0; i < 41; ++i) monitor.note_refused("c0", false);
  const auto usage = monitor.summarize(tracker, 0, 0, {}, kWall);
  EXPECT_EQ(camera(usage, "c0").refused_frames, 42U);
  EXPECT_EQ(camera(usage, "c0").refused_writers, 1U);
  EXPECT_EQ(camera(usage, "c0").frames, 1U);  // refused frames are not received ones
  EXPECT_EQ(usage.counters.at("camera_id_claimed_by_second_writer"), 42U);
  EXPECT_NE(usage.lines().front().find("refused 42 from 1 second writer(s)"), std::string::npos);
}

}  // namespace
}  // namespace panoptes::estimator
