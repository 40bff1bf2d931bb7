// SPDX-License-Identifier: Apache-2.0
// panoptes_ros2_probe: a ROS 2 application on the wire without ROS (integration/test_ros2_topics.sh).
// Subscribes to the estimator's ROS 2 topics (docs/ros2.md) twice, as a ROS 2 SensorDataQoS
// subscriber would (best effort) and as a default one (reliable), and records one JSON line per
// sample received: the topic, the reader's QoS, header stamp and frame id, and the values a test
// compares with the estimator's own Pose JSONL and the simulator's truth.
#include <cstdio>
#include <exception>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/ros2.h"

namespace {

namespace geometry = geometry_msgs::msg::dds_;
namespace mocap = mocap4r2_msgs::msg::dds_;
using nlohmann::json;

json header_json(const std_msgs::msg::dds_::Header_& header) {
  return {
      {"sec", header.stamp().sec()}, {"nanosec", header.stamp().nanosec()}, {"frame_id", header.frame_id()}};
}

json marker_json(const mocap::Marker_& marker) {
  return {{"id_type", marker.id_type()},
          {"index", marker.marker_index()},
          {"name", marker.marker_name()},
          {"p", {marker.translation().x(), marker.translation().y(), marker.translation().z()}}};
}

json to_json(const geometry::PoseStamped_& m) {
  const auto& p = m.pose().position();
  const auto& q = m.pose().orientation();
  return {
      {"header", header_json(m.header())}, {"p", {p.x(), p.y(), p.z()}}, {"q", {q.x(), q.y(), q.z(), q.w()}}};
}

json to_json(const geometry::TwistStamped_& m) {
  const auto& v = m.twist().linear();
  const auto& w = m.twist().angular();
  return {{"header", header_json(m.header())}, {"v", {v.x(), v.y(), v.z()}}, {"w", {w.x(), w.y(), w.z()}}};
}

json to_json(const tf2_msgs::msg::dds_::TFMessage_& m) {
  json transforms = json::array();
  for (const auto& t : m.transforms()) {
    const auto& p = t.transform().translation();
    const auto& q = t.transform().rotation();
    transforms.push_back({{"header", header_json(t.header())},
                          {"child_frame_id", t.child_frame_id()},
                          {"p", {p.x(), p.y(), p.z()}},
                          {"q", {q.x(), q.y(), q.z(), q.w()}}});
  }
  return {{"transforms", transforms}};
}

json to_json(const mocap::RigidBodies_& m) {
  json bodies = json::array();
  for (const auto& body : m.rigidbodies()) {
    json markers = json::array();
    for (const auto& marker : body.markers()) markers.push_back(marker_json(marker));
    const auto& p = body.pose().position();
    const auto& q = body.pose().orientation();
    bodies.push_back({{"name", body.rigid_body_name()},
                      {"markers", markers},
                      {"p", {p.x(), p.y(), p.z()}},
                      {"q", {q.x(), q.y(), q.z(), q.w()}}});
  }
  return {{"header", header_json(m.header())}, {"frame_number", m.frame_number()}, {"rigidbodies", bodies}};
}

json to_json(const mocap::Markers_& m) {
  json markers = json::array();
  for (const auto& marker : m.markers()) markers.push_back(marker_json(marker));
  return {{"header", header_json(m.header())}, {"frame_number", m.frame_number()}, {"markers", markers}};
}

// The readers' callbacks only queue the sample; the main loop formats and writes them, so the JSON
// does not hold the participant's receive thread. On a loaded two-core machine the best-effort
// reader of rt/tf still lost 9-21 % of its samples with this (the reliable one had them resent):
// the loss is not only the probe's (test_ros2_topics' bound for it).
class Recorder {
 public:
  explicit Recorder(std::ofstream& out) : out_(out) {}

