// SPDX-License-Identifier: Apache-2.0
// features:<file.jsonl> replay: pacing, re-stamping, camera selection, malformed lines, stop().
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <future>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "panoptes/camera/sources.h"
#include "panoptes/jsonl.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

namespace fs = std::filesystem;

constexpr TimeNs kRecordedStart = 1'700'000'000'000'000'000;  // a 2023 wall time
constexpr auto kGenerousWait = std::chrono::seconds(10);

class TempFile {
 public:
  TempFile() {
    std::random_device random;
    path_ = fs::temp_directory_path() / ("panoptes_features_test_" + std::to_string(random()) + ".jsonl");
  }
  ~TempFile() {
    std::error_code ignored;
    fs::remove(path_, ignored);
  }
  const fs::path& path() const { return path_; }
  std::string spec() const { return "features:" + path_.string(); }

 private:
  fs::path path_;
};

FeatureFrame make_frame(const std::string& camera_id, std::int64_t number, TimeNs stamp_ns) {
  FeatureFrame frame;
  frame.camera_id = camera_id;
  frame.frame = number;
  frame.stamp_ns = stamp_ns;
  frame.arrival_ns = stamp_ns + 3 * kNsPerMillisecond;
  for (int i = 0; i <= number % 3; ++i) {
    Blob blob;
    blob.x = 10.25 * (i + 1) + static_cast<double>(number);
    blob.y = 20.5 + i;
    blob.area = 7 + i;
    blob.sum = 1234.5 * (i + 1);
    blob.peak = 200 + i;
    blob.m20 = 1.5;
    blob.m11 = -0.25;
    blob.m02 = 2.0;
    frame.blobs.push_back(blob);
  }
  return frame;
}

// `count` frames of one camera, `spacing_ns` apart, numbered from 100.
std::vector<FeatureFrame> make_frames(const std::string& camera_id, int count, TimeNs spacing_ns) {
  std::vector<FeatureFrame> frames;
  frames.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k)
    frames.push_back(make_frame(camera_id, 100 + k, kRecordedStart + k * spacing_ns));
  return frames;
}

void write_frames(const fs::path& path, const std::vector<FeatureFrame>& frames) {
  JsonlWriter out(path);
  for (const FeatureFrame& frame : frames) out.write(frame);
  out.flush();
}

std::string open_error(const std::string& spec, const SourceOptions& options = {}) {
  try {
    open_source(spec, options);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "no error";
}

SourceOptions unpaced() {
  SourceOptions options;
  options.paced = false;
  return options;
}

TEST(FeaturesSource, UnpacedReplayKeepsOrderContentAndSpacing) {
  TempFile file;
  const auto recorded = make_frames("cam3", 5, 40 * kNsPerMillisecond);
  write_frames(file.path(), recorded);
  const TimeNs before = wall_now_ns();
  auto source = open_source(file.spec(), unpaced());
  EXPECT_EQ(source->info().backend, "features");
  EXPECT_EQ(source->info().camera_id, "cam3");
  EXPECT_EQ(source->info().width, 0);
  EXPECT_EQ(source->info().height, 0);
  EXPECT_NEAR(source->info().nominal_rate_hz, 25.0, 1e-9);

  std::vector<CapturedFrame> replayed;
  while (auto frame = source->next()) replayed.push_back(std::move(*frame));
  ASSERT_EQ(replayed.size(), recorded.size());
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    const CapturedFrame& frame = replayed[k];
    EXPECT_EQ(frame.sequence, recorded[k].frame);
    EXPECT_EQ(frame.image.width, 0);
    EXPECT_EQ(frame.image.height, 0);
    EXPECT_TRUE(frame.image.data.empty());
    ASSERT_TRUE(frame.blobs);
    ASSERT_EQ(frame.blobs->size(), recorded[k].blobs.size());
    for (std::size_t i = 0; i < frame.blobs->size(); ++i) {
      const Blob& got = (*frame.blobs)[i];
      const Blob& want = recorded[k].blobs[i];
      EXPECT_DOUBLE_EQ(got.x, want.x);
      EXPECT_DOUBLE_EQ(got.y, want.y);
      EXPECT_DOUBLE_EQ(got.area, want.area);
      EXPECT_DOUBLE_EQ(got.sum, want.sum);
      EXPECT_EQ(got.peak, want.peak);
      EXPECT_DOUBLE_EQ(got.m20, want.m20);
      EXPECT_DOUBLE_EQ(got.m11, want.m11);
      EXPECT_DOUBLE_EQ(got.m02, want.m02);
    }
    // Re-stamped onto now, recorded spacing kept exactly.
    EXPECT_EQ(frame.stamp_ns - replayed.front().stamp_ns, recorded[k].stamp_ns - recorded.front().stamp_ns);
  }
  EXPECT_GE(replayed.front().stamp_ns, before);
  EXPECT_LE(replayed.front().stamp_ns, wall_now_ns());
  EXPECT_EQ(source->counters().count("malformed"), 0u);
}

