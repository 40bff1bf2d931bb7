// SPDX-License-Identifier: Apache-2.0
// The v4l2 backend against an in-memory device (fake_v4l2_device.h) and, for the missing-device
// error, against the real device implementation.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "fake_v4l2_device.h"
#include "panoptes/camera/sources.h"
#include "panoptes/time.h"
#include "v4l2_device.h"
#include "v4l2_source.h"

namespace panoptes::camera {
namespace {

using testing::FakeFault;
using testing::FakeFormat;
using testing::FakeV4l2Camera;

constexpr auto kGenerousWait = std::chrono::seconds(10);  // bounds a wait that should end at once

std::shared_ptr<FakeV4l2Camera> make_camera(FakeV4l2Camera::Config config = {}) {
  return std::make_shared<FakeV4l2Camera>(std::move(config));
}

FakeV4l2Camera::Config with_formats(std::vector<FakeFormat> formats) {
  FakeV4l2Camera::Config config;
  config.formats = std::move(formats);
  return config;
}

std::unique_ptr<FrameSource> open_fake(const std::shared_ptr<FakeV4l2Camera>& camera,
                                       const SourceOptions& options = {}) {
  return make_v4l2_source("/dev/video0", camera->factory(), options);
}

std::string open_error(const std::shared_ptr<FakeV4l2Camera>& camera, const SourceOptions& options = {}) {
  try {
    open_fake(camera, options);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "no error";
}

int pixel(const Image& image, int x, int y) {
  return image.bytes_per_pixel() == 1 ? image.row8(y)[x] : image.row16(y)[x];
}

// Every pixel equals the camera's pattern for the frame's V4L2 sequence (equal to the delivered
// sequence in a stream without reconnections).
void expect_pattern(const CapturedFrame& frame, int bits) {
  const Image& image = frame.image;
  ASSERT_EQ(image.bits, bits);
  int mismatches = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const int expected = FakeV4l2Camera::pixel(x, y, static_cast<std::uint32_t>(frame.sequence), bits,
                                                 image.width, image.height);
      if (pixel(image, x, y) != expected && ++mismatches <= 3) {
        ADD_FAILURE() << "pixel (" << x << ", " << y << ") = " << pixel(image, x, y) << ", expected "
                      << expected;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(V4l2Source, GreyFramesRespectRowPadding) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_GREY, 64, 48, 7}}));
  auto source = open_fake(camera);
  EXPECT_EQ(source->info().backend, "v4l2");
  EXPECT_EQ(source->info().camera_id, "video0");
  EXPECT_EQ(source->info().model, "Fake V4L2 camera");
  EXPECT_EQ(source->info().serial, "platform:fake-0");
  EXPECT_EQ(source->info().width, 64);
  EXPECT_EQ(source->info().height, 48);
  EXPECT_EQ(source->info().bits, 8);
  EXPECT_DOUBLE_EQ(source->info().nominal_rate_hz, 30);
  for (int k = 0; k < 3; ++k) {
    const auto frame = source->next();
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->sequence, k);
    EXPECT_FALSE(frame->blobs);
    ASSERT_EQ(frame->image.width, 64);
    ASSERT_EQ(frame->image.height, 48);
    expect_pattern(*frame, 8);
  }
}

TEST(V4l2Source, Y16FramesAreLittleEndianSixteenBit) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_Y16, 40, 30, 6}}));
  auto source = open_fake(camera);
  EXPECT_EQ(source->info().bits, 16);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  expect_pattern(*frame, 16);
  // The spots use the high byte: a byte-order mistake cannot pass.
  EXPECT_EQ(pixel(frame->image, 20, 15), 60000);
}

TEST(V4l2Source, YuyvFramesKeepTheLumaChannel) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_YUYV, 32, 24, 4}}));
  auto source = open_fake(camera);
  EXPECT_EQ(source->info().bits, 8);
  for (int k = 0; k < 2; ++k) {
    const auto frame = source->next();
    ASSERT_TRUE(frame);
    expect_pattern(*frame, 8);
  }
}

