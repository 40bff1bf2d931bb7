// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/estimator/frame_screen.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kNow = 1'700'000'000'000'000'000LL;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Blob good_blob(double x = 100.5, double y = 200.25) {
  Blob blob;
  blob.x = x;
  blob.y = y;
  blob.area = 12;
  blob.sum = 2400;
  blob.peak = 220;
  blob.m20 = blob.m02 = 1.1;
  return blob;
}

FeatureFrame good_frame(int blobs = 3) {
  FeatureFrame frame;
  frame.camera_id = "cam0";
  frame.frame = 7;
  frame.stamp_ns = kNow;
  for (int i = 0; i < blobs; ++i) frame.blobs.push_back(good_blob(10.0 * i, 5.0 * i));
  return frame;
}

TEST(FrameScreen, PassesAGoodFrameUntouched) {
  FrameScreen screen;
  FeatureFrame frame = good_frame();
  EXPECT_TRUE(screen.screen(frame, kNow + kNsPerSecond));
  EXPECT_EQ(frame.blobs.size(), 3u);
  EXPECT_TRUE(screen.counts().empty());
  EXPECT_EQ(screen.stats().frames, 1u);
  EXPECT_EQ(screen.stats().blobs, 3u);
  // An empty frame is information (the camera saw nothing), not an error.
  FeatureFrame empty = good_frame(0);
  EXPECT_TRUE(screen.screen(empty, kNow));
  EXPECT_TRUE(screen.counts().empty());
}

TEST(FrameScreen, DropsBlobsWithNonFiniteValues) {
  FrameScreen screen;
  FeatureFrame frame = good_frame(1);
  const double bad_values[] = {kNaN, kInf, -kInf};
  for (double bad : bad_values) {
    for (int field = 0; field < 7; ++field) {
      Blob blob = good_blob();
      double* fields[] = {&blob.x, &blob.y, &blob.area, &blob.sum, &blob.m20, &blob.m11, &blob.m02};
      *fields[field] = bad;
      frame.blobs.push_back(blob);
    }
  }
  ASSERT_TRUE(screen.screen(frame, kNow));
  ASSERT_EQ(frame.blobs.size(), 1u);  // only the good one is left
  EXPECT_EQ(frame.blobs[0].x, good_blob(0, 0).x);
  EXPECT_EQ(screen.count(screen_reason::kNonFiniteBlob), 21u);
  EXPECT_EQ(screen.stats().blobs_dropped, 21u);
  EXPECT_EQ(screen.stats().blobs, 22u);
}

TEST(FrameScreen, DropsBlobsWithNegativeArea) {
  FrameScreen screen;
  FeatureFrame frame = good_frame(2);
  frame.blobs[0].area = -1;
  frame.blobs[1].area = -1e-9;
  frame.blobs.push_back(good_blob());
  frame.blobs.back().area = 0;  // zero is a degenerate but finite blob: kept
  ASSERT_TRUE(screen.screen(frame, kNow));
  EXPECT_EQ(frame.blobs.size(), 1u);
  EXPECT_EQ(screen.count(screen_reason::kNegativeArea), 2u);
  // A NaN area is a non-finite blob, not a negative one: one reason per blob.
  FeatureFrame nan_area = good_frame(1);
  nan_area.blobs[0].area = kNaN;
  ASSERT_TRUE(screen.screen(nan_area, kNow));
  EXPECT_EQ(screen.count(screen_reason::kNegativeArea), 2u);
  EXPECT_EQ(screen.count(screen_reason::kNonFiniteBlob), 1u);
}