TEST(FeaturesSource, UnpacedReplayDoesNotWaitForRecordedTime) {
  TempFile file;
  write_frames(file.path(), make_frames("cam0", 2, 3600 * kNsPerSecond));  // an hour apart
  auto source = open_source(file.spec(), unpaced());
  auto pending = std::async(std::launch::async, [&] {
    int frames = 0;
    while (source->next()) ++frames;
    return frames;
  });
  ASSERT_EQ(pending.wait_for(kGenerousWait), std::future_status::ready);
  EXPECT_EQ(pending.get(), 2);
}

// Replays 6 frames 50 ms apart at `rate_scale`; returns the frames.
std::vector<CapturedFrame> replay_paced(double rate_scale, TimeNs* elapsed_ns) {
  TempFile file;
  write_frames(file.path(), make_frames("cam0", 6, 50 * kNsPerMillisecond));
  SourceOptions options;
  options.rate_scale = rate_scale;
  auto source = open_source(file.spec(), options);
  std::vector<CapturedFrame> frames;
  const TimeNs start = wall_now_ns();
  while (auto frame = source->next()) frames.push_back(std::move(*frame));
  *elapsed_ns = wall_now_ns() - start;
  return frames;
}

TEST(FeaturesSource, PacedReplayFollowsTheRecordedPace) {
  TimeNs elapsed = 0;
  const auto frames = replay_paced(1.0, &elapsed);
  ASSERT_EQ(frames.size(), 6u);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    EXPECT_EQ(frames[k].stamp_ns - frames.front().stamp_ns, static_cast<TimeNs>(k) * 50 * kNsPerMillisecond);
    // Never delivered before its (re-stamped) time.
    EXPECT_GE(frames[k].arrival_ns, frames[k].stamp_ns) << k;
  }
  EXPECT_GE(elapsed, 250 * kNsPerMillisecond);
}

TEST(FeaturesSource, RateScaleDividesTheSpacing) {
  TimeNs elapsed = 0;
  const auto frames = replay_paced(4.0, &elapsed);
  ASSERT_EQ(frames.size(), 6u);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    EXPECT_EQ(frames[k].stamp_ns - frames.front().stamp_ns, static_cast<TimeNs>(k) * 12'500'000) << k;
    EXPECT_GE(frames[k].arrival_ns, frames[k].stamp_ns) << k;
  }
  EXPECT_GE(elapsed, 62 * kNsPerMillisecond);
}

TEST(FeaturesSource, RateScaleMustBePositive) {
  TempFile file;
  write_frames(file.path(), make_frames("cam0", 2, kNsPerSecond));
  SourceOptions options;
  options.rate_scale = 0;
  const std::string error = open_error(file.spec(), options);
  EXPECT_NE(error.find(file.spec() + ": rate scale must be a positive number"), std::string::npos) << error;
}

