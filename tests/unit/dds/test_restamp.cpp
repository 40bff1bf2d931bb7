// SPDX-License-Identifier: Apache-2.0
// shift_sample_times: panoptes_replay moves every absolute time of every recorded topic by one
// offset (docs/recording.md, "Replay"); durations and unknown (0) times stay.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/dds/cdr.h"
#include "panoptes/dds/decode.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/ros2.h"

namespace panoptes::dds {
namespace {

using Bytes = std::vector<std::uint8_t>;
constexpr std::int64_t kShift = 95'000'000'000;  // the 95 s of issue 34

template <class T>
T shifted(const std::string& topic, const T& message, std::int64_t offset = kShift) {
  Bytes cdr = encode_sample(message);
  EXPECT_TRUE(shift_sample_times(topic, cdr, offset)) << topic;
  T out;
  EXPECT_EQ(decode_sample(cdr.data(), cdr.size(), out), DecodeError::kNone) << topic;
  return out;
}

TEST(Restamp, MocapFrameStampsPublishTimeAndStagesMoveDurationsStay) {
  msg::MocapFrame frame;
  frame.frame_number(42);
  frame.stamp_ns(1'000);
  frame.publish_ns(1'500);
  frame.source_camera("cam1");
  frame.source_frame(7);
  frame.stages().camera_arrival_ns(1'100);
  frame.stages().camera_processing_ns(30);
  frame.stages().feature_publish_ns(1'200);
  frame.stages().received_ns(1'300);
  frame.stages().dequeued_ns(1'350);
  frame.stages().updated_ns(0);  // unknown
  msg::FrameBody body;
  body.name("wand");
  body.prediction_horizon_ns(5'000'000);
  frame.bodies().push_back(body);
  const msg::MocapFrame out = shifted("rt/panoptes/frames", frame);
  EXPECT_EQ(out.frame_number(), 42U);
  EXPECT_EQ(out.stamp_ns(), 1'000 + kShift);
  EXPECT_EQ(out.publish_ns(), 1'500 + kShift);
  EXPECT_EQ(out.stages().camera_arrival_ns(), 1'100 + kShift);
  EXPECT_EQ(out.stages().camera_processing_ns(), 30);
  EXPECT_EQ(out.stages().feature_publish_ns(), 1'200 + kShift);
  EXPECT_EQ(out.stages().received_ns(), 1'300 + kShift);
  EXPECT_EQ(out.stages().dequeued_ns(), 1'350 + kShift);
  EXPECT_EQ(out.stages().updated_ns(), 0);
  ASSERT_EQ(out.bodies().size(), 1U);
  EXPECT_EQ(out.bodies()[0].prediction_horizon_ns(), 5'000'000);
  // What a client computes as latency (publish - stamp) is unchanged.
  EXPECT_EQ(out.publish_ns() - out.stamp_ns(), frame.publish_ns() - frame.stamp_ns());
}

TEST(Restamp, TracksStatusAndTimeSyncMoveEveryTime) {
  msg::TrackFrame tracks;
  tracks.stamp_ns(10);
  tracks.publish_ns(20);
  const auto t = shifted("rt/panoptes/tracks", tracks);
  EXPECT_EQ(t.stamp_ns(), 10 + kShift);
  EXPECT_EQ(t.publish_ns(), 20 + kShift);

  msg::EstimatorStatus status;
  status.stamp_ns(30);
  status.latency_window_ms(2.5);
  msg::CameraUsage camera;
  camera.camera_id("cam0");
  camera.last_stamp_ns(25);
  camera.latency_p50_ms(3.0);
  status.cameras().push_back(camera);
  const auto s = shifted("rt/panoptes/estimator_status", status);
  EXPECT_EQ(s.stamp_ns(), 30 + kShift);
  ASSERT_EQ(s.cameras().size(), 1U);
  EXPECT_EQ(s.cameras()[0].last_stamp_ns(), 25 + kShift);
  EXPECT_EQ(s.cameras()[0].latency_p50_ms(), 3.0);
  EXPECT_EQ(s.latency_window_ms(), 2.5);

  msg::TimeSync sync;
  sync.client_id("cam0");
  sync.t1_ns(1);
  sync.t2_ns(2);
  sync.t3_ns(3);
  const auto y = shifted("rt/panoptes/time_sync", sync);
  EXPECT_EQ(y.t1_ns(), 1 + kShift);
  EXPECT_EQ(y.t2_ns(), 2 + kShift);
  EXPECT_EQ(y.t3_ns(), 3 + kShift);
}

TEST(Restamp, EveryStampedTopicMovesByTheSameOffset) {
  msg::BodyPose pose;
  pose.name("wand");
  pose.stamp_ns(100);
  pose.prediction_horizon_ns(7);
  const auto p = shifted("rt/panoptes/bodies", pose, -50);
  EXPECT_EQ(p.stamp_ns(), 50);
  EXPECT_EQ(p.prediction_horizon_ns(), 7);
  msg::BodyDescriptions descriptions;
  descriptions.stamp_ns(100);
  EXPECT_EQ(shifted("rt/panoptes/body_descriptions", descriptions).stamp_ns(), 100 + kShift);
  msg::CameraInfo info;
  info.camera_id("cam0");
  info.stamp_ns(100);
  EXPECT_EQ(shifted("rt/panoptes/camera_info", info).stamp_ns(), 100 + kShift);
  msg::CameraStatus camera;
  camera.camera_id("cam0");
  camera.stamp_ns(100);
  camera.clock_offset_ns(-3);
  const auto c = shifted("rt/panoptes/camera_status", camera);
  EXPECT_EQ(c.stamp_ns(), 100 + kShift);
  EXPECT_EQ(c.clock_offset_ns(), -3);
  msg::Predictions predictions;
  predictions.camera_id("cam0");
  predictions.stamp_ns(100);
  EXPECT_EQ(shifted("rt/panoptes/predictions", predictions).stamp_ns(), 100 + kShift);
  msg::SystemCalibration calibration;
  calibration.stamp_ns(100);
  EXPECT_EQ(shifted("rt/panoptes/calibration", calibration).stamp_ns(), 100 + kShift);
  msg::CameraPreview preview;
  preview.camera_id("cam0");
  preview.stamp_ns(100);
  EXPECT_EQ(shifted("rt/panoptes/camera_preview", preview).stamp_ns(), 100 + kShift);
  msg::FeatureFrame features;
  features.camera_id("cam0");
  features.stamp_ns(100);
  features.arrival_ns(110);
  features.processing_ns(5);
  const auto f = shifted("rt/panoptes/features", features);
  EXPECT_EQ(f.stamp_ns(), 100 + kShift);
  EXPECT_EQ(f.arrival_ns(), 110 + kShift);
  EXPECT_EQ(f.processing_ns(), 5);
}

// The ROS 2 topics (recorded since issue 34 item 7): every header stamp moves, also under a
// namespace or a body's name; sec/nanosec carry and borrow; an all-zero stamp stays.
TEST(Restamp, Ros2HeaderStampsMoveOnEveryRos2Topic) {
  const auto stamp_ns = [](const std_msgs::msg::dds_::Header_& h) {
    return std::int64_t{h.stamp().sec()} * 1'000'000'000 + std::int64_t{h.stamp().nanosec()};
  };
  std_msgs::msg::dds_::Header_ header;
  header.stamp().sec(1'764'000'000);
  header.stamp().nanosec(999'999'000);
  header.frame_id("world");
  const std::int64_t before = stamp_ns(header);

  tf2_msgs::msg::dds_::TFMessage_ tf;
  tf.transforms().resize(2);
  tf.transforms()[0].header(header);
  tf.transforms()[0].child_frame_id("head");
  tf.transforms()[1].header(header);
  const auto t = shifted("rt/tf", tf, 5'000);  // carries into the next second
  EXPECT_EQ(stamp_ns(t.transforms()[0].header()), before + 5'000);
  EXPECT_EQ(t.transforms()[1].header().stamp().sec(), 1'764'000'001);
  EXPECT_EQ(t.transforms()[0].child_frame_id(), "head");

  geometry_msgs::msg::dds_::PoseStamped_ pose;
  pose.header(header);
  pose.pose().position().x(0.25);
  const auto p = shifted("rt/lab1/panoptes/head/pose", pose, -1'000'000'000'000);  // borrows
  EXPECT_EQ(stamp_ns(p.header()), before - 1'000'000'000'000);
  EXPECT_EQ(p.pose().position().x(), 0.25);
  EXPECT_EQ(p.header().frame_id(), "world");

  geometry_msgs::msg::dds_::TwistStamped_ twist;
  twist.header(header);
  EXPECT_EQ(stamp_ns(shifted("rt/panoptes/tool/twist", twist).header()), before + kShift);
  mocap4r2_msgs::msg::dds_::RigidBodies_ bodies;
  bodies.header(header);
  bodies.frame_number(9);
  const auto b = shifted("rt/rigid_bodies", bodies);
  EXPECT_EQ(stamp_ns(b.header()), before + kShift);
  EXPECT_EQ(b.frame_number(), 9U);
  mocap4r2_msgs::msg::dds_::Markers_ markers;
  EXPECT_EQ(stamp_ns(shifted("rt/lab1/markers", markers).header()), 0);  // unknown stays unknown
  markers.header(header);
  EXPECT_EQ(stamp_ns(shifted("rt/lab1/markers", markers).header()), before + kShift);
}

TEST(Restamp, SamplesWithoutTimesPassAndMalformedOnesAreRefused) {
  msg::CameraCommand command;
  command.command("set_threshold");
  const Bytes original = encode_sample(command);
  Bytes cdr = original;
  EXPECT_TRUE(shift_sample_times("rt/panoptes/camera_command", cdr, kShift));
  EXPECT_EQ(cdr, original);
  msg::MocapFrame frame;
  frame.source_camera("cam0");
  Bytes cut = encode_sample(frame);
  cut.resize(10);
  EXPECT_FALSE(shift_sample_times("rt/panoptes/frames", cut, kShift));
}

}  // namespace
}  // namespace panoptes::dds
