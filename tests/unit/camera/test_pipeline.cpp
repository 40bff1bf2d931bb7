// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "panoptes/camera/detector.h"
#include "panoptes/camera/mailbox.h"
#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/node_log.h"
#include "panoptes/camera/pipeline.h"
#include "panoptes/camera/sources.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

// Delivers `count` frames (blobs, or black images), then ends; throws instead after `fail_after`
// frames; with `endless` it keeps delivering slowly until stop().
class ScriptedSource final : public FrameSource {
 public:
  int count = 0;
  int fail_after = -1;
  bool endless = false;
  bool images = false;
  std::atomic<bool> stopped{false};

  const SourceInfo& info() const override { return info_; }
  std::optional<CapturedFrame> next() override {
    if (stopped.load()) return std::nullopt;
    if (fail_after >= 0 && delivered_ == fail_after) throw std::runtime_error("device fell off the bus");
    if (endless) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    } else if (delivered_ >= count) {
      return std::nullopt;
    }
    CapturedFrame frame;
    frame.sequence = delivered_++;
    frame.stamp_ns = 1'000'000'000 + frame.sequence * 1000;
    frame.arrival_ns = 2'000'000'000 + frame.sequence * 1000;
    if (images) {
      frame.image = Image(64, 48, 8);
    } else {
      frame.blobs = std::vector<Blob>(1);
      frame.blobs->front().x = static_cast<double>(frame.sequence);
    }
    return frame;
  }
  void stop() override { stopped.store(true); }

 private:
  SourceInfo info_ = [] {
    SourceInfo info;
    info.camera_id = "scripted";
    info.backend = "features";
    return info;
  }();
  std::int64_t delivered_ = 0;
};

class RecordingSink final : public FeatureSink {
 public:
  std::vector<FeatureFrame> frames;
  int finished = 0;
  void add(FeatureFrame&& frame) override {
    // Slower than the source: a lossy queue would drop.
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    frames.push_back(std::move(frame));
  }
  void finish() override { ++finished; }
};

class PreviewObserver final : public PipelineObserver {
 public:
  std::vector<Image> previews;
  int passes = 0;
  void on_pass(TimeNs) override { ++passes; }
  void on_preview(const Image& preview, TimeNs) override { previews.push_back(preview); }
};

class PipelineTest : public ::testing::Test {
 protected:
  CameraPipelineOptions options(bool lossless) {
    CameraPipelineOptions options;
    options.camera_id = "cam7";
    options.queue_capacity = 2;
    options.lossless = lossless;
    options.stop_on_signal = false;
    return options;
  }

  NodeLog log{"test_pipeline"};
  ScriptedSource source;
  Detector detector{DetectorConfig{}};
  NodeClock identity;
  StampCorrection stamps{identity, nullptr};
  RecordingSink sink;
};

