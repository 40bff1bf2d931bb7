// SPDX-License-Identifier: Apache-2.0
// bench_latency: end-to-end latency of the live pipeline on this machine (loopback profile), side by
// side with the DDS floor, as JSON (docs/benchmarks.md, "Distributed deployment").
//
//   pipeline: simulated cameras -> camera_node (render handed over, detection, publish)
//             -> estimator_node (tracker) -> this process, subscribed to rt/panoptes/tracks.
//   (i)  per TrackFrame: its source frame's arrival at camera_node (FeatureFrame.arrival_ns) to the
//        TrackFrame's arrival here; breakdown from the stamps both messages carry and the time
//        this process received the same FeatureFrame (a stand-in for the estimator's reception,
//        same host, same hop).
//   (ii) floor: every FeatureFrame received here is sent again at once, as is, on another DDS
//        domain to an echo process (this program, --role echo), which answers with a TrackFrame
//        of the pipeline's size; two raw DDS hops with the same payloads between two processes,
//        plus that frame's detection time.
//   ratio_vs_dds_floor_p99 = p99(i) / p99(ii).
// All stamps are wall-clock ns on one host (camera nodes synchronise to the estimator's clock, the
// same clock here, so the correction is microseconds).
// The output is TrackFrame for now; rigid-body BodyPose (rt/panoptes/bodies) takes the same path.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/calibration.h"
#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/process.h"
#include "panoptes/simulator.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using panoptes::TimeNs;
namespace msg = panoptes::msg;

constexpr int kFloorDomain = 77;

fs::path executable_path() {
  std::error_code error;
  return fs::read_symlink("/proc/self/exe", error);
}

using Child = panoptes::ChildProcess;

struct Stats {
  std::vector<double> ms;
  void add(TimeNs ns) { ms.push_back(static_cast<double>(ns) * 1e-6); }
  double at(double q) {
    if (ms.empty()) return 0.0;
    std::sort(ms.begin(), ms.end());
    return ms[static_cast<std::size_t>(q * static_cast<double>(ms.size() - 1))];
  }
  nlohmann::json json() { return {{"p50", at(0.5)}, {"p99", at(0.99)}, {"max", at(1.0)}, {"n", ms.size()}}; }
};

struct FeatureSeen {
  TimeNs arrival_ns = 0;     // at camera_node
  TimeNs processing_ns = 0;  // detection
  TimeNs publish_ns = 0;     // written by camera_node
  TimeNs received_ns = 0;    // here
  TimeNs floor_sent_ns = 0;  // re-sent on the floor domain
};

using FrameKey = std::pair<std::string, long long>;

