// SPDX-License-Identifier: Apache-2.0
// bench_ros2_outputs: CPU cost of estimator_node's ROS 2 publishers (issue 15, docs/ros2.md) at
// 4 cameras x 240 Hz = 960 processed frames/s with 2 bodies, side by side with the native
// rt/panoptes/frames (MocapFrame) write of the same frames in the same run, as JSON
// (docs/ros2.md, "Cost of the ROS 2 publishers").
//
// Frames are paced in real time at --rate. Each phase lasts --seconds:
//   idle         no writes (the process's DDS threads only): the baseline
//   native       per frame: to_frame_message + MocapFrame write
//   native+ros2  per frame: the same, then Ros2Outputs::publish
// first with no subscriber, then with a subscriber process (this program, --subscriber) reading
// rt/panoptes/frames and every ROS 2 topic with best-effort readers (ROS 2 SensorDataQoS), then with
// one reading them reliably (ROS 2's default QoS). Per call, the CPU time (and wall time) of the call on the
// estimator-like thread; per phase, the CPU time of the whole process (getrusage), which includes Fast DDS's
// own threads (e.g. receiving the reliable readers' acknowledgements). % of one core = CPU seconds per
// second.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/estimator_app/frame_messages.h"
#include "panoptes/estimator_app/ros2_outputs.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/ros2.h"

namespace {

using nlohmann::json;
using panoptes::TimeNs;
namespace app = panoptes::estimator_app;
namespace session = panoptes::session;

// The clients scene's bodies (deploy/scenes/clients.yaml): "head" with 4 markers, "tool" with 5, and
// 2 loose markers; all tracked.
const std::vector<std::pair<std::string, int>> kBodies = {{"head", 4}, {"tool", 5}};
constexpr int kLooseMarkers = 2;

// The FrameOutput of frame `k` (camera k % cameras), bodies moving on circles.
session::FrameOutput make_frame(std::uint64_t k, TimeNs stamp_ns, int cameras) {
  session::FrameOutput frame;
  frame.frame_number = k + 1;
  frame.stamp_ns = stamp_ns;
  frame.source_camera = "c" + std::to_string(k % static_cast<std::uint64_t>(cameras));
  frame.source_frame = static_cast<std::int64_t>(k / static_cast<std::uint64_t>(cameras));
  const double t = panoptes::ns_to_seconds(stamp_ns % (1000 * panoptes::kNsPerSecond));
  std::int64_t track_id = 1;
  for (std::size_t b = 0; b < kBodies.size(); ++b) {
    session::BodyOutput body;
    body.name = kBodies[b].first;
    body.id = static_cast<int>(b) + 1;
    body.tracking_valid = true;
    body.pose.stamp_ns = stamp_ns;
    body.pose.body = body.name;
    const double phase = t + static_cast<double>(b);
    body.pose.p = {std::cos(phase), std::sin(phase), 1.0 + 0.1 * static_cast<double>(b)};
    body.pose.q = {0.0, 0.0, std::sin(phase / 2), std::cos(phase / 2)};
    body.pose.v = {-std::sin(phase), std::cos(phase), 0.0};
    body.pose.w = {0.0, 0.0, 1.0};
    body.pose.quality = 1.0;
    body.pose.cameras = cameras;
    body.labelled_markers = kBodies[b].second;
    for (int m = 0; m < kBodies[b].second; ++m) {
      session::MarkerOutput marker;
      marker.track.stamp_ns = stamp_ns;
      marker.track.id = track_id++;
      marker.track.p = body.pose.p + Eigen::Vector3d(0.05 * m, 0.03 * m, 0.01 * m);
      marker.track.cameras = cameras;
      marker.body = body.name;
      marker.body_marker = m;
      frame.markers.push_back(marker);
    }
    frame.bodies.push_back(body);
  }
  for (int m = 0; m < kLooseMarkers; ++m) {
    session::MarkerOutput marker;
    marker.track.stamp_ns = stamp_ns;
    marker.track.id = track_id++;
    marker.track.p = {0.5 * m, -0.5, 0.2};
    frame.markers.push_back(marker);
  }
  return frame;
}

double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

TimeNs thread_cpu_ns() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<TimeNs>(t.tv_sec) * panoptes::kNsPerSecond + t.tv_nsec;
}