TEST(V4l2Source, MjpgFramesAreDecodedToGrey) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_MJPEG, 64, 48, 0}}));
  auto source = open_fake(camera);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  ASSERT_EQ(frame->image.width, 64);
  ASSERT_EQ(frame->image.height, 48);
  ASSERT_EQ(frame->image.bits, 8);
  // JPEG is lossy: spots stay bright and the background stays dark.
  for (const auto& [x, y] : {std::pair{16, 12}, std::pair{32, 24}, std::pair{48, 16}}) {
    EXPECT_GT(pixel(frame->image, x, y), 200) << x << ", " << y;
  }
  EXPECT_LT(pixel(frame->image, 5, 40), 100);
  EXPECT_LT(pixel(frame->image, 60, 2), 100);
}

TEST(V4l2Source, PrefersGreyThenY16ThenYuyvThenMjpg) {
  const FakeFormat grey{V4L2_PIX_FMT_GREY, 32, 24, 0};
  const FakeFormat y16{V4L2_PIX_FMT_Y16, 32, 24, 0};
  const FakeFormat yuyv{V4L2_PIX_FMT_YUYV, 32, 24, 0};
  const FakeFormat mjpg{V4L2_PIX_FMT_MJPEG, 32, 24, 0};
  const FakeFormat h264{V4L2_PIX_FMT_H264, 32, 24, 0};
  struct Case {
    std::vector<FakeFormat> offered;
    std::uint32_t chosen;
  };
  const Case cases[] = {
      {{mjpg, yuyv, y16, grey}, V4L2_PIX_FMT_GREY},
      {{mjpg, yuyv, y16}, V4L2_PIX_FMT_Y16},
      {{h264, mjpg, yuyv}, V4L2_PIX_FMT_YUYV},
      {{h264, mjpg}, V4L2_PIX_FMT_MJPEG},
  };
  for (const Case& test : cases) {
    auto camera = make_camera(with_formats(test.offered));
    auto source = open_fake(camera);
    EXPECT_EQ(camera->current_fourcc(), test.chosen) << fourcc_to_string(test.chosen);
    EXPECT_TRUE(source->next());
  }
}

TEST(V4l2Source, HonoursTheRequestedPixelFormat) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_GREY, 32, 24, 0}, {V4L2_PIX_FMT_Y16, 32, 24, 2}}));
  SourceOptions options;
  options.settings.pixel_format = "Y16";
  auto source = open_fake(camera, options);
  EXPECT_EQ(camera->current_fourcc(), V4L2_PIX_FMT_Y16);
  EXPECT_EQ(source->info().bits, 16);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  expect_pattern(*frame, 16);
}

TEST(V4l2Source, RequestedFormatNotOfferedListsTheOfferedOnes) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_GREY, 32, 24, 0}, {V4L2_PIX_FMT_YUYV, 32, 24, 0}}));
  SourceOptions options;
  options.settings.pixel_format = "MJPG";
  EXPECT_EQ(open_error(camera, options),
            "v4l2:/dev/video0: pixel format MJPG is not offered by the device (it offers: GREY, YUYV)");
  options.settings.pixel_format = "RGB3";
  EXPECT_EQ(
      open_error(camera, options),
      "v4l2:/dev/video0: pixel format 'RGB3' is not supported by the v4l2 backend (it reads GREY, Y16, YUYV, "
      "MJPG)");
}

TEST(V4l2Source, NoReadableFormatListsTheOfferedOnes) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_H264, 32, 24, 0}}));
  const std::string error = open_error(camera);
  EXPECT_NE(error.find("v4l2:/dev/video0: the device offers no format"), std::string::npos) << error;
  EXPECT_NE(error.find("it offers: H264"), std::string::npos) << error;
}