int run_echo(const std::string& profile, double duration_s, int tracks) {
  panoptes::dds::BusOptions options;
  options.profile_file = profile;
  options.domain_id = kFloorDomain;
  options.participant_name = "bench_latency_echo";
  panoptes::dds::Bus bus(options);
  auto writer = bus.make_writer<msg::TrackFrame>();
  std::mutex mutex;
  auto reader = bus.make_reader<msg::FeatureFrame>([&](msg::FeatureFrame&& frame) {
    msg::TrackFrame reply;
    reply.stamp_ns(frame.stamp_ns());
    reply.source_camera(frame.camera_id());
    reply.source_frame(frame.frame());
    reply.tracks().resize(static_cast<std::size_t>(tracks));
    reply.publish_ns(panoptes::wall_now_ns());
    std::lock_guard lock(mutex);
    writer->write(reply);
  });
  const TimeNs end = panoptes::wall_now_ns() + panoptes::seconds_to_ns(duration_s);
  while (!panoptes::stop_requested() && panoptes::wall_now_ns() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path self = executable_path();
  const fs::path bin_dir = self.parent_path();
  std::string scene_file = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/latency240.yaml";
  std::string profile = std::string(PANOPTES_SOURCE_DIR) + "/deploy/dds/loopback.xml";
  std::string role = "bench";
  std::string log_dir;
  double duration_s = 10;
  double warmup_s = 2;
  double latency_window_ms = 0;
  int echo_tracks = 3;
  bool json_output = false;
  CLI::App app{
      "bench_latency: end-to-end latency camera_node -> estimator_node -> subscriber vs the DDS floor",
      "bench_latency"};
  app.add_flag("--json", json_output, "print the result as one JSON object");
  app.add_option("--scene", scene_file, "simulator scene (its cameras are the camera_nodes)")
      ->capture_default_str();
  app.add_option("--duration", duration_s, "seconds measured")
      ->check(CLI::Range(2.0, 600.0))
      ->capture_default_str();
  app.add_option("--warmup", warmup_s, "seconds ignored after scene time 0")->capture_default_str();
  app.add_option("--latency-window-ms", latency_window_ms,
                 "estimator_node --latency-window-ms (0: process frames as they arrive; the default "
                 "estimator configuration waits 20 ms to put frames of all cameras in order)")
      ->capture_default_str();
  app.add_option("--dds-profile", profile, "Fast DDS profile for every process")->capture_default_str();
  app.add_option("--log-dir", log_dir, "keep the child processes' logs here");
  app.add_option("--role", role, "internal: bench | echo")->check(CLI::IsMember({"bench", "echo"}));
  app.add_option("--echo-tracks", echo_tracks, "internal: tracks in the echo's TrackFrame");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();

  try {
    if (role == "echo") return run_echo(profile, duration_s, echo_tracks);

    const panoptes::Scene scene = panoptes::Scene::load(scene_file);
    const fs::path run_dir = log_dir.empty()
                                 ? fs::temp_directory_path() / ("bench-latency-" + std::to_string(getpid()))
                                 : fs::path(log_dir);
    fs::create_directories(run_dir);
    const fs::path calibration = run_dir / "calibration.yaml";
    panoptes::save_calibration(scene.calibration(), calibration);
    const int markers = static_cast<int>(scene.marker_names().size());

    std::mutex mutex;
    std::map<FrameKey, FeatureSeen> features;
    Stats end_to_end, detection, camera_queue, transport_in, estimator, transport_out, floor_hops,
        floor_total;
    std::map<FrameKey, TimeNs> pending_floor;  // detection time of frames sent on the floor domain
    TimeNs measure_from = 0;
    TimeNs measure_to = 0;

    panoptes::dds::BusOptions floor_options;
    floor_options.profile_file = profile;
    floor_options.domain_id = kFloorDomain;
    floor_options.participant_name = "bench_latency_floor";
    panoptes::dds::Bus floor_bus(floor_options);
    auto floor_writer = floor_bus.make_writer<msg::FeatureFrame>();
    auto floor_reader = floor_bus.make_reader<msg::TrackFrame>([&](msg::TrackFrame&& reply) {
      const TimeNs now = panoptes::wall_now_ns();
      std::lock_guard lock(mutex);
      auto it = features.find({reply.source_camera(), reply.source_frame()});
      if (it == features.end() || it->second.floor_sent_ns == 0) return;
      if (it->second.received_ns < measure_from || it->second.received_ns > measure_to) return;
      floor_hops.add(now - it->second.floor_sent_ns);
      floor_total.add(now - it->second.floor_sent_ns + it->second.processing_ns);
    });

    panoptes::dds::BusOptions options;
    options.profile_file = profile;
    options.participant_name = "bench_latency";
    panoptes::dds::Bus bus(options);
    auto feature_reader = bus.make_reader<msg::FeatureFrame>([&](msg::FeatureFrame&& frame) {
      const TimeNs now = panoptes::wall_now_ns();
      {
        std::lock_guard lock(mutex);
        FeatureSeen& seen = features[{frame.camera_id(), frame.frame()}];
        seen = {frame.arrival_ns(), frame.processing_ns(), frame.publish_ns(), now, panoptes::wall_now_ns()};
        // Forget frames older than 2 s (bounded memory).
        if (features.size() > 4096) {
          for (auto it = features.begin(); it != features.end();) {
            it = now - it->second.received_ns > panoptes::kNsPerSecond * 2 ? features.erase(it)
                                                                           : std::next(it);
          }
        }
      }
      floor_writer->write(frame);
    });
    auto track_reader = bus.make_reader<msg::TrackFrame>([&](msg::TrackFrame&& frame) {
      const TimeNs now = panoptes::wall_now_ns();
      std::lock_guard lock(mutex);
      auto it = features.find({frame.source_camera(), frame.source_frame()});
      if (it == features.end()) return;
      const FeatureSeen& seen = it->second;
      if (seen.received_ns < measure_from || seen.received_ns > measure_to) return;
      end_to_end.add(now - seen.arrival_ns);
      detection.add(seen.processing_ns);
      camera_queue.add(seen.publish_ns - seen.arrival_ns - seen.processing_ns);
      transport_in.add(seen.received_ns - seen.publish_ns);
      estimator.add(frame.publish_ns() - seen.received_ns);
      transport_out.add(now - frame.publish_ns());
    });

    const TimeNs epoch = (panoptes::wall_now_ns() / panoptes::kNsPerSecond + 3) * panoptes::kNsPerSecond;
    measure_from = epoch + panoptes::seconds_to_ns(warmup_s);
    measure_to = measure_from + panoptes::seconds_to_ns(duration_s);
    const double run_s = warmup_s + duration_s + 4;
    std::vector<std::unique_ptr<Child>> children;
    children.push_back(std::make_unique<Child>(
        "echo",
        std::vector<std::string>{self.string(), "--role", "echo", "--dds-profile", profile, "--duration",
                                 std::to_string(run_s + 2), "--echo-tracks", std::to_string(markers)},
        run_dir / "echo.log"));
    children.push_back(std::make_unique<Child>(
        "estimator_node",
        std::vector<std::string>{(bin_dir / "estimator_node").string(), "--calibration", calibration.string(),
                                 "--dds-profile", profile, "--latency-window-ms",
                                 std::to_string(latency_window_ms), "--duration", std::to_string(run_s + 2)},
        run_dir / "estimator_node.log"));
    for (const auto& camera : scene.cameras()) {
      const std::string& id = camera.calibration.id;
      children.push_back(std::make_unique<Child>(
          "camera_node[" + id + "]",
          std::vector<std::string>{(bin_dir / "camera_node").string(), "--source",
                                   "sim:" + scene_file + "#" + id, "--sim-epoch-ns", std::to_string(epoch),
                                   "--dds-profile", profile, "--duration", std::to_string(run_s), "--quiet"},
          run_dir / (id + ".log")));
    }
    while (!panoptes::stop_requested() && panoptes::wall_now_ns() < measure_to + panoptes::kNsPerSecond / 2)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (auto it = children.rbegin(); it != children.rend(); ++it) (*it)->stop();

    std::lock_guard lock(mutex);
    double rate = 0;
    for (const auto& camera : scene.cameras()) rate = std::max(rate, camera.rate_hz);
    const double floor_p99 = floor_total.at(0.99);
    const double floor_p50 = floor_total.at(0.5);
    nlohmann::json result = {
        {"benchmark", "end-to-end latency, loopback"},
        {"cameras", scene.cameras().size()},
        {"rate_hz", rate},
        {"scene", scene_file},
        {"duration_s", duration_s},
        {"estimator_latency_window_ms", latency_window_ms},
        {"output", "TrackFrame (rt/panoptes/tracks)"},
        {"track_frames_per_s", static_cast<double>(end_to_end.ms.size()) / duration_s},
        {"end_to_end_ms", end_to_end.json()},
        {"breakdown_ms",
         {{"detection", detection.json()},
          {"camera_node_queue_and_publish", camera_queue.json()},
          {"transport_camera_to_estimator", transport_in.json()},
          {"estimator", estimator.json()},
          {"transport_estimator_to_subscriber", transport_out.json()}}},
        {"dds_floor_ms", {{"two_hops", floor_hops.json()}, {"two_hops_plus_detection", floor_total.json()}}},
        {"ratio_vs_dds_floor_p50", floor_p50 > 0 ? end_to_end.at(0.5) / floor_p50 : 0.0},
        {"ratio_vs_dds_floor_p99", floor_p99 > 0 ? end_to_end.at(0.99) / floor_p99 : 0.0},
        {"logs", run_dir.string()},
    };
    if (json_output) {
      std::printf("%s\n", result.dump(2).c_str());
    } else {
      std::printf(
          "end to end p50 %.3f ms p99 %.3f ms; DDS floor + detection p50 %.3f ms p99 %.3f ms; ratio p99 "
          "%.2f\n",
          end_to_end.at(0.5), end_to_end.at(0.99), floor_p50, floor_p99,
          result["ratio_vs_dds_floor_p99"].get<double>());
    }
    if (end_to_end.ms.empty()) {
      std::fprintf(stderr, "bench_latency: no TrackFrame matched a FeatureFrame; see the logs in %s\n",
                   run_dir.c_str());
      return panoptes::kExitFailure;
    }
    if (log_dir.empty()) fs::remove_all(run_dir);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_latency: %s\n", error.what());
    return panoptes::kExitFailure;
  }
  return panoptes::kExitOk;
}