// Per call: its CPU time on the calling thread (what the estimator thread spends) and its wall time
// (which also counts being preempted, e.g. by the subscriber that a write woke up on 2 cores).
struct CallTimes {
  std::vector<double> cpu_us;
  std::vector<double> wall_us;
  double cpu_s = 0;

  template <class Call>
  void time(Call&& call) {
    const TimeNs wall0 = panoptes::wall_now_ns();
    const TimeNs cpu0 = thread_cpu_ns();
    call();
    const TimeNs cpu = thread_cpu_ns() - cpu0;
    const TimeNs wall = panoptes::wall_now_ns() - wall0;
    cpu_us.push_back(static_cast<double>(cpu) * 1e-3);
    wall_us.push_back(static_cast<double>(wall) * 1e-3);
    cpu_s += panoptes::ns_to_seconds(cpu);
  }

  static double at(const std::vector<double>& sorted, double q) {
    return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))];
  }

  json summary(double phase_s) {
    if (cpu_us.empty()) return nullptr;
    std::sort(cpu_us.begin(), cpu_us.end());
    std::sort(wall_us.begin(), wall_us.end());
    return {
        {"calls", cpu_us.size()},          {"cpu_mean_us", cpu_s * 1e6 / static_cast<double>(cpu_us.size())},
        {"cpu_p50_us", at(cpu_us, 0.5)},   {"cpu_p99_us", at(cpu_us, 0.99)},
        {"wall_p50_us", at(wall_us, 0.5)}, {"wall_p99_us", at(wall_us, 0.99)},
        {"wall_max_us", wall_us.back()},   {"percent_of_one_core", 100.0 * cpu_s / phase_s}};
  }
};

struct Publisher {
  panoptes::dds::Bus& bus;
  std::unique_ptr<panoptes::dds::Writer<panoptes::msg::MocapFrame>> frames;
  app::Ros2Outputs ros2;
  std::uint64_t k = 0;
  TimeNs first_stamp_ns = panoptes::wall_now_ns();
};

// One phase: `write_native` and `write_ros2` select what each frame does.
json run_phase(Publisher& p, const std::string& name, bool write_native, bool write_ros2, double seconds,
               double rate_hz, int cameras) {
  CallTimes native, ros2;
  const auto period = std::chrono::nanoseconds(static_cast<TimeNs>(1e9 / rate_hz));
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_s();
  auto next = start;
  const auto end = start + std::chrono::nanoseconds(panoptes::seconds_to_ns(seconds));
  std::uint64_t frames = 0;
  while (next < end && !panoptes::stop_requested()) {
    std::this_thread::sleep_until(next);
    next += period;
    const TimeNs stamp_ns = p.first_stamp_ns + static_cast<TimeNs>(static_cast<double>(p.k) * 1e9 / rate_hz);
    const session::FrameOutput frame = make_frame(p.k++, stamp_ns, cameras);
    ++frames;
    if (write_native)
      native.time([&] { p.frames->write(app::to_frame_message(frame, panoptes::wall_now_ns())); });
    if (write_ros2) ros2.time([&] { p.ros2.publish(frame); });
  }
  const double phase_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu_s = process_cpu_s() - cpu_start;
  return {{"phase", name},
          {"seconds", phase_s},
          {"frames", frames},
          {"frames_per_s", static_cast<double>(frames) / phase_s},
          {"process_cpu_percent_of_one_core", 100.0 * cpu_s / phase_s},
          {"native_mocapframe_write", native.summary(phase_s)},
          {"ros2_publish", ros2.summary(phase_s)}};
}