  template <class T>
  void subscribe(panoptes::dds::Bus& bus, const std::string& topic) {
    for (const auto qos : {panoptes::dds::Qos::kBestEffort, panoptes::dds::Qos::kDefault}) {
      const std::string qos_name = qos == panoptes::dds::Qos::kBestEffort ? "best_effort" : "reliable";
      readers_.push_back(bus.make_reader<T>(
          [this, topic, qos_name](T&& message) {
            const panoptes::TimeNs recv_ns = panoptes::wall_now_ns();
            auto sample = std::make_shared<T>(std::move(message));
            std::lock_guard lock(mutex_);
            pending_.emplace_back([sample, topic, qos_name, recv_ns] {
              json line = to_json(*sample);
              line["topic"] = topic;
              line["qos"] = qos_name;
              line["recv_ns"] = recv_ns;
              return line.dump();
            });
          },
          qos, {}, topic));
    }
  }

  // Stops the readers and writes what they queued.
  void close() {
    readers_.clear();
    flush();
  }

  // Writes the samples queued since the last call.
  void flush() {
    std::vector<std::function<std::string()>> batch;
    {
      std::lock_guard lock(mutex_);
      batch.swap(pending_);
    }
    for (const auto& line : batch) out_ << line() << '\n';
    out_.flush();
  }

 private:
  std::ofstream& out_;
  std::mutex mutex_;
  std::vector<std::function<std::string()>> pending_;
  std::vector<std::shared_ptr<void>> readers_;
};

int run(int argc, char** argv) {
  std::string out_file;
  std::string dds_profile;
  double duration_s = 0;
  std::vector<std::string> bodies;
  std::vector<std::string> namespaces = {"/"};
  CLI::App app{"panoptes_ros2_probe: records the estimator's ROS 2 topics (best-effort and reliable readers)",
               "panoptes_ros2_probe"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--out", out_file, "JSONL file to write")->required();
  app.add_option("--body", bodies, "body name tokens whose pose and twist topics to read")->expected(0, -1);
  app.add_option("--dds-profile", dds_profile, "Fast DDS XML profile")
      ->default_str("$PANOPTES_DDS_PROFILE or deploy/dds/loopback.xml");
  app.add_option("--duration", duration_s, "stop after this many seconds (0 = until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_option(
         "--namespace", namespaces,
         "ROS 2 namespaces ('/' for none) whose rigid_bodies, markers and body topics to read; /tf is "
         "global (estimator_node --ros2-namespace, docs/ros2.md)")
      ->expected(1, -1);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();

  std::ofstream out(out_file);
  if (!out) {
    std::fprintf(stderr, "panoptes_ros2_probe: cannot write %s\n", out_file.c_str());
    return panoptes::kExitBadInput;
  }
  try {
    panoptes::dds::BusOptions options;
    options.profile_file = dds_profile;
    options.participant_name = "panoptes_ros2_probe";
    panoptes::dds::Bus bus(options);
    Recorder recorder(out);
    recorder.subscribe<tf2_msgs::msg::dds_::TFMessage_>(bus, "rt/tf");
    for (const auto& ns : namespaces) {
      const std::string prefix = ns == "/" ? "rt" : "rt" + ns;
      recorder.subscribe<mocap::RigidBodies_>(bus, prefix + "/rigid_bodies");
      recorder.subscribe<mocap::Markers_>(bus, prefix + "/markers");
      for (const auto& body : bodies) {
        std::string topic = prefix;
        topic.append("/panoptes/").append(body);
        recorder.subscribe<geometry::PoseStamped_>(bus, topic + "/pose");
        recorder.subscribe<geometry::TwistStamped_>(bus, topic + "/twist");
      }
    }
    std::fprintf(stderr, "panoptes_ros2_probe: recording to %s\n", out_file.c_str());
    const panoptes::TimeNs end = panoptes::wall_now_ns() + panoptes::seconds_to_ns(duration_s);
    while (!panoptes::stop_requested() && (duration_s <= 0 || panoptes::wall_now_ns() < end)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      recorder.flush();
    }
    recorder.close();
  } catch (const panoptes::InputError& error) {  // e.g. $PANOPTES_DOMAIN=abc, the DDS profile, Security files
    std::fprintf(stderr, "panoptes_ros2_probe: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_ros2_probe: %s\n", error.what());
    return panoptes::kExitFailure;
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_ros2_probe", [&] { return run(argc, argv); });
}
