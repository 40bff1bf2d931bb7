// SPDX-License-Identifier: Apache-2.0
// Adaptive process noise (issue 35 item 2; docs/estimator.md, "Adaptive process noise"): a marker
// on a swung club (25 m/s through the bottom) keeps one identity with the default settings, also
// when it leaves every view at the top of the swing (rejoin_fast_tracks), and a slow marker is
// tracked as well as with one fixed σ².
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "panoptes/estimator/tracker.h"
#include "test_cameras.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;

// A pendulum swing about a pivot 1.7 m up, θ(t) = 2.5 sin(10 t): the head, 1.0 m out, at
// 25 m/s through the bottom (centripetal 625 m/s²), or a slow circle at 0.5 m/s.
Eigen::Vector3d club_head(double t) {
  const double amplitude = 2.5, omega = 10.0;  // peak angular speed 25 rad/s at r = 1 m
  const double theta = amplitude * std::sin(omega * t);
  return {std::sin(theta), 0.1, 1.7 - std::cos(theta)};
}

Eigen::Vector3d slow_marker(double t) {
  return {0.5 * std::cos(t), 0.5 * std::sin(t), 1.0};
}

struct Result {
  std::set<std::int64_t> ids;
  int instants = 0;  // while the marker is visible
  int tracked = 0;
  double sum2 = 0;
};

// `hidden`: where no camera sees the marker (none: everywhere visible).
template <class Path>
Result track(Path path, const TrackerOptions& options, double duration_s,
             const std::function<bool(const Eigen::Vector3d&)>& hidden = nullptr) {
  const auto cameras = make_ring_calibration(6, 4.0, 2.5, true);
  std::vector<CameraModel> models;
  for (const auto& c : cameras) models.push_back(c.model());
  Tracker tracker(options);
  tracker.set_calibration(SystemCalibration{cameras});
  std::mt19937_64 rng(35);
  std::normal_distribution<double> noise(0.0, 0.1);
  Result result;
  // Six cameras at 110 Hz, phases spread over the frame interval.
  const TimeNs period = 9'090'909;
  for (int k = 0; k < static_cast<int>(duration_s * 110); ++k) {
    for (std::size_t c = 0; c < models.size(); ++c) {
      const TimeNs t = k * period + static_cast<TimeNs>(c) * period / 6;
      FeatureFrame frame;
      frame.camera_id = cameras[c].id;
      frame.frame = k;
      frame.stamp_ns = kEpoch + t;
      const Eigen::Vector3d p = path(ns_to_seconds(t));
      const bool seen = !hidden || !hidden(p);
      const auto pixel = models[c].project(p);
      if (seen && pixel && models[c].in_image(*pixel)) {
        Blob blob;
        blob.x = pixel->x() + noise(rng);
        blob.y = pixel->y() + noise(rng);
        blob.area = 12;
        frame.blobs.push_back(blob);
      }
      EXPECT_EQ(tracker.process(frame), FrameOutcome::kProcessed);
      if (ns_to_seconds(t) < 0.3 || !seen) continue;
      ++result.instants;
      for (const auto& record : tracker.current_tracks()) {
        const double error = (record.p - p).norm();
        if (error < 0.02) {
          result.ids.insert(record.id);
          ++result.tracked;
          result.sum2 += error * error;
          break;
        }
      }
    }
  }
  return result;
}

TEST(AdaptiveNoise, SwungClubHeadKeepsOneIdentityWithTheDefaults) {
  const Result r = track(club_head, TrackerOptions{}, 3.0);
  std::printf("adaptive: %zu ids, tracked %d of %d instants\n", r.ids.size(), r.tracked, r.instants);
  EXPECT_EQ(r.ids.size(), 1u) << "the club head changed identity";
  EXPECT_GE(r.tracked, 0.99 * r.instants) << r.tracked << " of " << r.instants;
}

TEST(AdaptiveNoise, FixedDefaultNoiseLosesTheClubHead) {
  // The same scene with adaptation off: the test above is not passing by accident of the scene.
  TrackerOptions fixed;
  fixed.process_noise_max_scale = 1.0;
  const Result r = track(club_head, fixed, 3.0);
  std::printf("fixed: %zu ids, tracked %d of %d instants\n", r.ids.size(), r.tracked, r.instants);
  EXPECT_TRUE(r.ids.size() > 1u || r.tracked < 0.99 * r.instants)
      << r.ids.size() << " ids, " << r.tracked << " of " << r.instants;
}

// Above 2.35 m no camera sees the head: ~84 ms at the top of every swing (it leaves at ~10 m/s and
// comes back where it left). The track coasts on a straight line meanwhile, far from the return.
bool above_the_views(const Eigen::Vector3d& p) {
  return p.z() > 2.35;
}

TEST(AdaptiveNoise, ClubHeadThatLeavesEveryViewRejoinsItsIdentity) {
  const Result r = track(club_head, TrackerOptions{}, 3.0, above_the_views);
  std::printf("rejoin: %zu ids, tracked %d of %d visible instants\n", r.ids.size(), r.tracked, r.instants);
  EXPECT_EQ(r.ids.size(), 1u) << "the club head came back under another identity";
  EXPECT_GE(r.tracked, 0.95 * r.instants) << r.tracked << " of " << r.instants;
  // Without the rejoin every top of the swing starts a new identity (the test is not vacuous).
  TrackerOptions off;
  off.rejoin_fast_tracks = false;
  const Result without = track(club_head, off, 3.0, above_the_views);
  std::printf("no rejoin: %zu ids\n", without.ids.size());
  EXPECT_GT(without.ids.size(), 3u);
}

TEST(AdaptiveNoise, SlowMarkerAsAccurateAsWithFixedNoise) {
  TrackerOptions fixed;
  fixed.process_noise_max_scale = 1.0;
  const Result adaptive = track(slow_marker, TrackerOptions{}, 3.0);
  const Result reference = track(slow_marker, fixed, 3.0);
  ASSERT_GT(adaptive.tracked, 0);
  ASSERT_GT(reference.tracked, 0);
  const double rmse = std::sqrt(adaptive.sum2 / adaptive.tracked);
  const double rmse_fixed = std::sqrt(reference.sum2 / reference.tracked);
  std::printf("slow marker RMSE: adaptive %.4f mm, fixed %.4f mm\n", rmse * 1e3, rmse_fixed * 1e3);
  EXPECT_LE(rmse, 1.03 * rmse_fixed);
  EXPECT_EQ(adaptive.ids.size(), 1u);
}

}  // namespace
}  // namespace panoptes::estimator