TEST(V4l2Source, FrameSizeTheDeviceCannotDeliverIsAnError) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_GREY, 64, 48, 0}}));
  SourceOptions options;
  options.settings.roi_width = 32;
  options.settings.roi_height = 24;
  EXPECT_EQ(open_error(camera, options),
            "v4l2:/dev/video0: frame size 32x24 is not offered by the device for GREY (nearest: 64x48)");
  options.settings.roi_width = 64;
  options.settings.roi_height = 48;
  EXPECT_EQ(open_error(camera, options), "no error");
}

TEST(V4l2Source, EveryBufferIsRequeuedAndReleasedOnClose) {
  auto camera = make_camera();
  SourceOptions options;
  options.settings.buffers = 4;
  {
    auto source = open_fake(camera, options);
    EXPECT_EQ(camera->buffers_requested(), 4);
    EXPECT_EQ(camera->buffers_allocated(), 4);
    EXPECT_EQ(camera->mappings(), 4);
    EXPECT_TRUE(camera->streaming());
    // Four buffers and twenty frames: a buffer not given back would stall the stream.
    for (int k = 0; k < 20; ++k) {
      ASSERT_TRUE(source->next()) << k;
      EXPECT_EQ(camera->buffers_queued(), 4) << "after frame " << k;
    }
  }
  EXPECT_FALSE(camera->streaming());
  EXPECT_EQ(camera->mappings(), 0);
  EXPECT_EQ(camera->buffers_allocated(), 0);
}

TEST(V4l2Source, TakesFewerBuffersWhenTheDriverGrantsFewer) {
  FakeV4l2Camera::Config config;
  config.max_buffers = 3;
  auto camera = make_camera(config);
  auto source = open_fake(camera);  // asks for the default 8
  EXPECT_EQ(camera->buffers_requested(), 8);
  EXPECT_EQ(camera->mappings(), 3);
  for (int k = 0; k < 10; ++k) ASSERT_TRUE(source->next());
}

// Stamps: CLOCK_MONOTONIC buffer time on the wall clock, moved to mid-exposure.
TimeNs wall_of_monotonic(TimeNs monotonic_ns) {
  return monotonic_ns + (wall_now_ns() - monotonic_now_ns());
}

constexpr double kExposureUs = 10'000;                     // 10 ms: half of it is far above the tolerance
constexpr TimeNs kClockTolerance = 2 * kNsPerMillisecond;  // offset sampled at different moments

TEST(V4l2Source, EndOfFrameStampsMoveBackByHalfTheExposure) {
  auto camera = make_camera();
  SourceOptions options;
  options.settings.exposure_us = kExposureUs;
  auto source = open_fake(camera, options);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_DOUBLE_EQ(frame->exposure_us, kExposureUs);
  const TimeNs expected = wall_of_monotonic(camera->last_timestamp_ns()) - 5 * kNsPerMillisecond;
  EXPECT_NEAR(static_cast<double>(frame->stamp_ns - expected), 0.0, kClockTolerance);
  EXPECT_LE(frame->stamp_ns, frame->arrival_ns);
}

TEST(V4l2Source, StartOfExposureStampsMoveForwardByHalfTheExposure) {
  FakeV4l2Camera::Config config;
  config.start_of_exposure_timestamps = true;
  auto camera = make_camera(config);
  SourceOptions options;
  options.settings.exposure_us = kExposureUs;
  auto source = open_fake(camera, options);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  const TimeNs expected = wall_of_monotonic(camera->last_timestamp_ns()) + 5 * kNsPerMillisecond;
  EXPECT_NEAR(static_cast<double>(frame->stamp_ns - expected), 0.0, kClockTolerance);
}

