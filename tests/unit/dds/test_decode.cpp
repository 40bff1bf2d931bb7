// SPDX-License-Identifier: Apache-2.0
// decode_sample (every typed reader's decoder) and the Bus's counting of malformed samples
// (docs/hostile_input.md).
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../dds_test_support.h"
#include "panoptes/calibration.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/cdr.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/decode.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::dds {
namespace {

using Bytes = std::vector<std::uint8_t>;

msg::FeatureFrame frame_with_id(const std::string& id, int blobs) {
  msg::FeatureFrame frame;
  frame.camera_id(id);
  frame.frame(7);
  frame.stamp_ns(123456789);
  for (int i = 0; i < blobs; ++i) {
    msg::Blob blob;
    blob.x(static_cast<float>(i));
    frame.blobs().push_back(blob);
  }
  return frame;
}

void put_u32(Bytes& cdr, std::size_t offset, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) cdr[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

TEST(Decode, EveryValidSampleDecodesWhateverItsStringLengths) {
  // Strings of every length modulo the alignment, so padding after them takes every size: the
  // unterminated-string checks must never reject a genuine sample.
  for (int length = 0; length < 20; ++length) {
    const std::string id(static_cast<std::size_t>(length), 'c');
    for (int blobs : {0, 1, 3}) {
      const msg::FeatureFrame frame = frame_with_id(id, blobs);
      msg::FeatureFrame decoded;
      const Bytes cdr = encode_sample(frame);
      ASSERT_EQ(decode_sample(cdr.data(), cdr.size(), decoded), DecodeError::kNone) << length << " " << blobs;
      EXPECT_EQ(decoded, frame);
    }
    msg::CameraCommand command;
    command.target(id);
    command.command("set_threshold");
    command.arguments({id, "x"});
    msg::CameraCommand decoded_command;
    const Bytes cdr = encode_sample(command);
    ASSERT_EQ(decode_sample(cdr.data(), cdr.size(), decoded_command), DecodeError::kNone) << length;
    EXPECT_EQ(decoded_command, command);
    msg::TimeSync sync;
    sync.client_id(id);
    msg::TimeSync decoded_sync;
    const Bytes sync_cdr = encode_sample(sync);
    EXPECT_EQ(decode_sample(sync_cdr.data(), sync_cdr.size(), decoded_sync), DecodeError::kNone) << length;
  }
}

TEST(Decode, NamesEachKindOfMalformedSample) {
  const Bytes cdr = encode_sample(frame_with_id("rogue-id-11", 0));
  msg::FeatureFrame out;
  EXPECT_EQ(decode_sample(cdr.data(), cdr.size() / 2, out), DecodeError::kTruncated);
  EXPECT_EQ(decode_sample(cdr.data(), 3, out), DecodeError::kTruncated);
  EXPECT_EQ(decode_sample(nullptr, 0, out), DecodeError::kTruncated);

  Bytes bad_header = cdr;
  bad_header[0] = 0xff;
  EXPECT_EQ(decode_sample(bad_header.data(), bad_header.size(), out), DecodeError::kBadEncapsulation);

  Bytes absurd_sequence = cdr;  // the empty blob sequence is the last member
  put_u32(absurd_sequence, cdr.size() - 4, 0x7ffffff0U);
  EXPECT_EQ(decode_sample(absurd_sequence.data(), absurd_sequence.size(), out), DecodeError::kTruncated);
  Bytes absurd_string = cdr;
  put_u32(absurd_string, 4, 0xfffffff0U);
  EXPECT_EQ(decode_sample(absurd_string.data(), absurd_string.size(), out), DecodeError::kTruncated);

  // 11 characters: the padding after the id absorbs the missing NUL, the rest still decodes.
  Bytes unterminated = cdr;
  put_u32(unterminated, 4, 11);
  unterminated[8 + 11] = 'X';
  EXPECT_EQ(decode_sample(unterminated.data(), unterminated.size(), out), DecodeError::kUnterminatedString);

  // A command whose last argument lacks its NUL: the sample is one byte short.
  msg::CameraCommand command;
  command.target("*");
  command.arguments({"abc"});
  Bytes short_command = encode_sample(command);
  ASSERT_EQ(short_command.back(), 0);
  short_command.pop_back();
  put_u32(short_command, short_command.size() - 4 - 3, 3);  // the argument's length field
  msg::CameraCommand decoded;
  EXPECT_EQ(decode_sample(short_command.data(), short_command.size(), decoded),
            DecodeError::kUnterminatedString);
  EXPECT_EQ(decode_error_name(DecodeError::kUnterminatedString), "cdr_unterminated_string");
}

TEST(Decode, CameraInfoWithNonFiniteCalibrationIsRejected) {
  msg::CameraInfo info = to_camera_info("cam0", CameraIntrinsics{}, std::nullopt);
  info.width(640);
  info.height(480);
  info.K({600, 600, 320, 240});
  EXPECT_EQ(camera_info_problem(info), "");
  EXPECT_TRUE(calibration_from(info).has_value());
  info.K({std::numeric_limits<double>::quiet_NaN(), 600, 320, 240});
  EXPECT_EQ(camera_info_problem(info), "non_finite_calibration");
  EXPECT_FALSE(calibration_from(info).has_value());
  info.K({600, 600, 320, 240});
  info.camera_id(std::string("cam\x01", 4));
  EXPECT_EQ(camera_info_problem(info), "bad_camera_id");
}

// A camera carried by a rig says so (docs/inside_out.md): `moving` reaches the calibration, so the
// estimator does not take its mount for a fixed pose.
TEST(Decode, CameraInfoCarriesMoving) {
  CameraIntrinsics intrinsics;
  intrinsics.width = 1280;
  intrinsics.height = 1024;
  intrinsics.fx = intrinsics.fy = 800;
  const RigidTransform mount;
  const auto moving = calibration_from(to_camera_info("head", intrinsics, mount, true));
  ASSERT_TRUE(moving.has_value());
  EXPECT_TRUE(moving->moving);
  const auto fixed = calibration_from(to_camera_info("cam0", intrinsics, mount));
  ASSERT_TRUE(fixed.has_value());
  EXPECT_FALSE(fixed->moving);
}

// The calibration in use as rt/panoptes/calibration carries it (issue 36 item 5): every camera,
// intrinsics, distortion and pose ([x, y, z, w] quaternion), has_pose false without a pose; and it
// survives the wire (CDR) unchanged.
TEST(Decode, SystemCalibrationCarriesEveryCamera) {
  SystemCalibration calibration;
  CameraCalibration posed;
  posed.id = "cam0";
  posed.intrinsics = {1280, 1024, 1000.5, 1001.5, 640.25, 511.75, {0.1, -0.2, 0.001, -0.002, 0.03}};
  RigidTransform T;
  T.t = Eigen::Vector3d(1.0, -2.0, 2.5);
  T.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  posed.T_world_cam = T;
  CameraCalibration bare = posed;
  bare.id = "cam1";
  bare.T_world_cam.reset();
  calibration.cameras = {posed, bare};
  const msg::SystemCalibration message = to_message(calibration, 123);
  const auto bytes = encode_sample(message);
  msg::SystemCalibration m;
  ASSERT_EQ(decode_sample(bytes.data(), bytes.size(), m), DecodeError::kNone);
  EXPECT_EQ(m.stamp_ns(), 123);
  ASSERT_EQ(m.cameras().size(), 2U);
  EXPECT_EQ(m.cameras()[0].camera_id(), "cam0");
  EXPECT_EQ(m.cameras()[0].width(), 1280U);
  EXPECT_EQ(m.cameras()[0].K()[1], 1001.5);
  EXPECT_EQ(m.cameras()[0].distortion()[4], 0.03);
  EXPECT_TRUE(m.cameras()[0].has_pose());
  EXPECT_EQ(m.cameras()[0].T_world_cam().position()[1], -2.0);
  EXPECT_DOUBLE_EQ(m.cameras()[0].T_world_cam().orientation()[2], std::sin(0.15));
  EXPECT_DOUBLE_EQ(m.cameras()[0].T_world_cam().orientation()[3], std::cos(0.15));
  EXPECT_FALSE(m.cameras()[1].has_pose());
}

// A reader on the bus: malformed samples from a raw writer are counted by reason and never reach
// the callback; a genuine sample after them still does.
TEST(Decode, BusCountsMalformedSamplesAndKeepsReceiving) {
  BusOptions options;
  options.domain_id = panoptes::test::dds_test_domain();
  options.participant_name = "decode_reader";
  Bus reader_bus(options);
  options.participant_name = "decode_rogue";
  Bus rogue_bus(options);
  std::atomic<int> delivered{0};
  std::atomic<bool> genuine{false};
  auto reader = reader_bus.make_reader<msg::CameraCommand>([&](msg::CameraCommand&& command) {
    ++delivered;
    if (command.command() == "genuine") genuine = true;
  });
  auto writer = rogue_bus.make_raw_writer("rt/panoptes/camera_command");
  ASSERT_TRUE(panoptes::test::wait_until([&] { return writer->matched_readers() >= 1; }));

  msg::CameraCommand command;
  command.target("rogue-id-11");
  const Bytes cdr = encode_sample(command);
  Bytes bad_header = cdr;
  bad_header[0] = 0xff;
  Bytes unterminated = cdr;
  put_u32(unterminated, 4, 11);
  unterminated[8 + 11] = 'X';
  EXPECT_TRUE(writer->write(Bytes(cdr.begin(), cdr.begin() + 6)));
  EXPECT_TRUE(writer->write(bad_header));
  EXPECT_TRUE(writer->write(unterminated));
  command.target("*");
  command.command("genuine");
  EXPECT_TRUE(writer->write(encode_sample(command)));

  EXPECT_TRUE(panoptes::test::wait_until([&] { return genuine.load(); }));
  EXPECT_EQ(delivered.load(), 1);
  const auto counts = reader_bus.receive_rejections();
  EXPECT_EQ(counts.count("cdr_truncated") ? counts.at("cdr_truncated") : 0, 1U);
  EXPECT_EQ(counts.count("cdr_bad_encapsulation") ? counts.at("cdr_bad_encapsulation") : 0, 1U);
  EXPECT_EQ(counts.count("cdr_unterminated_string") ? counts.at("cdr_unterminated_string") : 0, 1U);
}

}  // namespace
}  // namespace panoptes::dds
