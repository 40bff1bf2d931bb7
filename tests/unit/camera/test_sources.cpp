// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "panoptes/camera/detector.h"
#include "panoptes/camera/sources.h"
#include "panoptes/image_file_cv.h"
#include "panoptes/simulator.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    std::random_device random;
    path_ = fs::temp_directory_path() / ("panoptes_camera_test_" + std::to_string(random()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Binary PGM written by hand so the test does not depend on the reader's own library.
void write_pgm(const fs::path& path, int width, int height, int maxval, const std::vector<int>& values) {
  std::ofstream out(path, std::ios::binary);
  out << "P5\n# written by test_sources\n" << width << " " << height << "\n" << maxval << "\n";
  for (const int value : values) {
    if (maxval > 255) out.put(static_cast<char>(value >> 8));
    out.put(static_cast<char>(value & 0xff));
  }
}

std::string error_of(const std::string& spec, const SourceOptions& options = {}) {
  try {
    open_source(spec, options);
  } catch (const std::exception& error) {
    return error.what();
  }
  return "no error";
}

int pixel(const Image& image, int x, int y) {
  return image.bytes_per_pixel() == 1 ? image.row8(y)[x] : image.row16(y)[x];
}

TEST(ImageSource, ReadsADirectoryInNameOrder) {
  TempDir dir;
  // Written out of order; the 16-bit file is 12-bit data (maxval 4095).
  write_pgm(dir.path() / "frame_002.pgm", 3, 2, 255, {2, 0, 0, 0, 0, 200});
  write_pgm(dir.path() / "frame_000.pgm", 3, 2, 255, {0, 0, 0, 0, 0, 100});
  write_pgm(dir.path() / "frame_001.pgm", 3, 2, 4095, {1, 0, 0, 0, 0, 4000});
  std::ofstream(dir.path() / "notes.txt") << "not an image\n";

  auto source = open_source("images:" + dir.path().string(), {});
  EXPECT_EQ(source->info().camera_id, "images");
  EXPECT_EQ(source->info().backend, "images");
  EXPECT_EQ(source->info().width, 3);
  EXPECT_EQ(source->info().height, 2);

  const int expected_bits[] = {8, 12, 8};
  const int expected_last_pixel[] = {100, 4000, 200};
  for (int i = 0; i < 3; ++i) {
    const std::optional<CapturedFrame> frame = source->next();
    ASSERT_TRUE(frame.has_value()) << i;
    EXPECT_EQ(frame->sequence, i);
    EXPECT_EQ(frame->stamp_ns, 0);
    EXPECT_EQ(frame->image.width, 3);
    EXPECT_EQ(frame->image.height, 2);
    EXPECT_EQ(frame->image.bits, expected_bits[i]);
    EXPECT_EQ(pixel(frame->image, 0, 0), i);
    EXPECT_EQ(pixel(frame->image, 2, 1), expected_last_pixel[i]);
  }
  EXPECT_FALSE(source->next().has_value());
}

TEST(ImageSource, GlobMaxFramesAndCameraId) {
  TempDir dir;
  for (int i = 0; i < 5; ++i) {
    write_pgm(dir.path() / ("f" + std::to_string(i) + ".pgm"), 2, 2, 255, {i, 0, 0, 0});
  }
  auto globbed = open_source("images:" + (dir.path() / "f[13].pgm").string(), {});
  EXPECT_EQ(pixel(globbed->next()->image, 0, 0), 1);
  EXPECT_EQ(pixel(globbed->next()->image, 0, 0), 3);
  EXPECT_FALSE(globbed->next().has_value());

  SourceOptions options;
  options.camera_id = "bench";
  options.max_frames = 2;
  auto limited = open_source("images:" + (dir.path() / "*.pgm").string(), options);
  EXPECT_EQ(limited->info().camera_id, "bench");
  EXPECT_TRUE(limited->next().has_value());
  EXPECT_TRUE(limited->next().has_value());
  EXPECT_FALSE(limited->next().has_value());
}

TEST(ImageSource, ReadsSixteenBitAndColourPng) {
  TempDir dir;
  cv::Mat deep(4, 5, CV_16UC1, cv::Scalar(0));
  deep.at<std::uint16_t>(2, 3) = 50000;
  write_png(dir.path() / "a_deep.png", view_of(deep));
  cv::Mat colour(4, 5, CV_8UC3, cv::Scalar(0, 0, 0));
  colour.at<cv::Vec3b>(1, 1) = cv::Vec3b(200, 200, 200);  // grey in any colour conversion
  write_png(dir.path() / "b_colour.png", view_of(colour));

  auto source = open_source("images:" + dir.path().string(), {});
  const std::optional<CapturedFrame> first = source->next();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->image.bits, 16);
  EXPECT_EQ(pixel(first->image, 3, 2), 50000);
  const std::optional<CapturedFrame> second = source->next();
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(second->image.bits, 8);
  EXPECT_EQ(second->image.data.size(), 20u);
  EXPECT_EQ(pixel(second->image, 1, 1), 200);
}

TEST(ImageSource, ErrorsNameTheSpecOrFile) {
  const std::string missing = (fs::temp_directory_path() / "panoptes_no_such_dir_4711").string();
  const std::string missing_error = error_of("images:" + missing);
  EXPECT_NE(missing_error.find("no such directory"), std::string::npos) << missing_error;
  EXPECT_NE(missing_error.find(missing), std::string::npos) << missing_error;

  TempDir dir;
  const std::string empty_error = error_of("images:" + dir.path().string());
  EXPECT_NE(empty_error.find("no PGM/PNG files match"), std::string::npos) << empty_error;
  EXPECT_NE(error_of("images:" + (dir.path() / "*.pgm").string()).find("no PGM/PNG files match"),
            std::string::npos);

  write_pgm(dir.path() / "a.pgm", 2, 2, 255, {0, 0, 0, 0});
  std::ofstream(dir.path() / "b.pgm") << "P5\n2 2\n255\n";  // truncated: no pixel data
  // A broken file in the stream is counted and skipped, and named in last_error().
  auto source = open_source("images:" + dir.path().string(), {});
  EXPECT_TRUE(source->next().has_value());
  EXPECT_FALSE(source->next().has_value());
  EXPECT_EQ(source->counters().at("unreadable"), 1u);
  EXPECT_NE(source->last_error().find("b.pgm"), std::string::npos) << source->last_error();

  // A broken first file is skipped too; when no file can be read the source cannot start.
  fs::rename(dir.path() / "b.pgm", dir.path() / "0.pgm");
  auto skipping = open_source("images:" + dir.path().string(), {});
  EXPECT_EQ(skipping->counters().at("unreadable"), 1u);
  EXPECT_TRUE(skipping->next().has_value());
  fs::remove(dir.path() / "a.pgm");
  const std::string none_error = error_of("images:" + dir.path().string());
  EXPECT_NE(none_error.find("none of the 1 files can be read"), std::string::npos) << none_error;
  EXPECT_NE(none_error.find("0.pgm"), std::string::npos) << none_error;

  EXPECT_NE(error_of("camera:xyz").find("unknown source"), std::string::npos);
}

// --- simulator source -------------------------------------------------------------------------

const std::string kDemoScene = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml";

TEST(SimSource, FramesMatchTheSimulatorsFeatures) {
  const Scene scene = Scene::load(kDemoScene);
  ASSERT_FALSE(scene.cameras().empty());
  const std::string camera_id = scene.cameras().front().calibration.id;
  const CameraSimulator simulator(scene, camera_id);

  SourceOptions options;
  options.paced = false;
  options.sim_epoch_ns = 1'700'000'000 * kNsPerSecond;
  options.max_frames = 10;
  auto source = open_source("sim:" + kDemoScene + "#" + camera_id, options);
  const SourceInfo& info = source->info();
  EXPECT_EQ(info.camera_id, camera_id);
  EXPECT_EQ(info.backend, "sim");
  EXPECT_EQ(info.model, "panoptes-sim");
  EXPECT_EQ(info.width, simulator.config().calibration.intrinsics.width);
  EXPECT_EQ(info.height, simulator.config().calibration.intrinsics.height);
  EXPECT_EQ(info.nominal_rate_hz, simulator.config().rate_hz);
  ASSERT_TRUE(info.calibration.has_value());
  EXPECT_EQ(info.calibration->intrinsics.fx, simulator.config().calibration.intrinsics.fx);

  Detector detector;
  int frames = 0, compared = 0;
  double worst = 0;
  while (const std::optional<CapturedFrame> frame = source->next()) {
    EXPECT_EQ(frame->sequence, frames);
    EXPECT_EQ(frame->stamp_ns, options.sim_epoch_ns + simulator.frame_stamp_ns(frames));
    EXPECT_EQ(frame->image.width, info.width);
    const std::vector<Blob> blobs = detector.detect(frame->image);
    const FeatureFrame truth = simulator.features(frames);
    for (std::size_t i = 0; i < truth.blobs.size(); ++i) {
      const Blob& feature = truth.blobs[i];
      // Spots that overlap another or the border are not expected to give clean centroids.
      bool isolated =
          feature.x > 8 && feature.y > 8 && feature.x < info.width - 9 && feature.y < info.height - 9;
      for (std::size_t j = 0; j < truth.blobs.size(); ++j) {
        if (j != i && std::hypot(truth.blobs[j].x - feature.x, truth.blobs[j].y - feature.y) < 12)
          isolated = false;
      }
      if (!isolated) continue;
      double nearest = 1e9;
      for (const Blob& blob : blobs)
        nearest = std::min(nearest, std::hypot(blob.x - feature.x, blob.y - feature.y));
      EXPECT_LT(nearest, 0.3) << "frame " << frames << " feature (" << feature.x << ", " << feature.y << ")";
      worst = std::max(worst, nearest);
      ++compared;
    }
    ++frames;
  }
  EXPECT_EQ(frames, 10);
  EXPECT_GT(compared, 0);
  std::printf("[ sim      ] %d isolated features in 10 frames of %s: worst detector error %.4f px\n",
              compared, camera_id.c_str(), worst);
}

// Issue 32: the source delivered a frame at exactly t = duration (1201 frames of a 20 s scene at
// 60 Hz), one more than panoptes_sim features writes; mid-exposure lies in [0, duration).
TEST(SimSource, DeliversTheFramesOfZeroToDurationLikeTheSimulator) {
  TempDir dir;
  std::ifstream in(kDemoScene);
  std::stringstream text;
  text << in.rdbuf();
  const fs::path path = dir.path() / "half_second.yaml";
  std::ofstream(path) << std::regex_replace(text.str(), std::regex("\nduration: [0-9.]+"), "\nduration: 0.5");
  const Scene scene = Scene::load(path.string());
  ASSERT_EQ(scene.duration_ns(), kNsPerSecond / 2);
  SourceOptions options;
  options.paced = false;
  for (const std::string camera_id : {"cam0", "cam3"}) {
    const CameraSimulator simulator(scene, camera_id);
    const CameraSimulator::FrameRange range = simulator.frames_in(0, scene.duration_ns());
    auto source = open_source("sim:" + path.string() + "#" + camera_id, options);
    std::int64_t frames = 0;
    while (const std::optional<CapturedFrame> frame = source->next()) {
      EXPECT_EQ(frame->sequence, range.first + frames);
      EXPECT_LT(simulator.frame_time_ns(frame->sequence), scene.duration_ns());
      ++frames;
    }
    EXPECT_EQ(frames, range.end - range.first) << camera_id;
  }
  // By hand: cam0 is 60 Hz from t = 0 (frames 0..29; frame 30 is at 0.5 s), cam3 120 Hz from
  // 6.7 ms (0.0067 + 59/120 = 0.4984 s is the last).
  EXPECT_EQ(CameraSimulator(scene, "cam0").frames_in(0, scene.duration_ns()).end, 30);
  EXPECT_EQ(CameraSimulator(scene, "cam3").frames_in(0, scene.duration_ns()).end, 60);
  EXPECT_EQ(CameraSimulator(scene, "cam3").frames_in(kNsPerSecond / 4, scene.duration_ns()).first, 30);
}

TEST(SimSource, BadSpecsNameWhatIsWrong) {
  const std::string no_camera = error_of("sim:" + kDemoScene);
  EXPECT_NE(no_camera.find("#<camera id>"), std::string::npos) << no_camera;
  const std::string unknown = error_of("sim:" + kDemoScene + "#no_such_camera");
  EXPECT_NE(unknown.find("no_such_camera"), std::string::npos) << unknown;
  EXPECT_THROW(open_source("sim:/nonexistent/scene.yaml#cam0", {}), std::runtime_error);
}

TEST(SimSource, PacedSourceStartsAtTheNextFrameWhenStartedLate) {
  const Scene scene = Scene::load(kDemoScene);
  const std::string camera_id = scene.cameras().front().calibration.id;
  const CameraSimulator simulator(scene, camera_id);
  ASSERT_GT(scene.duration_ns(), 3 * kNsPerSecond);

  SourceOptions options;
  options.sim_epoch_ns = wall_now_ns() - 3 * kNsPerSecond / 2;
  options.max_frames = 2;
  auto source = open_source("sim:" + kDemoScene + "#" + camera_id, options);
  const auto readout = [&](std::int64_t k) {
    return options.sim_epoch_ns + simulator.frame_time_ns(k) + simulator.config().exposure_ns / 2;
  };
  const TimeNs called = wall_now_ns();
  const std::optional<CapturedFrame> first = source->next();
  ASSERT_TRUE(first.has_value());
  const std::int64_t k = first->sequence;
  EXPECT_GT(k, 0);
  EXPECT_LE(readout(k - 1), called) << "frame " << k - 1 << " was already read out and should be first";
  EXPECT_GE(first->arrival_ns, readout(k));
  EXPECT_EQ(first->stamp_ns, options.sim_epoch_ns + simulator.frame_stamp_ns(k));
  const std::optional<CapturedFrame> second = source->next();
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(second->sequence, k + 1);
  EXPECT_GE(second->arrival_ns, readout(k + 1));
  EXPECT_FALSE(source->next().has_value());
}

TEST(SimSource, StopWakesASleepingNext) {
  const Scene scene = Scene::load(kDemoScene);
  const std::string camera_id = scene.cameras().front().calibration.id;
  SourceOptions options;
  options.sim_epoch_ns = wall_now_ns() + 30 * kNsPerSecond;  // first frame far in the future
  auto source = open_source("sim:" + kDemoScene + "#" + camera_id, options);

  std::optional<CapturedFrame> result;
  TimeNs returned_ns = 0;
  std::thread reader([&] {
    result = source->next();
    returned_ns = monotonic_now_ns();
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const TimeNs stopped_ns = monotonic_now_ns();
  source->stop();
  reader.join();
  EXPECT_FALSE(result.has_value());
  EXPECT_LT(returned_ns - stopped_ns, kNsPerSecond);  // "promptly": a generous bound, not a speed test
}

}  // namespace
}  // namespace panoptes::camera