TEST(V4l2Source, WithoutMonotonicStampsTheArrivalStandsInForTheEndOfFrame) {
  FakeV4l2Camera::Config config;
  config.monotonic_timestamps = false;
  auto camera = make_camera(config);
  SourceOptions options;
  options.settings.exposure_us = kExposureUs;
  auto source = open_fake(camera, options);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->stamp_ns, frame->arrival_ns - 5 * kNsPerMillisecond);
}

TEST(V4l2Source, BadFramesAreCountedAndDropped) {
  auto camera = make_camera();
  camera->inject({FakeFault::kNone, FakeFault::kErrorFlag, FakeFault::kShortBuffer, FakeFault::kNone,
                  FakeFault::kSkipThreeSequences, FakeFault::kNone});
  auto source = open_fake(camera);
  std::vector<std::int64_t> sequences;
  for (int k = 0; k < 4; ++k) {
    const auto frame = source->next();
    ASSERT_TRUE(frame);
    sequences.push_back(frame->sequence);
    expect_pattern(*frame, 8);
  }
  // V4L2 sequences 0 ok, 1 error flag, 2 short, 3 ok, 7 ok (4-6 never arrived), 8 ok.
  EXPECT_EQ(sequences, (std::vector<std::int64_t>{0, 3, 7, 8}));
  const SourceCounters counters = source->counters();
  EXPECT_EQ(counters.at("corrupt"), 1u);
  EXPECT_EQ(counters.at("short"), 1u);
  EXPECT_EQ(counters.at("lost"), 3u);
  EXPECT_EQ(counters.count("decode_error"), 0u);
  EXPECT_EQ(camera->buffers_queued(), 8);  // dropped frames' buffers went back too
}

TEST(V4l2Source, UndecodableMjpgIsCountedAsDecodeError) {
  auto camera = make_camera(with_formats({{V4L2_PIX_FMT_MJPEG, 32, 24, 0}}));
  camera->inject({FakeFault::kCorruptJpeg, FakeFault::kNone});
  auto source = open_fake(camera);
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->sequence, 1);
  EXPECT_EQ(source->counters().at("decode_error"), 1u);
}

TEST(V4l2Source, DisconnectIsCountedAndTheDeviceIsReopened) {
  auto camera = make_camera();
  camera->set_failed_opens_after_disconnect(2);
  camera->inject({FakeFault::kNone, FakeFault::kNone, FakeFault::kDisconnect});
  SourceOptions options;
  options.settings.reconnect_interval_ms = 20;
  options.settings.exposure_us = 2000;
  options.settings.buffers = 4;
  auto source = open_fake(camera, options);
  ASSERT_TRUE(source->next());
  ASSERT_TRUE(source->next());
  // The third next() sees ENODEV, fails to reopen twice, then gets the camera back.
  auto pending = std::async(std::launch::async, [&] { return source->next(); });
  ASSERT_EQ(pending.wait_for(kGenerousWait), std::future_status::ready);
  const auto frame = pending.get();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->sequence, 2);  // numbering continues across the reconnection
  const SourceCounters counters = source->counters();
  EXPECT_EQ(counters.at("disconnect"), 1u);
  EXPECT_EQ(counters.at("reconnect"), 1u);
  EXPECT_EQ(camera->failed_opens(), 2);
  EXPECT_EQ(camera->opens(), 2);
  EXPECT_NE(source->last_error().find("cannot open: No such file or directory"), std::string::npos)
      << source->last_error();
  // The old stream's mappings are gone, the new one has its own, and the settings came back.
  EXPECT_EQ(camera->mappings(), 4);
  EXPECT_EQ(camera->control_value(V4L2_CID_EXPOSURE_ABSOLUTE), 20);
  ASSERT_TRUE(source->next());
}

TEST(V4l2Source, RestartReopensTheDevice) {
  auto camera = make_camera();
  auto source = open_fake(camera);
  ASSERT_TRUE(source->next());
  source->restart();
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_EQ(camera->opens(), 2);
  EXPECT_EQ(source->counters().at("restart"), 1u);
  EXPECT_EQ(source->counters().at("reconnect"), 1u);
  EXPECT_EQ(frame->sequence, 1);
}