json run_phases(Publisher& p, double seconds, double rate_hz, int cameras) {
  json phases = json::array();
  phases.push_back(run_phase(p, "idle", false, false, seconds, rate_hz, cameras));
  phases.push_back(run_phase(p, "native", true, false, seconds, rate_hz, cameras));
  phases.push_back(run_phase(p, "native+ros2", true, true, seconds, rate_hz, cameras));
  const double with = phases[2]["process_cpu_percent_of_one_core"];
  const double without = phases[1]["process_cpu_percent_of_one_core"];
  const double idle = phases[0]["process_cpu_percent_of_one_core"];
  return {{"phases", phases},
          {"ros2_process_cpu_percent_of_one_core", with - without},
          {"native_process_cpu_percent_of_one_core", without - idle},
          {"ros2_publish_percent_of_one_core", phases[2]["ros2_publish"]["percent_of_one_core"]},
          {"native_write_percent_of_one_core", phases[2]["native_mocapframe_write"]["percent_of_one_core"]}};
}

// --subscriber: reads every topic until SIGTERM; prints "ready" once all readers matched, then the
// sample counts as one JSON line.
int run_subscriber(bool best_effort) {
  panoptes::install_stop_handlers();
  panoptes::dds::BusOptions options;
  options.participant_name = "bench_ros2_subscriber";
  panoptes::dds::Bus bus(options);
  const auto qos = best_effort ? panoptes::dds::Qos::kBestEffort : panoptes::dds::Qos::kDefault;
  std::vector<std::string> topics = {"rt/panoptes/frames", "rt/tf", "rt/rigid_bodies", "rt/markers"};
  for (const auto& [body, markers] : kBodies) {
    topics.push_back("rt/panoptes/" + body + "/pose");
    topics.push_back("rt/panoptes/" + body + "/twist");
  }
  std::vector<std::atomic<std::uint64_t>> counts(topics.size());
  std::vector<std::shared_ptr<void>> readers;
  std::vector<std::function<int()>> matched;
  const auto add = [&]<class T>(std::size_t i, T*) {
    auto reader = bus.make_reader<T>([&counts, i](T&&) { counts[i].fetch_add(1); }, qos, {}, topics[i]);
    matched.emplace_back([r = reader.get()] { return r->matched_writers(); });
    readers.push_back(std::move(reader));
  };
  add(0, static_cast<panoptes::msg::MocapFrame*>(nullptr));
  add(1, static_cast<tf2_msgs::msg::dds_::TFMessage_*>(nullptr));
  add(2, static_cast<mocap4r2_msgs::msg::dds_::RigidBodies_*>(nullptr));
  add(3, static_cast<mocap4r2_msgs::msg::dds_::Markers_*>(nullptr));
  for (std::size_t i = 4; i < topics.size(); i += 2) {
    add(i, static_cast<geometry_msgs::msg::dds_::PoseStamped_*>(nullptr));
    add(i + 1, static_cast<geometry_msgs::msg::dds_::TwistStamped_*>(nullptr));
  }
  bool ready = false;
  while (!panoptes::stop_requested()) {
    if (!ready && std::all_of(matched.begin(), matched.end(), [](const auto& m) { return m() > 0; })) {
      ready = true;
      std::printf("ready\n");
      std::fflush(stdout);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  json result = json::object();
  for (std::size_t i = 0; i < topics.size(); ++i) result[topics[i]] = counts[i].load();
  std::printf("%s\n", result.dump().c_str());
  return 0;
}

struct Subscriber {
  pid_t pid = -1;
  FILE* out = nullptr;
};

Subscriber start_subscriber(bool best_effort) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    if (best_effort) {
      execl("/proc/self/exe", "bench_ros2_outputs", "--subscriber", "--best-effort",
            static_cast<char*>(nullptr));
    } else {
      execl("/proc/self/exe", "bench_ros2_outputs", "--subscriber", static_cast<char*>(nullptr));
    }
    _exit(127);
  }
  close(fds[1]);
  return {pid, fdopen(fds[0], "r")};
}

