// SPDX-License-Identifier: Apache-2.0
// The /tf rate limit (ros2.tf_rate_hz) and the ROS 2 namespace (ros2.namespace) of estimator_node's
// ROS 2 topics (docs/ros2.md): the limit's rate on fixed-rate and per-camera stamps over a simulated
// minute, the namespace on every topic name and on the wire, and the namespace's validation.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../dds_test_support.h"
#include "panoptes/dds/bus.h"
#include "panoptes/estimator_app/ros2_outputs.h"
#include "panoptes/session/estimator_config.h"
#include "panoptes/session/frame_clock.h"
#include "ros2_test_frames.h"

namespace panoptes::estimator_app {
namespace {

using namespace std::chrono_literals;
namespace geometry = geometry_msgs::msg::dds_;
namespace mocap = mocap4r2_msgs::msg::dds_;

constexpr TimeNs kStart = 1'795'472'027'022'242'760;  // a capture clock stamp (2026)
constexpr TimeNs kMinute = 60'000'000'000;

// How many of `stamps` a limit of `rate_hz` lets through, and the most it let through in any one
// second of the capture clock.
struct Admitted {
  std::size_t total = 0;
  std::size_t max_per_second = 0;
  std::size_t min_per_second = 0;  // over the whole seconds inside the run
};

Admitted admit_all(int rate_hz, const std::vector<TimeNs>& stamps) {
  RateLimiter limit(rate_hz);
  std::map<TimeNs, std::size_t> per_second;
  Admitted out;
  for (const TimeNs stamp : stamps) {
    if (!limit.admit(stamp)) continue;
    ++out.total;
    ++per_second[stamp / 1'000'000'000];
  }
  out.min_per_second = std::numeric_limits<std::size_t>::max();
  for (auto it = per_second.begin(); it != per_second.end(); ++it) {
    out.max_per_second = std::max(out.max_per_second, it->second);
    if (it != per_second.begin() && std::next(it) != per_second.end())
      out.min_per_second = std::min(out.min_per_second, it->second);
  }
  return out;
}

// The fixed-rate frames' instants (session::FrameClock) over a minute.
std::vector<TimeNs> fixed_rate_stamps(int frame_rate_hz) {
  const session::FrameClock clock(frame_rate_hz);
  std::vector<TimeNs> stamps;
  const std::int64_t first = clock.index_at(kStart) + 1;
  for (std::int64_t k = first; clock.instant(k) < clock.instant(first) + kMinute; ++k)
    stamps.push_back(clock.instant(k));
  return stamps;
}

// Per-camera frames: free-running cameras at `camera_hz` (one entry each) with their own phase, clock
// error (±100 ppm) and jitter (σ 0.2 ms), merged in the order they would reach the estimator (by
// stamp plus a random 0–3 ms of transport, so neighbours can come out of stamp order).
std::vector<TimeNs> per_camera_stamps(const std::vector<double>& camera_hz, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> jitter_ns(0.0, 2e5);
  std::vector<std::pair<TimeNs, TimeNs>> arrivals;  // (arrival, stamp)
  for (const double hz : camera_hz) {
    const double period_ns = 1e9 / hz * (1.0 + (unit(random) - 0.5) * 2e-4);
    const double phase_ns = unit(random) * period_ns;
    for (double t = phase_ns; t < static_cast<double>(kMinute); t += period_ns) {
      const TimeNs stamp = kStart + static_cast<TimeNs>(t + jitter_ns(random));
      arrivals.emplace_back(stamp + static_cast<TimeNs>(unit(random) * 3e6), stamp);
    }
  }
  std::sort(arrivals.begin(), arrivals.end());
  std::vector<TimeNs> stamps;
  for (const auto& [arrival, stamp] : arrivals) stamps.push_back(stamp);
  return stamps;
}

// The acceptance is ±5 % of the limit. Never more than `rate_hz` frames in a second of the capture
// clock (the grid has exactly `rate_hz` periods in each); on a fixed-rate grid exactly `rate_hz`.
void expect_rate(const Admitted& admitted, int rate_hz, bool exact, const std::string& what) {
  const double per_second = static_cast<double>(admitted.total) / 60.0;
  std::printf("%s: %.3f per second over the minute, %zu..%zu in a whole second\n", what.c_str(), per_second,
              admitted.min_per_second, admitted.max_per_second);
  EXPECT_NEAR(per_second, rate_hz, 0.05 * rate_hz) << what;
  EXPECT_LE(admitted.max_per_second, static_cast<std::size_t>(rate_hz)) << what;
  EXPECT_GE(static_cast<double>(admitted.min_per_second), 0.95 * rate_hz) << what;
  if (exact) {
    EXPECT_NEAR(per_second, rate_hz, 1.0 / 60.0 + 1e-9) << what << ": not exact";
    EXPECT_EQ(admitted.min_per_second, static_cast<std::size_t>(rate_hz)) << what;
  }
}

TEST(Ros2TfRate, IsExactOnTheFixedRateGrid) {
  const std::vector<TimeNs> grid240 = fixed_rate_stamps(240);
  ASSERT_EQ(grid240.size(), 240U * 60U);
  for (const int limit : {1, 30, 60, 100, 120, 240})
    expect_rate(admit_all(limit, grid240), limit, true, "240 Hz frames, limit " + std::to_string(limit));
  // A limit at or above the frame rate lets every frame through; 0 is no limit.
  EXPECT_EQ(admit_all(240, grid240).total, grid240.size());
  EXPECT_EQ(admit_all(1000, grid240).total, grid240.size());
  EXPECT_EQ(admit_all(0, grid240).total, grid240.size());
  // The default rate (120 Hz) on the default fixed rate (120 Hz): every frame.
  const std::vector<TimeNs> grid120 = fixed_rate_stamps(session::NodeSettings{}.frame_rate_hz);
  EXPECT_EQ(admit_all(session::Ros2Settings{}.tf_rate_hz, grid120).total, grid120.size());
}

TEST(Ros2TfRate, IsExactOnIrregularPerCameraStamps) {
  // The clients scene: 4 cameras at 240 Hz, 960 frames/s spaced irregularly and out of order.
  const std::vector<TimeNs> stamps = per_camera_stamps({240, 240, 240, 240}, 7);
  ASSERT_GT(stamps.size(), 4U * 240U * 59U);
  ASSERT_FALSE(std::is_sorted(stamps.begin(), stamps.end())) << "the test wants stamps out of order";
  for (const int limit : {30, 100, 120, 240})
    expect_rate(admit_all(limit, stamps), limit, false, "4 x 240 Hz cameras, limit " + std::to_string(limit));
  // The clients scene's six cameras at 90..120 Hz (deploy/scenes/clients.yaml), about 620 frames/s.
  const std::vector<TimeNs> clients = per_camera_stamps({90, 100, 110, 120, 95, 105}, 3);
  for (const int limit : {60, 100, 120})
    expect_rate(admit_all(limit, clients), limit, false, "clients scene, limit " + std::to_string(limit));
  // Fewer frames than periods: every frame in a period of its own passes, never more than the rate.
  const std::vector<TimeNs> sparse = per_camera_stamps({60}, 11);
  const Admitted admitted = admit_all(120, sparse);
  EXPECT_GE(admitted.total, sparse.size() * 95 / 100);
  EXPECT_LE(admitted.max_per_second, 120U);
}

TEST(Ros2TfRate, HoldsBackOlderFramesAndRestartsAfterAClockStepBack) {
  RateLimiter limit(100);  // 10 ms periods
  EXPECT_TRUE(limit.admit(kStart));
  EXPECT_FALSE(limit.admit(kStart + 1'000'000));     // same period
  EXPECT_FALSE(limit.admit(kStart - 30'000'000));    // older than the last one let through
  EXPECT_TRUE(limit.admit(kStart + 10'000'000));     // the next period
  EXPECT_TRUE(limit.admit(kStart - 5'000'000'000));  // 5 s back: the grid starts anew
  EXPECT_FALSE(limit.admit(kStart - 5'000'000'000 + 1));
  EXPECT_TRUE(limit.admit(kStart - 4'990'000'000));
  RateLimiter none(0);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(none.admit(kStart));
}

TEST(Ros2Namespace, IsAppliedToEveryTopicButTf) {
  const Ros2TopicNames none("");
  EXPECT_EQ(none.tf, "rt/tf");
  EXPECT_EQ(none.rigid_bodies, "rt/rigid_bodies");
  EXPECT_EQ(none.markers, "rt/markers");
  EXPECT_EQ(none.body("head", "pose"), "rt/panoptes/head/pose");
  EXPECT_EQ(Ros2TopicNames("/").rigid_bodies, "rt/rigid_bodies");
  for (const char* ns : {"/lab1", "lab1"}) {
    const Ros2TopicNames names(ns);
    EXPECT_EQ(names.tf, "rt/tf") << ns;
    EXPECT_EQ(names.rigid_bodies, "rt/lab1/rigid_bodies") << ns;
    EXPECT_EQ(names.markers, "rt/lab1/markers") << ns;
    EXPECT_EQ(names.body("head", "pose"), "rt/lab1/panoptes/head/pose") << ns;
    EXPECT_EQ(names.body("tool", "twist"), "rt/lab1/panoptes/tool/twist") << ns;
  }
  EXPECT_EQ(Ros2TopicNames("/site_a/room2").markers, "rt/site_a/room2/markers");
}

TEST(Ros2Namespace, FollowsTheRos2NameRules) {
  for (const char* good : {"", "/", "/lab1", "lab1", "/site_a/room_2", "/A/b9", "/_x"})
    EXPECT_EQ(session::check_ros2_namespace(good), "") << good;
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"/lab1/", "must not end with '/'"},
      {"//lab1", "must not contain '//'"},
      {"/a//b", "must not contain '//'"},
      {"/lab 1", "hold only"},
      {"/lab-1", "hold only"},
      {"/~/x", "hold only"},
      {"/{node}", "hold only"},
      {"/caf\xc3\xa9", "hold only"},
      {"/1lab", "must not start with a digit"},
      {"/lab/2nd", "must not start with a digit"},
      {"/a__b", "must not contain '__'"},
      {"/" + std::string(session::kMaxRos2NamespaceLength, 'a'), "at most 200 characters"},
  };
  for (const auto& [ns, reason] : bad) {
    const std::string why = session::check_ros2_namespace(ns);
    EXPECT_NE(why.find(reason), std::string::npos) << ns << ": " << why;
  }
}

// On the wire: with ros2.namespace /lab1 every ROS 2 topic but /tf is under /lab1 (readers of the
// namespaced names receive), and nothing goes to the names without it.
TEST(Ros2Namespace, EveryTopicIsNamespacedOnTheWire) {
  dds::Bus estimator(bus_options("estimator_ns")), application(bus_options("ros2_application_ns"));
  session::Ros2Settings settings;
  settings.topic_namespace = "/lab1";
  Ros2Outputs outputs(estimator, settings);
  outputs.publish(test_frame(1, kStart));  // creates the per-body writers
  std::map<std::string, std::atomic<int>> received;
  std::vector<std::shared_ptr<void>> readers;
  for (const std::string prefix : {"rt/lab1", "rt"}) {
    const auto count = [&received](const std::string& topic) {
      return [&received, topic](auto&&) { ++received.at(topic); };
    };
    for (const char* what : {"pose", "twist"}) {
      const std::string topic = prefix + "/panoptes/head/" + what;
      received[topic] = 0;
      if (std::string(what) == "pose")
        readers.push_back(
            application.make_reader<geometry::PoseStamped_>(count(topic), dds::Qos::kDefault, {}, topic));
      else
        readers.push_back(
            application.make_reader<geometry::TwistStamped_>(count(topic), dds::Qos::kDefault, {}, topic));
    }
    received[prefix + "/rigid_bodies"] = 0;
    received[prefix + "/markers"] = 0;
    readers.push_back(application.make_reader<mocap::RigidBodies_>(
        count(prefix + "/rigid_bodies"), dds::Qos::kDefault, {}, prefix + "/rigid_bodies"));
    readers.push_back(application.make_reader<mocap::Markers_>(count(prefix + "/markers"), dds::Qos::kDefault,
                                                               {}, prefix + "/markers"));
  }
  received["rt/tf"] = 0;
  readers.push_back(application.make_reader<tf2_msgs::msg::dds_::TFMessage_>(
      [&received](auto&&) { ++received.at("rt/tf"); }, dds::Qos::kDefault, {}, "rt/tf"));
  const std::vector<std::string> namespaced = {"rt/lab1/panoptes/head/pose", "rt/lab1/panoptes/head/twist",
                                               "rt/lab1/rigid_bodies", "rt/lab1/markers", "rt/tf"};
  std::uint64_t frame_number = 2;
  ASSERT_TRUE(panoptes::test::wait_until([&] {
    outputs.publish(test_frame(frame_number, kStart + static_cast<TimeNs>(frame_number) * 100'000'000));
    ++frame_number;
    std::this_thread::sleep_for(2ms);
    return std::all_of(namespaced.begin(), namespaced.end(),
                       [&received](const std::string& topic) { return received[topic].load() >= 3; });
  })) << "a namespaced topic received nothing";
  for (const char* topic :
       {"rt/panoptes/head/pose", "rt/panoptes/head/twist", "rt/rigid_bodies", "rt/markers"})
    EXPECT_EQ(received[topic].load(), 0) << topic << " was published without the namespace";
}

}  // namespace
}  // namespace panoptes::estimator_app
