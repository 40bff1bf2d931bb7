// SPDX-License-Identifier: Apache-2.0
// Seeded fuzz / property tests of the input path: JSON Lines parsing, FrameScreen, Tracker
// (issue 4). Garbage must come back as counted errors, never as an exception, a crash or a
// poisoned tracker: after all of it, the tracker must still track a real marker.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/estimator/frame_screen.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/jsonl.h"
#include "panoptes/records.h"
#include "test_cameras.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using Rng = std::mt19937_64;

double uniform(Rng& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}
int uniform_int(Rng& rng, int low, int high) {  // [low, high]
  return std::uniform_int_distribution<int>(low, high)(rng);
}
bool chance(Rng& rng, double p) {
  return uniform(rng, 0, 1) < p;
}

// A value of the kind a broken or hostile sender produces.
double extreme_value(Rng& rng) {
  static const double values[] = {kNaN, kInf, -kInf, 1e300, -1e300, 1e308, -0.0, 5e-324, -1e5 - 1, 1e5 + 1};
  return values[uniform_int(rng, 0, static_cast<int>(std::size(values)) - 1)];
}

// A blob inside the image; with `extremes`, sometimes one field is absurd or the area negative.
Blob random_blob(Rng& rng, double width, double height, bool extremes = true) {
  Blob blob;
  blob.x = uniform(rng, -0.5, width - 0.5);
  blob.y = uniform(rng, -0.5, height - 0.5);
  blob.area = uniform(rng, 0, 80);
  blob.sum = uniform(rng, 0, 1e5);
  blob.peak = uniform_int(rng, 0, 65535);
  blob.m20 = uniform(rng, 0, 10);
  blob.m02 = uniform(rng, 0, 10);
  blob.m11 = uniform(rng, -1, 1);
  if (!extremes) return blob;
  if (chance(rng, 0.3)) {
    double* fields[] = {&blob.x, &blob.y, &blob.area, &blob.sum, &blob.m20, &blob.m11, &blob.m02};
    *fields[uniform_int(rng, 0, 6)] = extreme_value(rng);
  }
  if (chance(rng, 0.05)) blob.area = -uniform(rng, 0, 100);
  return blob;
}

