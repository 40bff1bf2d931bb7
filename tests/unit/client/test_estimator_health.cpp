// SPDX-License-Identifier: Apache-2.0
// Client::estimator_health (issue 34, item 4): the cameras as the estimator's status reports them,
// a lost camera with its silence, refused frames of a second writer, and tracks only predicted.
#include <chrono>

#include <gtest/gtest.h>

#include "../dds_test_support.h"
#include "panoptes/client/client.h"
#include "panoptes/dds/bus.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::client {
namespace {

using namespace std::chrono_literals;

msg::CameraUsage camera(const std::string& id, std::uint8_t state, double since_s, std::uint64_t refused) {
  msg::CameraUsage c;
  c.camera_id(id);
  c.state(state);
  c.since_last_frame_s(since_s);
  c.utilisation(state == 0 ? 1.0 : 0.0);
  c.refused_frames(refused);
  return c;
}

TEST(EstimatorHealth, ReportsLiveAndLostCamerasFromTheEstimatorsStatus) {
  dds::BusOptions bus_options;
  bus_options.domain_id = test::dds_test_domain();
  bus_options.participant_name = "fake_estimator";
  dds::Bus bus(bus_options);
  auto writer = bus.make_writer<msg::EstimatorStatus>();
  ClientOptions options;
  options.domain_id = test::dds_test_domain();
  Client client(options);
  EXPECT_FALSE(client.estimator_health().received);
  EXPECT_EQ(client.estimator_health().age_s, -1);
  ASSERT_TRUE(writer->wait_for_readers(1, 10s));

  msg::EstimatorStatus status;
  status.cameras_live(3);
  status.cameras_lost(1);
  status.cameras().push_back(camera("c0", 0, 0.004, 812));
  status.cameras().push_back(camera("c1", 0, 0.006, 0));
  status.cameras().push_back(camera("c2", 0, 0.002, 0));
  status.cameras().push_back(camera("c3", 1, 1.234, 0));
  // Best effort: write until it arrives.
  ASSERT_TRUE(test::wait_until([&] {
    writer->write(status);
    return client.estimator_health().received;
  }));
  const EstimatorHealth health = client.estimator_health();
  EXPECT_EQ(health.cameras_live, 3);
  EXPECT_EQ(health.cameras_lost, 1);
  EXPECT_EQ(health.tracks_unobserved, 0);
  EXPECT_GE(health.age_s, 0.0);
  EXPECT_LT(health.age_s, 10.0);
  ASSERT_EQ(health.cameras.size(), 4U);
  EXPECT_TRUE(health.cameras[0].live);
  EXPECT_EQ(health.cameras[0].refused_frames, 812U);
  EXPECT_EQ(health.cameras[3].camera_id, "c3");
  EXPECT_FALSE(health.cameras[3].live);
  EXPECT_DOUBLE_EQ(health.cameras[3].since_last_frame_s, 1.234);

  // Every camera lost: the tracks it still holds are predictions.
  msg::EstimatorStatus blind;
  blind.cameras_lost(4);
  blind.tracks_unobserved(3);
  ASSERT_TRUE(test::wait_until([&] {
    writer->write(blind);
    return client.estimator_health().cameras_lost == 4;
  }));
  EXPECT_EQ(client.estimator_health().cameras_live, 0);
  EXPECT_EQ(client.estimator_health().tracks_unobserved, 3);
}

}  // namespace
}  // namespace panoptes::client