TEST(V4l2Source, ExposureSwitchesToManualAndIsRangeChecked) {
  auto camera = make_camera();
  auto source = open_fake(camera);
  EXPECT_EQ(source->set_control(Control::kExposureUs, 2000), "");
  const auto sets = camera->controls_set();
  ASSERT_EQ(sets.size(), 2u);
  EXPECT_EQ(sets[0], (std::pair<std::uint32_t, std::int32_t>{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL}));
  EXPECT_EQ(sets[1],
            (std::pair<std::uint32_t, std::int32_t>{V4L2_CID_EXPOSURE_ABSOLUTE, 20}));  // 100 µs units
  EXPECT_EQ(source->control(Control::kExposureUs), 2000.0);
  // The new exposure moves the stamps: frames report it.
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_DOUBLE_EQ(frame->exposure_us, 2000);

  EXPECT_EQ(source->set_control(Control::kExposureUs, 600'000),
            "exposure 600000 us is out of range [100, 500000] us");
  EXPECT_EQ(source->set_control(Control::kExposureUs, -1), "exposure must be positive (got -1)");
  EXPECT_EQ(camera->control_value(V4L2_CID_EXPOSURE_ABSOLUTE), 20);
}

TEST(V4l2Source, GainIsRangeCheckedInDeviceUnits) {
  auto camera = make_camera();
  auto source = open_fake(camera);
  EXPECT_EQ(source->set_control(Control::kGainDb, 100), "");
  EXPECT_EQ(camera->control_value(V4L2_CID_GAIN), 100);
  EXPECT_EQ(source->control(Control::kGainDb), 100.0);
  const std::string error = source->set_control(Control::kGainDb, 300);
  EXPECT_NE(error.find("gain 300 is out of range [0, 255]"), std::string::npos) << error;
  EXPECT_EQ(camera->control_value(V4L2_CID_GAIN), 100);
}

TEST(V4l2Source, MissingControlsAreReportedAsUnsupported) {
  FakeV4l2Camera::Config config;
  config.has_exposure = false;
  config.has_gain = false;
  config.timeperframe = false;
  auto camera = make_camera(config);
  auto source = open_fake(camera);
  EXPECT_NE(source->set_control(Control::kExposureUs, 1000).find("exposure is not supported"),
            std::string::npos);
  EXPECT_NE(source->set_control(Control::kGainDb, 1).find("gain is not supported"), std::string::npos);
  EXPECT_NE(source->set_control(Control::kFrameRateHz, 60).find("frame rate is not settable"),
            std::string::npos);
  EXPECT_FALSE(source->control(Control::kExposureUs));
  // No exposure control: stamps cannot be moved to mid-exposure and say so with exposure 0.
  const auto frame = source->next();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->exposure_us, 0);
}

TEST(V4l2Source, FrameRateIsSetThroughTheFrameInterval) {
  auto camera = make_camera();
  auto source = open_fake(camera);
  EXPECT_EQ(source->set_control(Control::kFrameRateHz, 60), "");
  EXPECT_EQ(camera->frame_rate(), 60u);
  EXPECT_EQ(source->control(Control::kFrameRateHz), 60.0);
  EXPECT_EQ(source->set_control(Control::kFrameRateHz, 100),
            "frame rate 100 Hz is not available; the device now runs at 120 Hz");
}

