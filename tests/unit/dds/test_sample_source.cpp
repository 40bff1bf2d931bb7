// SPDX-License-Identifier: Apache-2.0
// A sourced reader names each sample's DDS writer (Bus::make_sourced_reader): two camera nodes
// writing features for one camera id have different writers, which the estimator's camera-id
// ownership table (estimator/camera_ownership.h) tells apart (issue 34, item 4).
#include <chrono>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "../dds_test_support.h"
#include "panoptes/dds/bus.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::dds {
namespace {

using namespace std::chrono_literals;

BusOptions options(const std::string& name) {
  BusOptions o;
  o.domain_id = test::dds_test_domain();
  o.participant_name = name;
  return o;
}

TEST(SampleSource, TwoWritersOfOneCameraIdAreToldApart) {
  Bus estimator(options("estimator")), first(options("camera_c0")), second(options("impostor_c0"));
  std::mutex mutex;
  std::map<std::string, std::set<long long>> frames_by_writer;
  auto reader = estimator.make_sourced_reader<msg::FeatureFrame>(
      [&](msg::FeatureFrame&& frame, const SampleSource& source) {
        std::lock_guard lock(mutex);
        frames_by_writer[source.writer()].insert(frame.frame());
      });
  auto writer_a = first.make_writer<msg::FeatureFrame>(Qos::kDefault, {}, "c0");
  auto writer_b = second.make_writer<msg::FeatureFrame>(Qos::kDefault, {}, "c0");
  ASSERT_TRUE(writer_a->wait_for_readers(1, 10s));
  ASSERT_TRUE(writer_b->wait_for_readers(1, 10s));
  ASSERT_TRUE(test::wait_until([&] { return reader->matched_writers() == 2; }));
  for (int i = 0; i < 20; ++i) {
    msg::FeatureFrame frame;
    frame.camera_id("c0");
    frame.frame(i);
    (i % 2 == 0 ? writer_a : writer_b)->write(frame);
    std::this_thread::sleep_for(2ms);
  }
  // Best effort on loopback: allow a loss, but each writer must be seen.
  ASSERT_TRUE(test::wait_until([&] {
    std::lock_guard lock(mutex);
    std::size_t total = 0;
    for (const auto& [writer, frames] : frames_by_writer) total += frames.size();
    return frames_by_writer.size() == 2 && total >= 16;
  }));
  std::lock_guard lock(mutex);
  ASSERT_EQ(frames_by_writer.size(), 2U);
  const auto& [writer_1, frames_1] = *frames_by_writer.begin();
  const auto& [writer_2, frames_2] = *std::next(frames_by_writer.begin());
  EXPECT_NE(writer_1, writer_2);
  // One writer sent the even frames, the other the odd ones: never mixed.
  const bool even_1 = *frames_1.begin() % 2 == 0;
  for (long long f : frames_1) EXPECT_EQ(f % 2 == 0, even_1) << writer_1;
  for (long long f : frames_2) EXPECT_EQ(f % 2 == 0, !even_1) << writer_2;
  // "<24 hex digits>.<8 hex digits>": the participant prefixes differ, as the processes do.
  ASSERT_EQ(writer_1.size(), 33U);
  EXPECT_EQ(writer_1[24], '.');
  EXPECT_EQ(writer_1.find_first_not_of("0123456789abcdef."), std::string::npos);
  EXPECT_NE(writer_1.substr(0, 24), writer_2.substr(0, 24));
}

TEST(SampleSource, FormatsTheGuidAsHexWithTheEntityIdApart) {
  SampleSource source;
  for (std::size_t i = 0; i < source.writer_guid.size(); ++i)
    source.writer_guid[i] = static_cast<std::uint8_t>(i * 17);
  EXPECT_EQ(source.writer(), "00112233445566778899aabb.ccddeeff");
}

}  // namespace
}  // namespace panoptes::dds