std::vector<FeatureFrame> two_cameras() {
  std::vector<FeatureFrame> frames;
  for (int k = 0; k < 4; ++k) {
    frames.push_back(make_frame("cam0", k, kRecordedStart + k * (10 * kNsPerMillisecond)));
    frames.push_back(make_frame("cam1", 50 + k, kRecordedStart + k * (10 * kNsPerMillisecond) + 1000));
  }
  return frames;
}

TEST(FeaturesSource, CameraIdSelectsOneCamerasFrames) {
  TempFile file;
  write_frames(file.path(), two_cameras());
  SourceOptions options = unpaced();
  options.camera_id = "cam1";
  auto source = open_source(file.spec(), options);
  EXPECT_EQ(source->info().camera_id, "cam1");
  std::vector<std::int64_t> sequences;
  while (auto frame = source->next()) sequences.push_back(frame->sequence);
  EXPECT_EQ(sequences, (std::vector<std::int64_t>{50, 51, 52, 53}));
}

TEST(FeaturesSource, SeveralCamerasWithoutCameraIdIsAnError) {
  TempFile file;
  write_frames(file.path(), two_cameras());
  EXPECT_EQ(
      open_error(file.spec()),
      file.spec() + ": the file holds frames of several cameras (cam0, cam1); choose one with --camera-id");
  SourceOptions options;
  options.camera_id = "cam7";
  EXPECT_EQ(open_error(file.spec(), options),
            file.spec() + ": no frames of camera 'cam7' (the file has: cam0, cam1)");
}

TEST(FeaturesSource, MalformedLinesAreCountedAndSkipped) {
  TempFile file;
  {
    std::ofstream out(file.path());
    out << to_json_line(make_frame("cam0", 1, kRecordedStart)) << "\n";
    out << "{not json\n";
    out << "\n";  // blank lines are not records
    out << R"({"camera_id": "cam0", "stamp_ns": 5})"
        << "\n";  // no frame number
    out << to_json_line(make_frame("cam0", 2, kRecordedStart + kNsPerMillisecond)) << "\n";
  }
  auto source = open_source(file.spec(), unpaced());
  EXPECT_EQ(source->counters().at("malformed"), 2u);
  const std::string error = source->last_error();
  EXPECT_EQ(error.rfind(file.path().string() + ":2: ", 0), 0u) << error;
  EXPECT_NE(error.find("(and 1 more malformed lines)"), std::string::npos) << error;
  std::vector<std::int64_t> sequences;
  while (auto frame = source->next()) sequences.push_back(frame->sequence);
  EXPECT_EQ(sequences, (std::vector<std::int64_t>{1, 2}));
}

TEST(FeaturesSource, RecordedImageSizeIsReported) {
  TempFile file;
  {
    std::ofstream out(file.path());
    out << R"({"camera_id": "cam0", "frame": 0, "stamp_ns": 1700000000000000000, "width": 1280, "height": 1024,)"
        << R"( "blobs": []})"
        << "\n";
  }
  auto source = open_source(file.spec(), unpaced());
  EXPECT_EQ(source->info().width, 1280);
  EXPECT_EQ(source->info().height, 1024);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  ASSERT_TRUE(frame->blobs);
  EXPECT_TRUE(frame->blobs->empty());
}

TEST(FeaturesSource, MissingOrEmptyFilesAreErrorsNamingTheFile) {
  TempFile file;
  EXPECT_EQ(open_error(file.spec()), file.spec() + ": no such file");
  { std::ofstream out(file.path()); }
  EXPECT_EQ(open_error(file.spec()), file.spec() + ": no feature frames in the file");
  {
    std::ofstream out(file.path());
    out << "garbage\n";
  }
  const std::string error = open_error(file.spec());
  EXPECT_EQ(error.rfind(file.spec() + ": no feature frames in the file (1 malformed lines, first: " +
                            file.path().string() + ":1: ",
                        0),
            0u)
      << error;
}