TEST_F(PipelineTest, LosslessDeliversEveryFrameInOrderUnderItsCameraId) {
  source.count = 300;
  CameraPipeline pipeline(options(true), source, detector, stamps, sink, log);
  pipeline.run();
  ASSERT_EQ(sink.frames.size(), 300u);
  for (std::size_t i = 0; i < sink.frames.size(); ++i) {
    EXPECT_EQ(sink.frames[i].frame, static_cast<std::int64_t>(i));
    EXPECT_EQ(sink.frames[i].camera_id, "cam7");
    EXPECT_EQ(sink.frames[i].stamp_ns, 1'000'000'000 + static_cast<TimeNs>(i) * 1000);
  }
  EXPECT_EQ(sink.finished, 1);
  EXPECT_EQ(pipeline.frames(), 300u);
  EXPECT_EQ(pipeline.queue_drops(), 0u);
}

TEST_F(PipelineTest, StampsAreCorrectedOntoTheNodeClock) {
  source.count = 3;
  const NodeClock skewed(0, 0, ClockSkew{5'000, 0.0});
  const StampCorrection skewed_stamps(skewed, nullptr);
  CameraPipeline pipeline(options(true), source, detector, skewed_stamps, sink, log);
  pipeline.run();
  ASSERT_EQ(sink.frames.size(), 3u);
  EXPECT_EQ(sink.frames[1].stamp_ns, 1'000'001'000 + 5'000);
  EXPECT_EQ(sink.frames[1].arrival_ns, 2'000'001'000 + 5'000);
}

TEST_F(PipelineTest, AThrowingSourceEndsTheStreamAndIsCountedOffline) {
  source.count = 10;
  source.fail_after = 4;
  CameraPipelineOptions counting = options(true);
  counting.count_source_failure = true;
  CameraPipeline pipeline(counting, source, detector, stamps, sink, log);
  pipeline.run();
  EXPECT_EQ(sink.frames.size(), 4u);
  EXPECT_EQ(pipeline.counters().counts().at("source_error"), 1u);
  EXPECT_EQ(pipeline.counters().last_error(), "device fell off the bus");
}

TEST_F(PipelineTest, StopFromAnotherThreadStopsTheSourceAndFinishesTheSink) {
  source.endless = true;
  CameraPipeline pipeline(options(false), source, detector, stamps, sink, log);
  std::thread stopper([&pipeline] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    pipeline.stop();
  });
  pipeline.run();
  stopper.join();
  EXPECT_TRUE(source.stopped.load());
  EXPECT_EQ(sink.finished, 1);
  EXPECT_GT(sink.frames.size(), 0u);
}

TEST_F(PipelineTest, CommandsApplyBetweenFramesAndAPreviewGoesToTheObserver) {
  source.count = 5;
  source.images = true;
  Mailbox<Command> commands;
  commands.push({"*", 1, "set_threshold", {"77"}});
  commands.push({"other_camera", 2, "set_threshold", {"1"}});
  commands.push({"cam7", 3, "preview", {"16"}});
  commands.push({"cam7", 4, "no_such_command", {}});
  PreviewObserver observer;
  CameraPipeline pipeline(options(true), source, detector, stamps, sink, log);
  pipeline.set_commands(&commands);
  pipeline.set_observer(&observer);
  pipeline.run();
  EXPECT_EQ(detector.config().threshold, 77);
  EXPECT_EQ(pipeline.command_counters().at("command_set_threshold"), 1u);
  EXPECT_EQ(pipeline.command_counters().at("bad_command"), 1u);
  EXPECT_NE(pipeline.counters().last_error().find("no_such_command"), std::string::npos);
  ASSERT_EQ(observer.previews.size(), 1u);  // one preview, of the first frame after the command
  EXPECT_EQ(observer.previews[0].width, 16);
  EXPECT_GT(observer.passes, 0);
  EXPECT_EQ(sink.frames.size(), 5u);
}

TEST_F(PipelineTest, PredictionsNearTheFrameGuideTheSearch) {
  source.count = 4;
  source.images = true;
  PredictionBox predictions;
  predictions.store(1'000'002'000, {SearchWindow{10, 10, 5, 5}});
  CameraPipelineOptions guided = options(true);
  guided.prediction_max_age_ns = 1'000;  // frames 1, 2 and 3 are within 1 us of the prediction
  CameraPipeline pipeline(guided, source, detector, stamps, sink, log);
  pipeline.set_predictions(&predictions);
  pipeline.run();
  EXPECT_EQ(pipeline.guided_frames(), 3u);
}

TEST(PredictionBox, FreshOnlyWithinTheMaximumAge) {
  PredictionBox box;
  std::vector<SearchWindow> windows{SearchWindow{}};
  box.fresh_for(0, 1'000'000, windows);
  EXPECT_TRUE(windows.empty());  // nothing received yet
  box.store(10'000'000, {SearchWindow{1, 2, 3, 4}, SearchWindow{5, 6, 7, 8}});
  box.fresh_for(10'500'000, 1'000'000, windows);
  EXPECT_EQ(windows.size(), 2u);
  box.fresh_for(8'000'000, 1'000'000, windows);
  EXPECT_TRUE(windows.empty());
}

TEST(Mailbox, TakesAllInOrderAndKeepsOnlyTheNewestWhenFull) {
  Mailbox<int> box;
  for (int i = 0; i < static_cast<int>(Mailbox<int>::kCapacity) + 10; ++i) box.push(i);
  const auto items = box.take_all();
  ASSERT_EQ(items.size(), Mailbox<int>::kCapacity);
  EXPECT_EQ(items.front(), 10);
  EXPECT_EQ(items.back(), static_cast<int>(Mailbox<int>::kCapacity) + 9);
  EXPECT_TRUE(box.take_all().empty());
}

}  // namespace
}  // namespace panoptes::camera
