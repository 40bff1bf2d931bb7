// SPDX-License-Identifier: Apache-2.0
// Re-sampling asynchronous track and pose updates to a fixed rate: linear interpolation between
// the bracketing updates, gaps beyond max_gap left invalid, slerp for orientations.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "panoptes/formats/resample.h"

namespace panoptes {
namespace {

constexpr TimeNs kMs = kNsPerMillisecond;
constexpr TimeNs kEpoch = 1'700'000'000'000'000'000;

TrackRecord track(std::int64_t id, TimeNs t, const Eigen::Vector3d& p,
                  TrackStatus status = TrackStatus::kConfirmed) {
  TrackRecord record;
  record.id = id;
  record.stamp_ns = kEpoch + t;
  record.p = p;
  record.status = status;
  record.cameras = 3;
  record.position_covariance = {4e-6, 0, 0, 4e-6, 0, 4e-6};  // 2 mm sigma on each axis
  return record;
}

TEST(Resample, GridCoversEveryStampAtTheRate) {
  const std::vector<TrackRecord> tracks = {track(1, 0, {0, 0, 0}), track(1, 1000 * kMs, {1, 0, 0})};
  ResampleOptions options;
  options.rate_hz = 100.0;
  const SampleGrid grid = make_grid(tracks, {}, options);
  EXPECT_EQ(grid.start_ns, kEpoch);
  EXPECT_EQ(grid.count, 101U);
  EXPECT_EQ(grid.time_ns(100), kEpoch + 1000 * kMs);
  options.rate_hz = 0.0;
  EXPECT_THROW(make_grid(tracks, {}, options), std::invalid_argument);
  options.rate_hz = 100.0;
  EXPECT_THROW(make_grid({}, {}, options), std::invalid_argument);
}

TEST(Resample, LinearBetweenBracketingUpdatesAndInvalidAcrossLongGaps) {
  // Updates at 0, 7, 30 ms (asynchronous: no update on the 10 ms grid) and after a 200 ms gap.
  const std::vector<TrackRecord> tracks = {track(5, 30 * kMs, {3, 0, 0}),    track(5, 0, {0, 0, 0}),
                                           track(5, 7 * kMs, {0.7, 0.7, 0}), track(5, 230 * kMs, {3, 2, 0}),
                                           track(9, 100 * kMs, {0, 0, 1}),   track(9, 120 * kMs, {0, 0, 3})};
  ResampleOptions options;
  options.rate_hz = 100.0;
  options.max_gap_ns = 50 * kMs;
  const SampleGrid grid = make_grid(tracks, {}, options);
  const MarkerTrajectories out = resample_tracks(tracks, grid, options);
  ASSERT_EQ(out.marker_names, (std::vector<std::string>{"track_5", "track_9"}));
  ASSERT_EQ(out.frame_count(), 24U);  // 0 .. 230 ms
  EXPECT_DOUBLE_EQ(out.times_s[3], 0.03);
  // t = 10 ms lies between 7 ms (0.7, 0.7) and 30 ms (3, 0): weight 3/23 on the later one.
  const Eigen::Vector3d expected =
      (20.0 / 23.0) * Eigen::Vector3d(0.7, 0.7, 0) + (3.0 / 23.0) * Eigen::Vector3d(3, 0, 0);
  EXPECT_TRUE(out.is_valid(1, 0));
  EXPECT_LT((out.position(1, 0) - expected).norm(), 1e-12);
  EXPECT_LT((out.position(3, 0) - Eigen::Vector3d(3, 0, 0)).norm(), 1e-12);  // exactly on an update
  // 30 -> 230 ms is longer than max_gap: invalid in between, valid again on the update.
  for (std::size_t k = 4; k < 23; ++k) EXPECT_FALSE(out.is_valid(k, 0)) << k;
  EXPECT_TRUE(out.is_valid(23, 0));
  // Track 9 lives 100..120 ms only: no extrapolation before or after.
  EXPECT_FALSE(out.is_valid(9, 1));
  EXPECT_TRUE(out.is_valid(10, 1));
  EXPECT_LT((out.position(11, 1) - Eigen::Vector3d(0, 0, 2)).norm(), 1e-12);
  EXPECT_TRUE(out.is_valid(12, 1));
  EXPECT_FALSE(out.is_valid(13, 1));
  // Residual: 2 mm (root mean variance); three cameras: mask 0b111.
  EXPECT_NEAR(out.residuals_m[1 * 2 + 0], 0.002, 1e-9);
  EXPECT_EQ(out.camera_masks[1 * 2 + 0], 0x07);
}

TEST(Resample, CoastingIsComputedAndTentativeIsLeftOut) {
  const std::vector<TrackRecord> tracks = {track(1, 0, {0, 0, 0}, TrackStatus::kCoasting),
                                           track(1, 10 * kMs, {1, 0, 0}, TrackStatus::kCoasting),
                                           track(2, 0, {0, 0, 0}, TrackStatus::kTentative),
                                           track(2, 10 * kMs, {0, 0, 0}, TrackStatus::kTentative)};
  ResampleOptions options;
  const SampleGrid grid = make_grid(tracks, {}, options);
  const MarkerTrajectories out = resample_tracks(tracks, grid, options);
  ASSERT_EQ(out.marker_names, std::vector<std::string>{"track_1"});
  EXPECT_EQ(out.residuals_m[0], 0.0F);  // C3D: computed, not measured
  EXPECT_EQ(out.camera_masks[0], 0);
  options.include_tentative = true;
  EXPECT_EQ(resample_tracks(tracks, grid, options).marker_count(), 2U);
}

TEST(Resample, PosesSlerpAlongTheShorterArc) {
  const double angle = std::numbers::pi / 2;
  const Eigen::Quaterniond q1(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
  for (const double sign : {1.0, -1.0}) {  // q and -q are the same rotation
    PoseRecord a;
    a.body = "wand";
    a.stamp_ns = kEpoch;
    PoseRecord b = a;
    b.stamp_ns = kEpoch + 100 * kMs;
    b.p = Eigen::Vector3d(1, 2, 3);
    b.q = sign * Eigen::Vector4d(q1.x(), q1.y(), q1.z(), q1.w());
    ResampleOptions options;
    options.rate_hz = 20.0;
    const SampleGrid grid = make_grid({}, {a, b}, options);
    const BodyTrajectories out = resample_poses({a, b}, grid, options);
    ASSERT_EQ(out.frame_count(), 3U);
    ASSERT_EQ(out.body_names, std::vector<std::string>{"wand"});
    const Eigen::Vector4d& q = out.quaternions[1];
    const Eigen::Quaterniond half(Eigen::AngleAxisd(angle / 2, Eigen::Vector3d::UnitZ()));
    EXPECT_NEAR(std::abs(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).dot(half)), 1.0, 1e-12);
    EXPECT_LT((out.positions[1] - Eigen::Vector3d(0.5, 1, 1.5)).norm(), 1e-12);
    MarkerTrajectories markers = resample_tracks({}, grid, options);
    append_body_origins(markers, out);
    ASSERT_EQ(markers.marker_names, std::vector<std::string>{"wand"});
    EXPECT_LT((markers.position(2, 0) - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace panoptes
