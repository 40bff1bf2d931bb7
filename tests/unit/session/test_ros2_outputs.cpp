// SPDX-License-Identifier: Apache-2.0
// The ROS 2 topics of estimator_node (docs/ros2.md): stamps, names, the messages built from a
// FrameOutput, and delivery to a best-effort (ROS 2 SensorDataQoS-like) and a reliable (ROS 2
// default QoS-like) reader over the loopback profile.
#include <atomic>
#include <chrono>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "../dds_test_support.h"
#include "panoptes/dds/bus.h"
#include "panoptes/estimator_app/ros2_outputs.h"
#include "ros2_test_frames.h"

namespace panoptes::estimator_app {
namespace {

using namespace std::chrono_literals;
namespace geometry = geometry_msgs::msg::dds_;
namespace mocap = mocap4r2_msgs::msg::dds_;

TEST(Ros2Time, SplitsIntoSecondsAndNonNegativeNanoseconds) {
  const auto expect = [](TimeNs ns, std::int32_t sec, std::uint32_t nanosec) {
    const auto time = to_ros2_time(ns);
    EXPECT_EQ(time.sec(), sec) << ns;
    EXPECT_EQ(time.nanosec(), nanosec) << ns;
  };
  expect(0, 0, 0);
  expect(1'700'000'000, 1, 700'000'000);
  expect(-1'700'000'000, -2, 300'000'000);  // builtin_interfaces/Time's own example
  expect(-1, -1, 999'999'999);
  expect(-1'000'000'000, -1, 0);
  expect(1'795'472'027'022'242'760, 1'795'472'027, 22'242'760);
  expect(std::numeric_limits<TimeNs>::max(), std::numeric_limits<std::int32_t>::max(), 999'999'999);
  expect(std::numeric_limits<TimeNs>::min(), std::numeric_limits<std::int32_t>::min(), 0);
}

TEST(Ros2Names, ValidTokensStayAndOthersAreMappedDeterministically) {
  EXPECT_EQ(ros2_name_token("head"), "head");
  EXPECT_EQ(ros2_name_token("Tool_2"), "Tool_2");
  EXPECT_EQ(ros2_name_token("left hand"), "left_hand");
  EXPECT_EQ(ros2_name_token("wand-7.a"), "wand_7_a");
  EXPECT_EQ(ros2_name_token("a  --b"), "a_b");  // no repeated '_'
  EXPECT_EQ(ros2_name_token("__x__"), "x");     // no leading or trailing '_'
  EXPECT_EQ(ros2_name_token("3d"), "body_3d");  // a token must not start with a digit
  EXPECT_EQ(ros2_name_token("/robot/base"), "robot_base");
  EXPECT_EQ(ros2_name_token("caf\xc3\xa9"), "caf");
  EXPECT_EQ(ros2_name_token(""), "body");
  EXPECT_EQ(ros2_name_token("--"), "body");
}

TEST(Ros2Messages, CarryTheFramesStampsNamesAndValues) {
  session::Ros2Settings settings;
  settings.frame_id = "map";
  settings.child_frame_prefix = "mocap/";
  const Ros2Messages messages(settings);
  session::FrameOutput frame = test_frame(42, -1'700'000'000);
  frame.bodies[0].pose.horizon_ns = 50'000'000;  // predicted ahead: stamped at stamp + horizon

  geometry::PoseStamped_ pose;
  messages.pose(frame.bodies[0], pose);
  EXPECT_EQ(pose.header().stamp().sec(), -2);
  EXPECT_EQ(pose.header().stamp().nanosec(), 350'000'000U);
  EXPECT_EQ(pose.header().frame_id(), "map");
  EXPECT_EQ(pose.pose().position().y(), -1.25);
  EXPECT_EQ(pose.pose().orientation().x(), 0.1);  // x, y, z, w
  EXPECT_EQ(pose.pose().orientation().w(), frame.bodies[0].pose.q[3]);

  geometry::TwistStamped_ twist;
  messages.twist(frame.bodies[0], twist);
  EXPECT_EQ(twist.header().stamp().nanosec(), 350'000'000U);
  EXPECT_EQ(twist.twist().linear().z(), 3.0);
  EXPECT_EQ(twist.twist().angular().x(), -0.1);

  tf2_msgs::msg::dds_::TFMessage_ tf;
  messages.transforms(frame, {"head", "tool"}, tf);
  ASSERT_EQ(tf.transforms().size(), 1U);  // only tracked bodies
  EXPECT_EQ(tf.transforms()[0].header().frame_id(), "map");
  EXPECT_EQ(tf.transforms()[0].child_frame_id(), "mocap/head");
  EXPECT_EQ(tf.transforms()[0].transform().translation().x(), 0.5);
  EXPECT_EQ(tf.transforms()[0].transform().rotation().z(), 0.3);

  mocap::RigidBodies_ bodies;
  messages.rigid_bodies(frame, bodies);
  EXPECT_EQ(bodies.frame_number(), 42U);
  EXPECT_EQ(bodies.header().stamp().nanosec(), 350'000'000U);
  ASSERT_EQ(bodies.rigidbodies().size(), 1U);
  const mocap::RigidBody_& head = bodies.rigidbodies()[0];
  EXPECT_EQ(head.rigid_body_name(), "head");
  EXPECT_EQ(head.pose().position().z(), 1.75);
  ASSERT_EQ(head.markers().size(), 2U);
  EXPECT_EQ(head.markers()[0].id_type(), kMarkerUseBoth);
  EXPECT_EQ(head.markers()[0].marker_index(), 3);
  EXPECT_EQ(head.markers()[0].marker_name(), "head/3");
  EXPECT_EQ(head.markers()[1].marker_name(), "head/0");
  EXPECT_EQ(head.markers()[1].translation().x(), 0.6);

  mocap::Markers_ markers;
  messages.markers(frame, markers);
  EXPECT_EQ(markers.frame_number(), 42U);
  EXPECT_EQ(markers.header().stamp().sec(), -2);  // markers: the capture stamp itself
  EXPECT_EQ(markers.header().stamp().nanosec(), 300'000'000U);
  ASSERT_EQ(markers.markers().size(), 3U);
  EXPECT_EQ(markers.markers()[0].marker_name(), "head/3");
  EXPECT_EQ(markers.markers()[2].id_type(), kMarkerUseIndex);
  EXPECT_EQ(markers.markers()[2].marker_index(), 77);
  EXPECT_EQ(markers.markers()[2].marker_name(), "");
  EXPECT_EQ(markers.markers()[2].translation().y(), 2.5);

  // Reused messages shrink with the frame: no stale bodies or markers.
  frame.bodies[0].tracking_valid = false;
  frame.markers.resize(1);
  messages.transforms(frame, {"head", "tool"}, tf);
  messages.rigid_bodies(frame, bodies);
  messages.markers(frame, markers);
  EXPECT_TRUE(tf.transforms().empty());
  EXPECT_TRUE(bodies.rigidbodies().empty());
  EXPECT_EQ(markers.markers().size(), 1U);
}

using panoptes::test::wait_until;

// What a reader of one topic with one QoS received.
struct Received {
  std::mutex mutex;
  std::vector<std::string> frame_ids;
  std::vector<std::int64_t> stamps_ns;
  std::vector<std::string> names;  // child frames, rigid bodies, marker names
  std::size_t count() {
    std::lock_guard lock(mutex);
    return stamps_ns.size();
  }
  void add(const std_msgs::msg::dds_::Header_& header, const std::string& name) {
    std::lock_guard lock(mutex);
    frame_ids.push_back(header.frame_id());
    stamps_ns.push_back(static_cast<std::int64_t>(header.stamp().sec()) * 1'000'000'000 +
                        header.stamp().nanosec());
    names.push_back(name);
  }
};

// A subject's segments (docs/marker_sets.md, "Segment poses live") form one tf tree: the root
// from the world frame, each child relative to its parent; a child whose parent has no pose in the
// frame is left out, not hung from the world.
TEST(Ros2Messages, SegmentsFormOneTfTreePerSubject) {
  session::Ros2Settings settings;
  settings.child_frame_prefix = "mocap/";
  const Ros2Messages messages(settings);
  session::FrameOutput frame = test_frame(7, 1'000'000'000);
  const Eigen::Quaterniond q_pelvis(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()));
  const Eigen::Quaterniond q_thigh(Eigen::AngleAxisd(-0.4, Eigen::Vector3d(1.0, -0.5, 0.1).normalized()));
  const auto segment = [&](const std::string& name, const std::string& parent, const Eigen::Vector3d& p,
                           const Eigen::Quaterniond& q, bool valid) {
    session::BodyOutput body;
    body.name = name;
    body.segment = true;
    body.parent = parent;
    body.tracking_valid = valid;
    body.pose.stamp_ns = frame.stamp_ns;
    body.pose.p = p;
    body.pose.q = Eigen::Vector4d(q.x(), q.y(), q.z(), q.w());
    frame.bodies.push_back(body);
  };
  segment("s1/Pelvis", "", {1.0, 2.0, 0.9}, q_pelvis, true);
  segment("s1/R.Thigh", "s1/Pelvis", {1.1, 1.9, 0.5}, q_thigh, true);
  segment("s1/R.Shank", "s1/R.Thigh", {1.1, 1.9, 0.1}, q_thigh, false);
  segment("s1/R.Foot", "s1/R.Shank", {1.2, 1.9, 0.0}, q_thigh, true);  // its parent untracked
  tf2_msgs::msg::dds_::TFMessage_ tf;
  messages.transforms(frame, {"head", "tool", "s1_Pelvis", "s1_R_Thigh", "s1_R_Shank", "s1_R_Foot"}, tf);
  ASSERT_EQ(tf.transforms().size(), 3U);  // head, pelvis, thigh
  const auto& pelvis = tf.transforms()[1];
  EXPECT_EQ(pelvis.header().frame_id(), "world");
  EXPECT_EQ(pelvis.child_frame_id(), "mocap/s1_Pelvis");
  EXPECT_EQ(pelvis.transform().translation().z(), 0.9);
  const auto& thigh = tf.transforms()[2];
  EXPECT_EQ(thigh.header().frame_id(), "mocap/s1_Pelvis");
  EXPECT_EQ(thigh.child_frame_id(), "mocap/s1_R_Thigh");
  // Composing the parent's world pose with the relative one gives the child's world pose back.
  const auto& t = thigh.transform();
  const Eigen::Quaterniond q_relative(t.rotation().w(), t.rotation().x(), t.rotation().y(), t.rotation().z());
  const Eigen::Vector3d p_relative(t.translation().x(), t.translation().y(), t.translation().z());
  const Eigen::Vector3d p_world = q_pelvis * p_relative + Eigen::Vector3d(1.0, 2.0, 0.9);
  EXPECT_LT((p_world - Eigen::Vector3d(1.1, 1.9, 0.5)).norm(), 1e-12);
  EXPECT_LT((q_pelvis * q_relative).angularDistance(q_thigh), 1e-12);
}

TEST(Ros2Outputs, BestEffortAndReliableReadersReceiveEveryTopic) {
  dds::Bus estimator(bus_options("estimator")), application(bus_options("ros2_application"));
  session::Ros2Settings settings;
  settings.child_frame_prefix = "mocap/";
  Ros2Outputs outputs(estimator, settings);
  outputs.publish(test_frame(1, 1'000'000'000));  // creates the per-body writers

  const std::vector<dds::Qos> qos_list = {dds::Qos::kBestEffort, dds::Qos::kDefault};
  std::vector<Received> pose(2), twist(2), tf(2), bodies(2), markers(2);
  std::vector<std::shared_ptr<void>> readers;
  for (std::size_t q = 0; q < qos_list.size(); ++q) {
    readers.push_back(application.make_reader<geometry::PoseStamped_>(
        [&, q](geometry::PoseStamped_&& m) { pose[q].add(m.header(), ""); }, qos_list[q], {},
        "rt/panoptes/head/pose"));
    readers.push_back(application.make_reader<geometry::TwistStamped_>(
        [&, q](geometry::TwistStamped_&& m) { twist[q].add(m.header(), ""); }, qos_list[q], {},
        "rt/panoptes/head/twist"));
    readers.push_back(application.make_reader<tf2_msgs::msg::dds_::TFMessage_>(
        [&, q](tf2_msgs::msg::dds_::TFMessage_&& m) {
          for (const auto& t : m.transforms()) tf[q].add(t.header(), t.child_frame_id());
        },
        qos_list[q], {}, "rt/tf"));
    readers.push_back(application.make_reader<mocap::RigidBodies_>(
        [&, q](mocap::RigidBodies_&& m) {
          bodies[q].add(m.header(), m.rigidbodies().empty() ? "" : m.rigidbodies()[0].rigid_body_name());
        },
        qos_list[q], {}, "rt/rigid_bodies"));
    readers.push_back(application.make_reader<mocap::Markers_>(
        [&, q](mocap::Markers_&& m) {
          markers[q].add(m.header(), m.markers().empty() ? "" : m.markers()[0].marker_name());
        },
        qos_list[q], {}, "rt/markers"));
  }
  const auto all = [&](auto&& predicate) {
    for (auto* topic : {&pose, &twist, &tf, &bodies, &markers}) {
      for (auto& received : *topic) {
        if (!predicate(received)) return false;
      }
    }
    return true;
  };
  // Publish until every reader has matched and received a few frames (discovery takes a moment).
  std::uint64_t frame_number = 2;
  ASSERT_TRUE(wait_until([&] {
    outputs.publish(test_frame(frame_number, static_cast<TimeNs>(frame_number) * 1'000'000'000 + 5));
    ++frame_number;
    std::this_thread::sleep_for(2ms);
    return all([](Received& r) { return r.count() >= 5; });
  })) << "a reader received nothing";
  EXPECT_EQ(outputs.body_tokens().at("head"), "head");
  all([](Received& r) {
    std::lock_guard lock(r.mutex);
    for (std::size_t i = 0; i < r.stamps_ns.size(); ++i) {
      EXPECT_EQ(r.frame_ids[i], "world");
      EXPECT_EQ(r.stamps_ns[i] % 1'000'000'000, 5) << "a frame's stamp, split into sec and nanosec";
    }
    return true;
  });
  std::lock_guard lock(tf[0].mutex);
  EXPECT_EQ(tf[0].names.front(), "mocap/head");
}

TEST(Ros2Outputs, BodyNamesThatAreNotTokensGetUniqueTokens) {
  dds::Bus estimator(bus_options("estimator_names"));
  Ros2Outputs outputs(estimator, session::Ros2Settings{});
  session::FrameOutput frame;
  for (const char* name : {"left hand", "left-hand", "left_hand"}) {
    session::BodyOutput body;
    body.name = name;
    body.id = static_cast<int>(frame.bodies.size()) + 1;
    frame.bodies.push_back(body);
  }
  outputs.publish(frame);
  // The valid name keeps its token; the others map to it, find it taken and get their ids.
  EXPECT_EQ(outputs.body_tokens().at("left_hand"), "left_hand");
  EXPECT_EQ(outputs.body_tokens().at("left hand"), "left_hand_1");
  EXPECT_EQ(outputs.body_tokens().at("left-hand"), "left_hand_2");
  outputs.publish(frame);  // stable from frame to frame
  EXPECT_EQ(outputs.body_tokens().at("left hand"), "left_hand_1");
}

// A 300-character body name (Fast DDS 2.9 accepts the topic; were it refused, that body alone would
// lose its topics): nothing throws and the other bodies are published.
TEST(Ros2Outputs, AnOverlongBodyNameDoesNotStopTheOthers) {
  dds::Bus estimator(bus_options("estimator_long")), application(bus_options("ros2_application_long"));
  Ros2Outputs outputs(estimator, session::Ros2Settings{});
  session::FrameOutput frame = test_frame(1, 1'000'000'000);
  session::BodyOutput long_body = frame.bodies[0];
  long_body.name = std::string(300, 'x');
  long_body.id = 3;
  frame.bodies.push_back(long_body);
  std::atomic<int> received{0};
  auto reader = application.make_reader<geometry::PoseStamped_>(
      [&](geometry::PoseStamped_&&) { ++received; }, dds::Qos::kDefault, {}, "rt/panoptes/head/pose");
  EXPECT_TRUE(wait_until([&] {
    EXPECT_NO_THROW(outputs.publish(frame));
    std::this_thread::sleep_for(2ms);
    return received.load() > 0;
  }));
}

}  // namespace
}  // namespace panoptes::estimator_app
