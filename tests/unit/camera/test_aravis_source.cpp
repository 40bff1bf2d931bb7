// SPDX-License-Identifier: Apache-2.0
// The aravis source against Aravis's in-process fake camera ("Fake_1"): real GenICam feature
// access and a real stream, no network. The GigE Vision and USB3 Vision interfaces are disabled
// before anything enumerates, so opening "Fake_1" sends no discovery broadcast.
#include <arv.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "panoptes/camera/sources.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

constexpr const char* kSpec = "aravis:Fake_1";

void use_only_the_fake_interface() {
  arv_disable_interface("GigEVision");
  arv_disable_interface("USB3Vision");
  arv_enable_interface("Fake");
}

SourceOptions small_roi_options() {
  SourceOptions options;
  // A small region keeps the fake's per-frame rendering cheap; the offsets exercise the ROI path.
  options.settings.roi_x = 8;
  options.settings.roi_y = 4;
  options.settings.roi_width = 64;
  options.settings.roi_height = 48;
  options.settings.frame_rate_hz = 50;
  options.settings.buffers = 4;
  return options;
}

std::unique_ptr<FrameSource> open_fake(const SourceOptions& options) {
  use_only_the_fake_interface();
  return open_source(kSpec, options);
}

std::string open_error(const SourceOptions& options) {
  try {
    open_fake(options);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

// The fake's diagonal ramp at gain 0 and the default 10 ms exposure: (x + y + frame id) % 255 in
// Mono8, 256 times that modulo 65535 in Mono16, with x, y relative to the region.
std::uint64_t device_frame_id(std::int64_t sequence) {
  return static_cast<std::uint64_t>((sequence - 1) % 65535 + 1);
}

TEST(AravisSource, DeliversMono8FramesOfTheRegionWithStamps) {
  auto source = open_fake(small_roi_options());
  EXPECT_EQ(source->info().backend, "aravis");
  EXPECT_EQ(source->info().width, 64);
  EXPECT_EQ(source->info().height, 48);
  EXPECT_EQ(source->info().bits, 8);
  EXPECT_NEAR(source->info().nominal_rate_hz, 50.0, 0.5);
  std::int64_t previous = -1;
  for (int i = 0; i < 5; ++i) {
    const auto frame = source->next();
    ASSERT_TRUE(frame.has_value());
    ASSERT_EQ(frame->image.width, 64);
    ASSERT_EQ(frame->image.height, 48);
    ASSERT_EQ(frame->image.bits, 8);
    const std::uint64_t id = device_frame_id(frame->sequence);
    for (int y = 0; y < 48; y += 7) {
      for (int x = 0; x < 64; x += 5) {
        ASSERT_EQ(frame->image.row8(y)[x], (x + y + id) % 255) << "pixel " << x << "," << y;
      }
    }
    EXPECT_GT(frame->sequence, previous);
    previous = frame->sequence;
    EXPECT_DOUBLE_EQ(frame->exposure_us, 10000.0);
    // The fake's clock is the wall clock: the stamp is within a frame or two of now.
    EXPECT_LT(std::abs(frame->stamp_ns - wall_now_ns()), 200 * kNsPerMillisecond);
    EXPECT_LT(std::abs(frame->arrival_ns - wall_now_ns()), 200 * kNsPerMillisecond);
  }
  const SourceCounters counters = source->counters();
  EXPECT_EQ(counters.count("incomplete"), 0u);
  EXPECT_EQ(counters.count("lost"), 0u);
}

TEST(AravisSource, DeliversMono16AsLittleEndianWords) {
  SourceOptions options = small_roi_options();
  options.settings.pixel_format = "Mono16";
  auto source = open_fake(options);
  EXPECT_EQ(source->info().bits, 16);
  const auto frame = source->next();
  ASSERT_TRUE(frame.has_value());
  ASSERT_EQ(frame->image.bits, 16);
  const std::uint64_t id = device_frame_id(frame->sequence);
  for (int y = 0; y < 48; y += 7) {
    for (int x = 0; x < 64; x += 5) {
      ASSERT_EQ(frame->image.row16(y)[x], (256 * (x + y + id)) % 65535) << "pixel " << x << "," << y;
    }
  }
}

TEST(AravisSource, RejectsFormatsAndRegionsItCannotUse) {
  SourceOptions options = small_roi_options();
  options.settings.pixel_format = "Mono12";
  std::string error = open_error(options);
  EXPECT_NE(error.find("aravis:Fake_1"), std::string::npos) << error;
  EXPECT_NE(error.find("Mono12 is not offered"), std::string::npos) << error;
  EXPECT_NE(error.find("Mono16"), std::string::npos) << "lists what the camera offers: " << error;

  options.settings.pixel_format = "Mono12Packed";
  error = open_error(options);
  EXPECT_NE(error.find("packed"), std::string::npos) << error;

  options = small_roi_options();
  options.settings.roi_x = 2000;
  options.settings.roi_width = 100;
  error = open_error(options);
  EXPECT_NE(error.find("roi [2000, 4, 100, 48]"), std::string::npos) << error;
  EXPECT_NE(error.find("2048x2048"), std::string::npos) << error;

  options = small_roi_options();
  options.settings.exposure_us = 5;
  error = open_error(options);
  EXPECT_NE(error.find("exposure 5 us is out of range [10, 10000000] us"), std::string::npos) << error;
}

TEST(AravisSource, ControlsCheckBoundsAndReadBack) {
  auto source = open_fake(small_roi_options());
  EXPECT_EQ(source->set_control(Control::kExposureUs, 5000), "");
  EXPECT_NEAR(source->control(Control::kExposureUs).value(), 5000, 1);
  const std::string too_short = source->set_control(Control::kExposureUs, 5);
  EXPECT_NE(too_short.find("out of range [10, 10000000]"), std::string::npos) << too_short;
  EXPECT_NEAR(source->control(Control::kExposureUs).value(), 5000, 1) << "a refused value changes nothing";

  EXPECT_EQ(source->set_control(Control::kGainDb, 3), "");
  EXPECT_NEAR(source->control(Control::kGainDb).value(), 3, 1e-9);
  const std::string too_much_gain = source->set_control(Control::kGainDb, 20);
  EXPECT_NE(too_much_gain.find("gain 20 is out of range [0, 10]"), std::string::npos) << too_much_gain;

  EXPECT_EQ(source->set_control(Control::kFrameRateHz, 40), "");
  EXPECT_NEAR(source->control(Control::kFrameRateHz).value(), 40, 0.1);
  const std::string too_fast = source->set_control(Control::kFrameRateHz, 5000);
  EXPECT_NE(too_fast.find("frame rate 5000 Hz is out of range"), std::string::npos) << too_fast;

  // Frames keep coming and carry the new exposure.
  const auto frame = source->next();
  ASSERT_TRUE(frame.has_value());
  EXPECT_NEAR(frame->exposure_us, 5000, 1);
}

TEST(AravisSource, CountsTimeoutsWithoutDroppingTheCamera) {
  SourceOptions options = small_roi_options();
  options.settings.frame_rate_hz = 4;  // 250 ms between frames
  options.settings.timeout_ms = 100;   // two timeouts per frame, never five in a row
  auto source = open_fake(options);
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(source->next().has_value());
  const SourceCounters counters = source->counters();
  EXPECT_GE(counters.count("timeout") ? counters.at("timeout") : 0u, 3u);
  EXPECT_EQ(counters.count("disconnect"), 0u);
}

TEST(AravisSource, RestartReopensTheCameraAndCarriesOn) {
  auto source = open_fake(small_roi_options());
  const auto before = source->next();
  ASSERT_TRUE(before.has_value());
  source->restart();
  const auto after = source->next();
  ASSERT_TRUE(after.has_value());
  EXPECT_GT(after->sequence, before->sequence);
  const SourceCounters counters = source->counters();
  EXPECT_EQ(counters.at("restart"), 1u);
  EXPECT_EQ(counters.at("reconnect"), 1u);
  EXPECT_EQ(source->set_control(Control::kGainDb, 2), "") << "controls work on the reopened camera";
}

TEST(AravisSource, StopEndsABlockedNext) {
  SourceOptions options = small_roi_options();
  options.settings.frame_rate_hz = 0.2;  // 5 s between frames
  options.settings.timeout_ms = 60000;
  auto source = open_fake(options);
  // The first frame may come at once; the next is seconds away.
  std::thread stopper([&source] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    source->stop();
  });
  const auto begin = std::chrono::steady_clock::now();
  int frames = 0;
  while (source->next().has_value()) ++frames;
  const auto waited = std::chrono::steady_clock::now() - begin;
  stopper.join();
  EXPECT_LE(frames, 1);
  // Generous bound: a next() that ignored stop() would block until the 5 s frame.
  EXPECT_LT(waited, std::chrono::milliseconds(2000));
}

TEST(AravisSource, StopsAfterMaxFrames) {
  SourceOptions options = small_roi_options();
  options.max_frames = 2;
  auto source = open_fake(options);
  EXPECT_TRUE(source->next().has_value());
  EXPECT_TRUE(source->next().has_value());
  EXPECT_FALSE(source->next().has_value());
}

}  // namespace
}  // namespace panoptes::camera