TEST(V4l2Source, SettingsAreAppliedAtOpen) {
  auto camera = make_camera();
  SourceOptions options;
  options.settings.exposure_us = 5000;
  options.settings.gain_db = 7;
  options.settings.frame_rate_hz = 120;
  auto source = open_fake(camera, options);
  EXPECT_EQ(camera->control_value(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(camera->control_value(V4L2_CID_EXPOSURE_ABSOLUTE), 50);
  EXPECT_EQ(camera->control_value(V4L2_CID_GAIN), 7);
  EXPECT_EQ(camera->frame_rate(), 120u);
  EXPECT_DOUBLE_EQ(source->info().nominal_rate_hz, 120);

  auto other = make_camera();
  options.settings.exposure_us = 9e6;
  EXPECT_EQ(open_error(other, options),
            "v4l2:/dev/video0: exposure 9000000 us is out of range [100, 500000] us");
}

TEST(V4l2Source, StopUnblocksAWaitingNextAndTimeoutsAreCounted) {
  auto camera = make_camera();
  camera->set_paused(true);
  SourceOptions options;
  options.settings.timeout_ms = 100;
  auto source = open_fake(camera, options);
  auto pending = std::async(std::launch::async, [&] { return source->next(); });
  const auto deadline = std::chrono::steady_clock::now() + kGenerousWait;
  while (source->counters().count("timeout") == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_GE(source->counters().count("timeout"), 1u);
  EXPECT_EQ(source->last_error(), "no frame within 100 ms");
  EXPECT_EQ(pending.wait_for(std::chrono::milliseconds(0)), std::future_status::timeout);  // still waiting
  source->stop();
  ASSERT_EQ(pending.wait_for(kGenerousWait), std::future_status::ready);
  EXPECT_FALSE(pending.get());
}

TEST(V4l2Source, StopUnblocksAWaitForReconnection) {
  auto camera = make_camera();
  camera->set_failed_opens_after_disconnect(1'000'000);
  camera->inject({FakeFault::kDisconnect});
  SourceOptions options;
  options.settings.reconnect_interval_ms = 600'000;  // without stop() the next attempt is ten minutes away
  auto source = open_fake(camera, options);
  auto pending = std::async(std::launch::async, [&] { return source->next(); });
  const auto deadline = std::chrono::steady_clock::now() + kGenerousWait;
  while (source->counters().count("disconnect") == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(source->counters().count("disconnect"), 1u);
  source->stop();
  ASSERT_EQ(pending.wait_for(kGenerousWait), std::future_status::ready);
  EXPECT_FALSE(pending.get());
}

TEST(V4l2Source, MaxFramesEndsTheStream) {
  auto camera = make_camera();
  SourceOptions options;
  options.max_frames = 2;
  auto source = open_fake(camera, options);
  EXPECT_TRUE(source->next());
  EXPECT_TRUE(source->next());
  EXPECT_FALSE(source->next());
}

// The real device implementation: there is no /dev/video9 here (no media support in the kernel);
// the integration test of camera_node relies on the same one-line message and exit status 2.
TEST(V4l2Source, MissingDeviceIsAOneLineError) {
  if (std::filesystem::exists("/dev/video9")) GTEST_SKIP() << "/dev/video9 exists on this machine";
  try {
    open_source("v4l2:/dev/video9", {});
    FAIL() << "opened a missing device";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()), "v4l2:/dev/video9: cannot open: No such file or directory");
  }
}

TEST(V4l2Source, NonV4l2DeviceIsRejected) {
  if (!std::filesystem::exists("/dev/null")) GTEST_SKIP() << "no /dev/null";
  try {
    make_v4l2_source("/dev/null", open_real_v4l2_device, {});
    FAIL() << "accepted /dev/null";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()),
              "v4l2:/dev/null: not a V4L2 device (VIDIOC_QUERYCAP: Inappropriate ioctl for device)");
  }
}

TEST(V4l2Source, FourccNames) {
  EXPECT_EQ(fourcc_to_string(V4L2_PIX_FMT_GREY), "GREY");
  EXPECT_EQ(fourcc_to_string(V4L2_PIX_FMT_Y16), "Y16");
  EXPECT_EQ(fourcc_to_string(V4L2_PIX_FMT_MJPEG), "MJPG");
}

}  // namespace
}  // namespace panoptes::camera