// A valid frame to mutate.
FeatureFrame sample_frame(Rng& rng) {
  FeatureFrame frame;
  frame.camera_id = "cam" + std::to_string(uniform_int(rng, 0, 3));
  frame.frame = uniform_int(rng, 0, 100000);
  frame.stamp_ns = kEpoch + uniform_int(rng, 0, 1'000'000'000);
  frame.arrival_ns = frame.stamp_ns + 3'000'000;
  frame.processing_ns = 120'000;
  const int blobs = uniform_int(rng, 0, 4);
  for (int i = 0; i < blobs; ++i) {
    Blob blob = random_blob(rng, 1280, 1024, false);
    blob.x0 = static_cast<int>(blob.x) - 2;
    blob.y0 = static_cast<int>(blob.y) - 2;
    blob.x1 = blob.x0 + 5;
    blob.y1 = blob.y0 + 5;
    frame.blobs.push_back(blob);
  }
  return frame;
}

std::string random_bytes(Rng& rng, std::size_t length) {
  std::string bytes(length, '\0');
  for (char& c : bytes) c = static_cast<char>(uniform_int(rng, 0, 255));
  return bytes;
}

// One of several mutations of a valid JSON line: byte flips, deletions, truncation, and tokens
// that parse but carry absurd values (overflowing numbers, wrong types, lone surrogates).
std::string mutate(const std::string& line, Rng& rng) {
  static const char* tokens[] = {"NaN",
                                 "1e999",
                                 "-1e999",
                                 "1e300",
                                 "-1e300",
                                 "null",
                                 "[]",
                                 "{}",
                                 "\"x\"",
                                 "-0",
                                 "0.5",
                                 "true",
                                 "18446744073709551615",
                                 "9223372036854775808",
                                 "-9223372036854775809",
                                 "9223372036854775807",
                                 "-9223372036854775808",
                                 "\"\\u0000\"",
                                 "\"\\ud800\"",
                                 "[1,2,3,4]",
                                 "1e-400",
                                 "\"\xff\xfe\""};
  std::string out = line;
  const int rounds = uniform_int(rng, 1, 3);
  for (int round = 0; round < rounds && !out.empty(); ++round) {
    const std::size_t at = static_cast<std::size_t>(uniform_int(rng, 0, static_cast<int>(out.size()) - 1));
    switch (uniform_int(rng, 0, 5)) {
      case 0:  // flip a byte
        out[at] = static_cast<char>(uniform_int(rng, 1, 255));
        break;
      case 1:  // delete a span
        out.erase(at, static_cast<std::size_t>(uniform_int(rng, 1, 8)));
        break;
      case 2:  // truncate
        out.resize(at);
        break;
      case 3: {  // replace the number (or token) starting at the next digit
        const std::size_t begin = out.find_first_of("-0123456789", at);
        if (begin == std::string::npos) break;
        const std::size_t end = out.find_first_of(",]}", begin);
        out.replace(begin, (end == std::string::npos ? out.size() : end) - begin,
                    tokens[uniform_int(rng, 0, static_cast<int>(std::size(tokens)) - 1)]);
        break;
      }
      case 4:  // insert a token
        out.insert(at, tokens[uniform_int(rng, 0, static_cast<int>(std::size(tokens)) - 1)]);
        break;
      default:  // duplicate a span (repeated keys, nested garbage)
        out.insert(at, out.substr(at, static_cast<std::size_t>(uniform_int(rng, 1, 40))));
        break;
    }
  }
  return out;
}

bool blank(const std::string& line) {
  return line.find_first_not_of(" \t") == std::string::npos;
}

struct Pipeline {
  std::vector<CameraCalibration> cameras = make_ring_calibration(4, 3.0, 2.0, true);
  FrameScreen screen;
  Tracker tracker;
  std::uint64_t offered = 0;
  std::uint64_t accepted_blobs = 0;
  std::map<FrameOutcome, std::uint64_t> outcomes;

  Pipeline() { tracker.set_calibration(SystemCalibration{cameras}); }

  std::optional<FrameOutcome> feed(FeatureFrame frame, TimeNs reference_ns) {
    ++offered;
    if (!screen.screen_live(frame, reference_ns)) return std::nullopt;
    accepted_blobs += frame.blobs.size();
    for (const Blob& blob : frame.blobs) {
      EXPECT_TRUE(std::isfinite(blob.x) && std::isfinite(blob.y) && std::isfinite(blob.area) &&
                  blob.area >= 0);
    }
    const FrameOutcome outcome = tracker.process(frame);
    ++outcomes[outcome];
    return outcome;
  }

  void expect_counters_add_up() const {
    const auto& s = screen.stats();
    std::uint64_t frame_reasons = 0, blob_reasons = 0;
    for (const auto& [reason, n] : screen.counts()) {
      const bool frame_reason =
          reason == screen_reason::kBadCameraId || reason == screen_reason::kNonPositiveStamp ||
          reason == screen_reason::kStampOutOfRange || reason == screen_reason::kStampInFuture ||
          reason == screen_reason::kTooManyBlobs;
      (frame_reason ? frame_reasons : blob_reasons) += n;
    }
    EXPECT_EQ(s.frames, offered);
    EXPECT_EQ(s.frames_rejected, frame_reasons);
    EXPECT_EQ(s.blobs_dropped, blob_reasons);
    EXPECT_EQ(s.blobs - s.blobs_dropped, accepted_blobs);
    std::uint64_t processed_calls = 0;
    for (const auto& [outcome, n] : outcomes) processed_calls += n;
    EXPECT_EQ(processed_calls, s.frames - s.frames_rejected);
    const auto& t = tracker.stats();
    EXPECT_EQ(t.frames, processed_calls);
    auto outcome_count = [&](FrameOutcome outcome) {
      const auto it = outcomes.find(outcome);
      return it == outcomes.end() ? std::uint64_t{0} : it->second;
    };
    EXPECT_EQ(t.frames_unknown_camera, outcome_count(FrameOutcome::kUnknownCamera));
    EXPECT_EQ(t.frames_late, outcome_count(FrameOutcome::kLateReplayed));
    EXPECT_EQ(t.frames_too_late, outcome_count(FrameOutcome::kTooLate));
  }
};

TEST(Fuzz, ParserTurnsRandomBytesAndMutatedLinesIntoErrorsNeverExceptions) {
  Rng rng(20261121);
  std::vector<std::string> lines;
  for (int i = 0; i < 1500; ++i)
    lines.push_back(random_bytes(rng, static_cast<std::size_t>(uniform_int(rng, 0, 300))));
  // Random bytes that start like a frame, so the parser gets past the first character.
  for (int i = 0; i < 500; ++i) lines.push_back("{\"camera_id\":\"cam0\"," + random_bytes(rng, 60));
  for (int i = 0; i < 4000; ++i) lines.push_back(mutate(to_json_line(sample_frame(rng)), rng));
  // A valid line must parse back to the same frame (the mutations start from something real).
  const FeatureFrame valid = sample_frame(rng);
  const auto round_trip = parse_feature_frame(to_json_line(valid));
  ASSERT_TRUE(round_trip.value) << round_trip.error;
  EXPECT_EQ(round_trip.value->blobs.size(), valid.blobs.size());

  // What parses goes on through the screen to the tracker, as in the offline node.
  Pipeline pipeline;
  std::size_t parsed = 0, errors = 0, non_finite_values = 0;
  for (const auto& line : lines) {
    Parsed<FeatureFrame> result;
    ASSERT_NO_THROW(result = parse_feature_frame(line));
    if (result.value) {
      ++parsed;
      pipeline.feed(*result.value, kEpoch + kNsPerSecond);
      EXPECT_TRUE(result.error.empty());
      for (const Blob& blob : result.value->blobs) {
        if (!std::isfinite(blob.x) || !std::isfinite(blob.y) || !std::isfinite(blob.area))
          ++non_finite_values;
      }
    } else {
      ++errors;
      EXPECT_FALSE(result.error.empty());
    }
  }
  std::printf("%zu lines: %zu parsed, %zu errors, %zu parsed blobs with an infinite coordinate or area\n",
              lines.size(), parsed, errors, non_finite_values);
  EXPECT_EQ(parsed + errors, lines.size());
  pipeline.expect_counters_add_up();
  EXPECT_GT(pipeline.tracker.stats().frames, 50u);
  EXPECT_GT(parsed, 100u);  // the mutations must leave many lines valid, or the screen is never reached
  EXPECT_GT(errors, 2000u);

  // The same lines through read_feature_frames: every non-blank line is a frame or an error, and
  // the frames are exactly the lines that parse on their own.
  const std::filesystem::path path = std::filesystem::path(::testing::TempDir()) /
                                     ("panoptes_fuzz_" + std::to_string(::getpid()) + ".jsonl");
  std::size_t expected_frames = 0, expected_lines = 0;
  {
    std::ofstream out(path, std::ios::binary);
    for (std::string line : lines) {
      std::replace(line.begin(), line.end(), '\n', ' ');  // one record per line
      std::replace(line.begin(), line.end(), '\r', ' ');
      out << line << '\n';
      if (blank(line)) continue;
      ++expected_lines;
      if (parse_feature_frame(line).value) ++expected_frames;
    }
  }
  std::vector<std::string> read_errors;
  std::vector<FeatureFrame> frames;
  ASSERT_NO_THROW(frames = read_feature_frames(path, &read_errors));
  std::filesystem::remove(path);
  EXPECT_EQ(frames.size(), expected_frames);
  EXPECT_EQ(frames.size() + read_errors.size(), expected_lines);
}

// A garbage frame: random camera id (calibrated, unknown, empty, binary, huge), stamp near the
// reference or an hour away or duplicated or decreasing or non-positive, blob counts from 0 to
// a few thousand, values from sane to NaN/inf/±1e300.
FeatureFrame garbage_frame(Rng& rng, TimeNs reference_ns, TimeNs previous_stamp) {
  FeatureFrame frame;
  switch (uniform_int(rng, 0, 9)) {
    case 0:
      frame.camera_id = "cam9";  // not calibrated
      break;
    case 1:
      frame.camera_id = chance(rng, 0.5) ? "" : std::string(300, 'x');
      break;
    case 2:
      frame.camera_id = random_bytes(rng, static_cast<std::size_t>(uniform_int(rng, 1, 12)));
      break;
    default:
      frame.camera_id = "cam" + std::to_string(uniform_int(rng, 0, 3));
  }
  frame.frame = uniform_int(rng, -10, 1 << 30);
  const TimeNs hour = 3600 * kNsPerSecond;
  switch (uniform_int(rng, 0, 9)) {
    case 0:
      frame.stamp_ns = reference_ns + (chance(rng, 0.5) ? hour : -hour) + uniform_int(rng, -1000, 1000);
      break;
    case 1:
      frame.stamp_ns = previous_stamp;  // duplicate
      break;
    case 2:
      frame.stamp_ns = previous_stamp - uniform_int(rng, 1, 50'000'000);  // decreasing
      break;
    case 3: {
      static const TimeNs odd[] = {0, -1, std::numeric_limits<TimeNs>::min(),
                                   std::numeric_limits<TimeNs>::max(), 1};
      frame.stamp_ns = odd[uniform_int(rng, 0, static_cast<int>(std::size(odd)) - 1)];
      break;
    }
    case 4:
      frame.stamp_ns = reference_ns + static_cast<TimeNs>(uniform(rng, -12.0, 12.0) * 1e9);  // near the edge
      break;
    case 5:
      frame.stamp_ns =
          reference_ns + static_cast<TimeNs>(uniform(rng, 0.0, 1.0) * 1e9);  // ahead of the clock
      break;
    default:
      frame.stamp_ns = reference_ns - uniform_int(rng, 0, 20'000'000);
  }
  int blobs = uniform_int(rng, 0, 24);
  // Large frames: over the limit (rejected), or at the limit but all bad (every blob dropped).
  // Thousands of plausible blobs are not sent to the tracker: its initiation is not meant to be
  // fast on them, and speed is the benchmark's business.
  const bool large = chance(rng, 0.01);
  if (large) blobs = uniform_int(rng, 4000, 6000);
  for (int i = 0; i < blobs; ++i) {
    Blob blob = random_blob(rng, 1280, 1024);
    if (large && blobs <= 4096) blob.x = kNaN;
    frame.blobs.push_back(blob);
  }
  return frame;
}

Eigen::Vector3d marker_position(double t) {
  return {0.4 * std::cos(2.5 * t), 0.4 * std::sin(2.5 * t), 1.0 + 0.2 * std::sin(1.3 * t)};  // 1 m/s
}

TEST(Fuzz, ScreenAndTrackerSurviveGarbageAndStillTrackARealMarker) {
  Rng rng(4);
  Pipeline pipeline;
  TimeNs reference = kEpoch;
  TimeNs previous = kEpoch;
  std::uint64_t recent_too_late = 0;
  // A million blobs, once.
  {
    FeatureFrame huge;
    huge.camera_id = "cam0";
    huge.stamp_ns = reference;
    huge.blobs.assign(1'000'000, random_blob(rng, 1280, 1024));
    pipeline.feed(std::move(huge), reference);
  }
  for (int i = 0; i < 6000; ++i) {
    reference += kNsPerMillisecond;  // the "wall clock" of a live node
    FeatureFrame frame = garbage_frame(rng, reference, previous);
    // Duplicates and decreasing stamps follow the previous sane stamp (no overflow from INT64_MIN).
    if (frame.stamp_ns > 0 && frame.stamp_ns - reference < kNsPerSecond &&
        reference - frame.stamp_ns < kNsPerSecond)
      previous = frame.stamp_ns;
    const TimeNs stamp = frame.stamp_ns;
    const auto outcome = pipeline.feed(std::move(frame), reference);
    // A recent frame dropped as too late would mean an accepted stamp far in the future had made
    // the tracker drop the present.
    if (outcome == FrameOutcome::kTooLate && stamp >= reference - 100 * kNsPerMillisecond) ++recent_too_late;
  }
  pipeline.expect_counters_add_up();
  const auto& counts = pipeline.screen.counts();
  for (auto reason :
       {screen_reason::kBadCameraId, screen_reason::kNonPositiveStamp, screen_reason::kStampOutOfRange,
        screen_reason::kStampInFuture, screen_reason::kTooManyBlobs, screen_reason::kNonFiniteBlob,
        screen_reason::kNegativeArea, screen_reason::kBlobOutOfRange}) {
    EXPECT_GT(pipeline.screen.count(reason), 0u) << "the fuzzer never produced " << reason;
  }
  EXPECT_GT(pipeline.outcomes[FrameOutcome::kUnknownCamera], 0u);
  // Most accepted garbage is a few ms older than the newest frame: replayed, not dropped.
  EXPECT_GT(pipeline.outcomes[FrameOutcome::kProcessed] + pipeline.outcomes[FrameOutcome::kLateReplayed],
            2000u);
  EXPECT_EQ(recent_too_late, 0u);
  for (const auto& [reason, n] : counts)
    std::printf("  screen %-20s %llu\n", reason.c_str(), (unsigned long long)n);
  const auto& t = pipeline.tracker.stats();
  std::printf(
      "  tracker: %llu frames, %llu unknown camera, %llu late (replayed), %llu too late, %llu tracks "
      "created\n",
      (unsigned long long)t.frames, (unsigned long long)t.frames_unknown_camera,
      (unsigned long long)t.frames_late, (unsigned long long)t.frames_too_late,
      (unsigned long long)t.tracks_created);
  for (const auto& track : pipeline.tracker.current_tracks()) {
    EXPECT_TRUE(track.p.allFinite() && track.v.allFinite()) << "track " << track.id;
  }

  // Then a real marker: four cameras at 100 Hz (phases 0/2.5/5/7.5 ms), 0.1 px noise, 1.5 s,
  // starting 20 s after the garbage (whose accepted stamps reach at most 200 ms past it).
  std::vector<CameraModel> models;
  for (const auto& camera : pipeline.cameras) models.push_back(camera.model());
  std::normal_distribution<double> noise(0.0, 0.1);
  const TimeNs start = std::max(reference, pipeline.tracker.last_stamp_ns()) + 20 * kNsPerSecond;
  TimeNs last = start;
  for (int k = 0; k < 150; ++k) {
    for (std::size_t c = 0; c < models.size(); ++c) {
      const TimeNs t = k * 10'000'000LL + static_cast<TimeNs>(c) * 2'500'000LL;
      FeatureFrame frame;
      frame.camera_id = pipeline.cameras[c].id;
      frame.frame = k;
      frame.stamp_ns = start + t;
      const auto pixel = models[c].project(marker_position(ns_to_seconds(t)));
      ASSERT_TRUE(pixel && models[c].in_image(*pixel));
      Blob blob;
      blob.x = pixel->x() + noise(rng);
      blob.y = pixel->y() + noise(rng);
      blob.area = 12;
      frame.blobs.push_back(blob);
      last = frame.stamp_ns;
      const auto before = pipeline.outcomes[FrameOutcome::kProcessed];
      pipeline.feed(std::move(frame), last);
      EXPECT_EQ(pipeline.outcomes[FrameOutcome::kProcessed], before + 1) << "a good frame was not processed";
    }
  }
  pipeline.expect_counters_add_up();
  const auto tracks = pipeline.tracker.current_tracks();
  ASSERT_EQ(tracks.size(), 1u) << "the garbage left tracks behind, or the marker is not tracked";
  const double error = (tracks[0].p - marker_position(ns_to_seconds(last - start))).norm();
  std::printf("  after the garbage: one track, %.3f mm from the marker\n", error * 1e3);
  EXPECT_EQ(tracks[0].status, TrackStatus::kConfirmed);
  EXPECT_LT(error, 0.005);
}

}  // namespace
}  // namespace panoptes::estimator