TEST(FeaturesSource, MaxFramesEndsTheReplay) {
  TempFile file;
  write_frames(file.path(), make_frames("cam0", 5, kNsPerMillisecond));
  SourceOptions options = unpaced();
  options.max_frames = 3;
  auto source = open_source(file.spec(), options);
  int frames = 0;
  while (source->next()) ++frames;
  EXPECT_EQ(frames, 3);
}

TEST(FeaturesSource, StopUnblocksAPacedWait) {
  TempFile file;
  write_frames(file.path(), make_frames("cam0", 2, 3600 * kNsPerSecond));
  auto source = open_source(file.spec(), {});
  ASSERT_TRUE(source->next());  // the first frame is due at once
  auto pending = std::async(std::launch::async, [&] { return source->next(); });  // due in an hour
  EXPECT_EQ(pending.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);
  source->stop();
  ASSERT_EQ(pending.wait_for(kGenerousWait), std::future_status::ready);
  EXPECT_FALSE(pending.get());
}

TEST(FeaturesSource, RestartRewinds) {
  TempFile file;
  write_frames(file.path(), make_frames("cam0", 2, kNsPerMillisecond));
  auto source = open_source(file.spec(), unpaced());
  ASSERT_TRUE(source->next());
  ASSERT_TRUE(source->next());
  EXPECT_FALSE(source->next());
  source->restart();
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->sequence, 100);
}

// --sim-epoch-file: the replay waits for the file, then its frames are stamped from the epoch it
// holds (the recording's epoch, its first stamp rounded down to a second, maps to it).
TEST(FeaturesSource, EpochFileGatesTheReplayAndAnchorsItsStamps) {
  TempFile file;
  TempFile epoch_file;
  write_frames(file.path(), make_frames("cam0", 3, 10 * kNsPerMillisecond));
  SourceOptions options = unpaced();
  options.sim_epoch_file = epoch_file.path().string();
  auto source = open_source(file.spec(), options);
  auto first = std::async(std::launch::async, [&] { return source->next(); });
  EXPECT_EQ(first.wait_for(std::chrono::milliseconds(100)), std::future_status::timeout);  // no file yet
  const TimeNs epoch_ns = 1'800'000'000'123'456'789;
  std::ofstream(epoch_file.path()) << epoch_ns << "\n";
  ASSERT_EQ(first.wait_for(kGenerousWait), std::future_status::ready);
  const auto frame = first.get();
  ASSERT_TRUE(frame);
  const TimeNs recorded_epoch = kRecordedStart / kNsPerSecond * kNsPerSecond;
  EXPECT_EQ(frame->stamp_ns, epoch_ns + (kRecordedStart - recorded_epoch));
  const auto second = source->next();
  ASSERT_TRUE(second);
  EXPECT_EQ(second->stamp_ns - frame->stamp_ns, 10 * kNsPerMillisecond);
}

TEST(FeaturesSource, EpochFileWaitEndsOnStopAndABadFileIsNamed) {
  TempFile file;
  TempFile epoch_file;
  write_frames(file.path(), make_frames("cam0", 2, kNsPerMillisecond));
  SourceOptions options = unpaced();
  options.sim_epoch_file = epoch_file.path().string();
  auto waiting = open_source(file.spec(), options);
  auto pending = std::async(std::launch::async, [&] { return waiting->next(); });
  EXPECT_EQ(pending.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);
  waiting->stop();
  ASSERT_EQ(pending.wait_for(kGenerousWait), std::future_status::ready);
  EXPECT_FALSE(pending.get());

  std::ofstream(epoch_file.path()) << "soon\n";
  auto bad = open_source(file.spec(), options);
  try {
    bad->next();
    ADD_FAILURE() << "a file holding 'soon' was taken as an epoch";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(epoch_file.path().string()), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("'soon'"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace panoptes::camera