TEST(FrameScreen, DropsBlobsFarOutsideAnyImage) {
  FrameScreen screen;
  FeatureFrame frame = good_frame(0);
  frame.blobs = {good_blob(-0.5, -0.5), good_blob(99'999, 4000), good_blob(1e300, 10),
                 good_blob(10, -1e5 - 1), good_blob(-2e5, 3)};
  ASSERT_TRUE(screen.screen(frame, kNow));
  EXPECT_EQ(frame.blobs.size(), 2u);
  EXPECT_EQ(screen.count(screen_reason::kBlobOutOfRange), 3u);
}

TEST(FrameScreen, RejectsFramesWithTooManyBlobs) {
  FrameScreenOptions options;
  options.max_blobs = 100;
  FrameScreen screen(options);
  FeatureFrame at_limit = good_frame(100);
  EXPECT_TRUE(screen.screen(at_limit, kNow));
  FeatureFrame over = good_frame(101);
  EXPECT_FALSE(screen.screen(over, kNow));
  EXPECT_EQ(screen.count(screen_reason::kTooManyBlobs), 1u);

  // The default limit against a million blobs, all of them bad: rejected as a whole, so none of
  // them is looked at or counted as a blob.
  FrameScreen defaults;
  FeatureFrame huge = good_frame(0);
  huge.blobs.assign(1'000'000, good_blob(kNaN, kNaN));
  EXPECT_FALSE(defaults.screen(huge, kNow));
  EXPECT_EQ(defaults.count(screen_reason::kTooManyBlobs), 1u);
  EXPECT_EQ(defaults.count(screen_reason::kNonFiniteBlob), 0u);
  EXPECT_EQ(defaults.stats().blobs, 0u);
  EXPECT_EQ(huge.blobs.size(), 1'000'000u);  // a rejected frame is left as it was
}

TEST(FrameScreen, RejectsStampsFarFromTheReference) {
  FrameScreen screen;  // 10 s
  for (TimeNs offset :
       {-3600 * kNsPerSecond, -10 * kNsPerSecond - 1, 10 * kNsPerSecond + 1, 3600 * kNsPerSecond}) {
    FeatureFrame frame = good_frame();
    frame.stamp_ns = kNow + offset;
    EXPECT_FALSE(screen.screen(frame, kNow)) << offset;
  }
  for (TimeNs offset : {-10 * kNsPerSecond, -kNsPerSecond, TimeNs{0}, 10 * kNsPerSecond}) {
    FeatureFrame frame = good_frame();
    frame.stamp_ns = kNow + offset;
    EXPECT_TRUE(screen.screen(frame, kNow)) << offset;
  }
  EXPECT_EQ(screen.count(screen_reason::kStampOutOfRange), 4u);
  // The largest stamps must not overflow the difference.
  FeatureFrame far = good_frame();
  far.stamp_ns = std::numeric_limits<TimeNs>::max();
  EXPECT_FALSE(screen.screen(far, 1));
  EXPECT_EQ(screen.count(screen_reason::kStampOutOfRange), 5u);
  // Without a reference only the sign of the stamp is checked.
  EXPECT_TRUE(screen.screen(far, 0));
}

TEST(FrameScreen, LiveRejectsStampsAheadOfTheWallClock) {
  FrameScreen screen;  // 200 ms
  FeatureFrame ahead = good_frame();
  ahead.stamp_ns = kNow + 200 * kNsPerMillisecond + 1;
  EXPECT_FALSE(screen.screen_live(ahead, kNow));
  EXPECT_EQ(screen.count(screen_reason::kStampInFuture), 1u);
  // Offline the reference is not a clock (sorting already puts such a frame where it does no
  // harm): only the symmetric skew applies.
  EXPECT_TRUE(screen.screen(ahead, kNow));
  for (TimeNs offset : {200 * kNsPerMillisecond, TimeNs{0}, -9 * kNsPerSecond}) {
    FeatureFrame frame = good_frame();
    frame.stamp_ns = kNow + offset;
    EXPECT_TRUE(screen.screen_live(frame, kNow)) << offset;
  }
  // An hour ahead is out of range first.
  FeatureFrame far = good_frame();
  far.stamp_ns = kNow + 3600 * kNsPerSecond;
  EXPECT_FALSE(screen.screen_live(far, kNow));
  EXPECT_EQ(screen.count(screen_reason::kStampInFuture), 1u);
  EXPECT_EQ(screen.count(screen_reason::kStampOutOfRange), 1u);
}

TEST(FrameScreen, RejectsNonPositiveStamps) {
  FrameScreen screen;
  for (TimeNs stamp : {TimeNs{0}, TimeNs{-1}, std::numeric_limits<TimeNs>::min()}) {
    FeatureFrame frame = good_frame();
    frame.stamp_ns = stamp;
    EXPECT_FALSE(screen.screen(frame, kNow));
    EXPECT_FALSE(screen.screen(frame, 0));
  }
  EXPECT_EQ(screen.count(screen_reason::kNonPositiveStamp), 6u);
  EXPECT_EQ(screen.count(screen_reason::kStampOutOfRange), 0u);
}

TEST(FrameScreen, RejectsBadCameraIds) {
  FrameScreen screen;
  const std::string bad_ids[] = {"", std::string(257, 'c'), std::string("cam\0x", 5), "cam\n0", "\x7f"};
  for (const auto& id : bad_ids) {
    FeatureFrame frame = good_frame();
    frame.camera_id = id;
    EXPECT_FALSE(screen.screen(frame, kNow)) << id.size();
  }
  EXPECT_EQ(screen.count(screen_reason::kBadCameraId), 5u);
  const std::string good_ids[] = {"c", "cam-07_left", std::string(256, 'c'), "kamera-\xc3\xa9"};
  for (const auto& id : good_ids) {
    FeatureFrame frame = good_frame();
    frame.camera_id = id;
    EXPECT_TRUE(screen.screen(frame, kNow)) << id;
  }
}

TEST(FrameScreen, CountsEveryFrameUnderOneReasonAndTheTotalsAddUp) {
  FrameScreen screen;
  FeatureFrame frame = good_frame();
  frame.camera_id = "";
  frame.stamp_ns = -5;
  frame.blobs.assign(5000, good_blob(kNaN, 0));
  EXPECT_FALSE(screen.screen(frame, kNow));  // the first reason, the camera id, is the one counted
  EXPECT_EQ(screen.counts().size(), 1u);
  EXPECT_EQ(screen.count(screen_reason::kBadCameraId), 1u);

  FeatureFrame mixed = good_frame(4);
  mixed.blobs[1].x = kNaN;
  mixed.blobs[2].area = -3;
  mixed.blobs[3].y = 1e7;
  EXPECT_TRUE(screen.screen(mixed, kNow));
  EXPECT_EQ(mixed.blobs.size(), 1u);
  const auto& s = screen.stats();
  EXPECT_EQ(s.frames, 2u);
  EXPECT_EQ(s.frames_rejected, 1u);
  EXPECT_EQ(s.blobs, 4u);
  EXPECT_EQ(s.blobs_dropped, 3u);
  std::uint64_t total = 0;
  for (const auto& [reason, n] : screen.counts()) total += n;
  EXPECT_EQ(total, s.frames_rejected + s.blobs_dropped);
}

TEST(OfflineReferenceStamps, IgnoresGarbageAtTheEndsAndFollowsLongRecordings) {
  // 40 s of one camera at 30 Hz (longer than the 10 s skew), with garbage stamps sorted to both
  // ends: an hour early, and an hour late.
  std::vector<FeatureFrame> frames;
  auto add = [&](TimeNs stamp) {
    frames.push_back(good_frame(0));
    frames.back().stamp_ns = stamp;
  };
  for (int i = 0; i < 10; ++i) add(kNow - 3600 * kNsPerSecond + i);
  for (int i = 0; i < 1200; ++i) add(kNow + i * kNsPerSecond / 30);
  for (int i = 0; i < 10; ++i) add(kNow + 3600 * kNsPerSecond + i);
  const auto references = offline_reference_stamps(frames);
  ASSERT_EQ(references.size(), frames.size());
  FrameScreen screen;
  std::size_t accepted = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const bool ok = screen.screen(frames[i], references[i]);
    const bool real = i >= 10 && i < 1210;
    EXPECT_EQ(ok, real) << i;
    accepted += ok ? 1 : 0;
  }
  EXPECT_EQ(accepted, 1200u);
  EXPECT_EQ(screen.count(screen_reason::kStampOutOfRange), 20u);
  EXPECT_TRUE(offline_reference_stamps({}).empty());
}

}  // namespace
}  // namespace panoptes::estimator