std::string read_line(FILE* in) {
  std::string line;
  for (int c = std::fgetc(in); c != EOF && c != '\n'; c = std::fgetc(in)) line += static_cast<char>(c);
  return line;
}

// Runs the phases with a subscriber process reading every topic with `best_effort` or reliable
// readers; null if it never matched every topic.
json run_with_subscriber(Publisher& p, bool best_effort, double seconds, double rate_hz, int cameras) {
  Subscriber sub = start_subscriber(best_effort);
  if (read_line(sub.out) != "ready") {
    std::fprintf(stderr, "bench_ros2_outputs: the subscriber did not match every topic\n");
    kill(sub.pid, SIGTERM);
    waitpid(sub.pid, nullptr, 0);
    std::fclose(sub.out);
    return nullptr;
  }
  json result = run_phases(p, seconds, rate_hz, cameras);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the last samples arrive
  kill(sub.pid, SIGTERM);
  const std::string counts = read_line(sub.out);
  waitpid(sub.pid, nullptr, 0);
  std::fclose(sub.out);
  result["subscriber_qos"] = best_effort ? "best_effort" : "reliable";
  result["subscriber_received"] = counts.empty() ? json(nullptr) : json::parse(counts);
  const json& phases = result["phases"];
  result["written"] = {
      {"mocapframes", phases[1]["frames"].get<std::uint64_t>() + phases[2]["frames"].get<std::uint64_t>()},
      {"ros2_frames", phases[2]["frames"]}};
  return result;
}

int run(int argc, char** argv) {
  double seconds = 5.0;
  double rate_hz = 960.0;
  int cameras = 4;
  bool subscriber = false;
  bool best_effort = false;
  CLI::App cli{
      "bench_ros2_outputs: CPU cost of the ROS 2 publishers next to the native MocapFrame write (JSON)",
      "bench_ros2_outputs"};
  cli.option_defaults()->always_capture_default();
  cli.add_option("--seconds", seconds, "length of each phase")->check(CLI::PositiveNumber);
  cli.add_option("--rate", rate_hz, "processed frames per second (cameras x camera rate)")
      ->check(CLI::Range(1.0, 100000.0));
  cli.add_option("--cameras", cameras, "cameras the frames come from (source_camera, BodyPose cameras)")
      ->check(CLI::Range(1, 64));
  cli.add_flag("--subscriber", subscriber, "internal: run as the subscriber process");
  cli.add_flag("--best-effort", best_effort, "internal: the subscriber reads best effort");
  if (const auto exit_code = panoptes::parse_command_line(cli, argc, argv)) return *exit_code;
  if (subscriber) return run_subscriber(best_effort);
  panoptes::install_stop_handlers();

  panoptes::dds::BusOptions options;
  options.participant_name = "bench_ros2_outputs";
  panoptes::dds::Bus bus(options);
  session::Ros2Settings settings;
  settings.tf_rate_hz = 0;  // the worst case, and the figures of docs/ros2.md: /tf with every frame
  Publisher p{bus, bus.make_writer<panoptes::msg::MocapFrame>(), app::Ros2Outputs(bus, settings)};
  p.ros2.publish(make_frame(0, p.first_stamp_ns, cameras));  // creates the per-body writers

  json result = {{"rate_hz", rate_hz},
                 {"cameras", cameras},
                 {"bodies", kBodies.size()},
                 {"markers_per_frame", 9 + kLooseMarkers},
                 {"seconds_per_phase", seconds}};
  result["no_subscriber"] = run_phases(p, seconds, rate_hz, cameras);
  result["best_effort_subscriber"] = run_with_subscriber(p, true, seconds, rate_hz, cameras);
  result["reliable_subscriber"] = run_with_subscriber(p, false, seconds, rate_hz, cameras);
  std::printf("%s\n", result.dump(2).c_str());
  return result["best_effort_subscriber"].is_null() || result["reliable_subscriber"].is_null()
             ? panoptes::kExitFailure
             : panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_ros2_outputs", [&] { return run(argc, argv); });
}
