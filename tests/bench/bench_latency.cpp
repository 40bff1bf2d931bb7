// SPDX-License-Identifier: Apache-2.0
// bench_latency: end-to-end latency of the live pipeline on this machine (loopback profile), side by
// side with the raw DDS floor through the same processes, as JSON (docs/protocol.md, "End-to-end
// latency: 4 cameras × 240 Hz").
//
//   pipeline: simulated cameras -> camera_node (render handed over, detection, publish)
//             -> estimator_node --bodies (tracker, rigid body) -> this process, subscribed to
//             rt/panoptes/bodies.
//   (i)  per camera frame: its arrival at camera_node (FeatureFrame.arrival_ns) to the arrival here
//        of the BodyPose it produced. estimator_node --latency-probe traces each frame (when it
//        arrived, when its poses were written, with which stamp), which ties poses to frames.
//   (ii) floor: camera_node --latency-probe writes, right after each FeatureFrame, a probe of the
//        same serialized size; estimator_node --latency-probe echoes it at once from its DDS
//        listener as a message of a BodyPose's size; this process receives the echo. Two raw DDS
//        hops with the pipeline's payloads between the pipeline's processes, at the same time as
//        the pipeline, plus that frame's detection time.
//   ratio_vs_dds_floor_p99 = p99(i) / p99(ii). TrackFrame (rt/panoptes/tracks) is a secondary row.
// Every process runs in the run's DDS domain: --domain, else $PANOPTES_DOMAIN when set (as every
// program reads it; the test harness gives each test its own), else one of the run's own, so that
// other pipelines on the host cannot mix in. All stamps are wall-clock ns on one host (camera nodes
// synchronise to the estimator's clock, the same clock here, so the correction is microseconds).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/process.h"
#include "panoptes/simulator.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace {

namespace fs = std::filesystem;
using panoptes::TimeNs;
namespace msg = panoptes::msg;

// CPU time used so far by the whole host (busy, and stolen by the hypervisor) and by this process
// and its children (the pipeline), from /proc: how loaded the machine was while measuring.
struct CpuSample {
  TimeNs at_ns = 0;
  double host_busy_s = 0;
  double host_steal_s = 0;
  double pipeline_s = 0;
};

CpuSample sample_cpu() {
  CpuSample sample;
  sample.at_ns = panoptes::wall_now_ns();
  const auto tick = static_cast<double>(sysconf(_SC_CLK_TCK));
  std::ifstream host("/proc/stat");
  std::string cpu;
  unsigned long long user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
  host >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal;
  sample.host_busy_s = static_cast<double>(user + nice + system + irq + softirq) / tick;
  sample.host_steal_s = static_cast<double>(steal) / tick;
  const long self = getpid();
  std::error_code error;
  for (const auto& entry : fs::directory_iterator("/proc", error)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    std::getline(stat, line);
    const auto paren = line.rfind(')');
    if (paren == std::string::npos) continue;
    std::istringstream fields(line.substr(paren + 1));
    std::string state;
    long ppid = 0;
    fields >> state >> ppid;
    if (std::stol(name) != self && ppid != self) continue;
    std::string skip;
    for (int i = 0; i < 9; ++i) fields >> skip;  // pgrp .. cmajflt
    unsigned long long utime = 0, stime = 0;
    fields >> utime >> stime;
    sample.pipeline_s += static_cast<double>(utime + stime) / tick;
  }
  return sample;
}

nlohmann::json cpu_json(const CpuSample& from, const CpuSample& to) {
  const double seconds = panoptes::ns_to_seconds(to.at_ns - from.at_ns);
  if (seconds <= 0) return {};
  const double busy = (to.host_busy_s - from.host_busy_s) / seconds;
  const double pipeline = (to.pipeline_s - from.pipeline_s) / seconds;
  return {{"cores", std::thread::hardware_concurrency()},
          {"host_busy_cores", busy},
          {"pipeline_cores", pipeline},
          {"other_processes_cores", std::max(0.0, busy - pipeline)},
          {"steal_cores", (to.host_steal_s - from.host_steal_s) / seconds}};
}

fs::path executable_path() {
  std::error_code error;
  return fs::read_symlink("/proc/self/exe", error);
}

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

// What the listeners record, untouched; joined after the run so that the listeners stay short.
struct Received {
  TimeNs at_ns = 0;  // here
};
struct EchoReceived : Received {
  msg::LatencyProbeEcho echo;
};
struct TraceReceived : Received {
  msg::LatencyTrace trace;
};
struct PoseReceived : Received {
  TimeNs stamp_ns = 0;
};
struct TracksReceived : Received {
  std::string camera_id;
  long long frame = 0;
  TimeNs publish_ns = 0;
};

struct Recorder {
  std::mutex mutex;
  std::vector<EchoReceived> echoes;
  std::vector<TraceReceived> traces;
  std::vector<PoseReceived> poses;
  std::vector<TracksReceived> tracks;
};

using FrameKey = std::pair<std::string, long long>;

struct Results {
  Stats end_to_end, detection, camera_queue, transport_in, estimator, transport_out;
  Stats estimator_inbox, estimator_update, estimator_publish;  // the estimator stage, split
  Stats tracks_end_to_end, tracks_transport_out;
  Stats floor_total, floor_hops, floor_hop_in, floor_hop_out;
  std::size_t frames_traced = 0;        // in the window
  std::size_t frames_with_pose = 0;     // of those, frames that updated the body
  std::size_t poses_unmatched = 0;      // frames whose pose did not arrive
  std::vector<nlohmann::json> samples;  // per frame, every stamp (--samples)
};

Results join(const Recorder& recorded, TimeNs from_ns, TimeNs to_ns) {
  Results results;
  const auto measured = [&](TimeNs arrival_ns) { return arrival_ns >= from_ns && arrival_ns <= to_ns; };

  std::map<FrameKey, const msg::LatencyProbe*> probes;
  for (const EchoReceived& received : recorded.echoes) {
    const msg::LatencyProbe& probe = received.echo.probe();
    probes[{probe.camera_id(), probe.frame()}] = &probe;
    if (!measured(probe.arrival_ns())) continue;
    results.floor_hops.add(received.at_ns - probe.publish_ns());
    results.floor_total.add(received.at_ns - probe.publish_ns() + probe.processing_ns());
    results.floor_hop_in.add(received.echo.received_ns() - probe.publish_ns());
    results.floor_hop_out.add(received.at_ns - received.echo.publish_ns());
  }

  // A pose is tied to the frame whose trace names its stamp. A late frame, replayed, republishes
  // the newest stamp, so one stamp can have several poses: they are taken in the order written.
  std::map<TimeNs, std::deque<TimeNs>> pose_arrivals;
  for (const PoseReceived& pose : recorded.poses) pose_arrivals[pose.stamp_ns].push_back(pose.at_ns);
  std::vector<const TraceReceived*> traces;
  for (const TraceReceived& received : recorded.traces) {
    if (measured(received.trace.arrival_ns())) ++results.frames_traced;
    if (received.trace.poses() > 0) traces.push_back(&received);
  }
  std::sort(traces.begin(), traces.end(), [](const TraceReceived* a, const TraceReceived* b) {
    return a->trace.poses_published_ns() < b->trace.poses_published_ns();
  });
  for (const TraceReceived* received : traces) {
    const msg::LatencyTrace& trace = received->trace;
    auto arrivals = pose_arrivals.find(trace.pose_stamp_ns());
    if (arrivals == pose_arrivals.end() || arrivals->second.empty()) {
      if (measured(trace.arrival_ns())) ++results.poses_unmatched;
      continue;
    }
    const TimeNs pose_at_ns = arrivals->second.front();
    arrivals->second.pop_front();
    if (!measured(trace.arrival_ns())) continue;
    ++results.frames_with_pose;
    results.end_to_end.add(pose_at_ns - trace.arrival_ns());
    results.detection.add(trace.processing_ns());
    results.estimator.add(trace.poses_published_ns() - trace.received_ns());
    results.estimator_inbox.add(trace.dequeued_ns() - trace.received_ns());
    results.estimator_update.add(trace.updated_ns() - trace.dequeued_ns());
    results.estimator_publish.add(trace.poses_published_ns() - trace.updated_ns());
    results.transport_out.add(pose_at_ns - trace.poses_published_ns());
    TimeNs feature_publish_ns = 0;
    if (auto probe = probes.find({trace.camera_id(), trace.frame()}); probe != probes.end()) {
      feature_publish_ns = probe->second->feature_publish_ns();
      results.camera_queue.add(feature_publish_ns - trace.arrival_ns() - trace.processing_ns());
      results.transport_in.add(trace.received_ns() - feature_publish_ns);
    }
    results.samples.push_back({{"camera", trace.camera_id()},
                               {"frame", trace.frame()},
                               {"stamp_ns", trace.stamp_ns()},
                               {"arrival_ns", trace.arrival_ns()},
                               {"processing_ns", trace.processing_ns()},
                               {"feature_publish_ns", feature_publish_ns},
                               {"received_ns", trace.received_ns()},
                               {"dequeued_ns", trace.dequeued_ns()},
                               {"updated_ns", trace.updated_ns()},
                               {"poses_published_ns", trace.poses_published_ns()},
                               {"pose_received_ns", pose_at_ns}});
  }

  std::map<FrameKey, const msg::LatencyTrace*> traced;
  for (const TraceReceived& received : recorded.traces)
    traced[{received.trace.camera_id(), received.trace.frame()}] = &received.trace;
  for (const TracksReceived& tracks : recorded.tracks) {
    auto trace = traced.find({tracks.camera_id, tracks.frame});
    if (trace == traced.end() || !measured(trace->second->arrival_ns())) continue;
    results.tracks_end_to_end.add(tracks.at_ns - trace->second->arrival_ns());
    results.tracks_transport_out.add(tracks.at_ns - tracks.publish_ns);
  }
  return results;
}

// The run's domain without --domain: $PANOPTES_DOMAIN when set (checked as every program checks it:
// DomainError, exit 2, for a bad value), else one of the run's own.
int run_domain() {
  const char* variable = std::getenv(panoptes::dds::kDomainVariable);
  if (variable != nullptr && *variable != '\0') return panoptes::dds::resolve_domain();
  return 100 + static_cast<int>(getpid() % 100);
}

int run(int argc, char** argv) {
  const fs::path bin_dir = executable_path().parent_path();
  std::string scene_file = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/latency240.yaml";
  std::string profile = std::string(PANOPTES_SOURCE_DIR) + "/deploy/dds/loopback.xml";
  std::string log_dir;
  std::string samples_file;
  std::string security_dir;
  double duration_s = 10;
  double warmup_s = 2;
  double latency_window_ms = -1;  // < 0: not passed, the estimator's default
  int domain = -1;                // not given: $PANOPTES_DOMAIN when set, else 100 + pid % 100
  bool json_output = false;
  bool subscribe_tracks = true;
  CLI::App app{
      "bench_latency: end-to-end latency, simulated cameras -> camera_node -> estimator_node -> a "
      "subscriber of the rigid body's BodyPose, against the raw DDS floor measured through the same "
      "processes in the same run (docs/benchmarks.md). Progress on stderr, result on stdout.",
      "bench_latency"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_flag("--json", json_output, "print the result as one JSON object");
  app.add_option("--scene", scene_file,
                 "simulator scene: its cameras are the camera_nodes, its first body is the one measured")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--duration", duration_s, "seconds measured")
      ->check(CLI::Range(2.0, 600.0))
      ->capture_default_str();
  app.add_option("--warmup", warmup_s, "seconds ignored after scene time 0 (body identification)")
      ->check(CLI::Range(0.5, 60.0))
      ->capture_default_str();
  app.add_option("--latency-window-ms", latency_window_ms,
                 "estimator_node --latency-window-ms (0: frames are processed as they arrive, late ones "
                 "replayed; e.g. 20: frames wait 20 ms to be put in stamp order)")
      ->check(CLI::Range(0.0, 1000.0))
      ->default_str("not passed: the estimator's default");
  app.add_flag("!--no-tracks", subscribe_tracks,
               "do not subscribe to rt/panoptes/tracks (the secondary TrackFrame row)");
  app.add_option("--domain", domain,
                 "DDS domain of the run, for every process (so that other pipelines on this host do not "
                 "mix in)")
      ->check(CLI::Range(0, panoptes::dds::kMaxDomainId))
      ->default_str("$PANOPTES_DOMAIN when set (a bad value exits 2 naming it), else 100 + pid % 100");
  app.add_option("--dds-profile", profile, "Fast DDS profile for every process")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--log-dir", log_dir, "keep the child processes' logs and inputs here")
      ->default_str("a temporary folder");
  app.add_option(
      "--samples", samples_file,
      "write every measured frame's stamps (camera_node, estimator_node, here) to this JSONL file");
  app.add_option("--security-dir", security_dir,
                 "DDS Security for every process (docs/security.md): a studio of "
                 "deploy/security/panoptes-security with the identities 'estimator', 'console' (this "
                 "process) and one camera identity per camera id of the scene")
      ->check(CLI::ExistingDirectory);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  if (domain < 0) domain = run_domain();
  panoptes::install_stop_handlers();
  // The security options of a child with `identity`; none for a plain run.
  const auto security_argv = [&](const std::string& identity) {
    return security_dir.empty()
               ? std::vector<std::string>{}
               : std::vector<std::string>{"--security-dir", security_dir, "--security-identity", identity};
  };

  try {
    const panoptes::Scene scene = panoptes::Scene::load(scene_file);
    const auto bodies = scene.body_definitions();
    if (bodies.empty()) {
      std::fprintf(stderr, "bench_latency: %s has no `bodies:`; the output measured is a BodyPose\n",
                   scene_file.c_str());
      return panoptes::kExitBadInput;
    }
    const std::string body = bodies.front().name;
    const fs::path run_dir = log_dir.empty()
                                 ? fs::temp_directory_path() / ("bench-latency-" + std::to_string(getpid()))
                                 : fs::path(log_dir);
    fs::create_directories(run_dir);
    const fs::path calibration = run_dir / "calibration.yaml";
    const fs::path bodies_file = run_dir / "bodies.yaml";
    panoptes::save_calibration(scene.calibration(), calibration);
    panoptes::save_bodies(bodies, bodies_file);

    Recorder recorded;
    panoptes::dds::BusOptions options;
    options.profile_file = profile;
    options.participant_name = "bench_latency";
    if (!security_dir.empty()) options.security = {security_dir, "console"};
    options.domain_id = domain;
    setenv("PANOPTES_DOMAIN", std::to_string(domain).c_str(), 1);  // for the nodes
    panoptes::dds::Bus bus(options);
    // Listeners only append (timestamp first); everything is joined after the run.
    auto echo_reader = bus.make_reader<msg::LatencyProbeEcho>([&](msg::LatencyProbeEcho&& echo) {
      const TimeNs now = panoptes::wall_now_ns();
      std::lock_guard lock(recorded.mutex);
      recorded.echoes.push_back({{now}, std::move(echo)});
    });
    auto pose_reader = bus.make_reader<msg::BodyPose>([&](msg::BodyPose&& pose) {
      const TimeNs now = panoptes::wall_now_ns();
      if (pose.name() != body) return;
      std::lock_guard lock(recorded.mutex);
      recorded.poses.push_back({{now}, pose.stamp_ns()});
    });
    auto trace_reader = bus.make_reader<msg::LatencyTraces>([&](msg::LatencyTraces&& traces) {
      const TimeNs now = panoptes::wall_now_ns();
      std::lock_guard lock(recorded.mutex);
      for (msg::LatencyTrace& trace : traces.frames()) recorded.traces.push_back({{now}, std::move(trace)});
    });
    std::unique_ptr<panoptes::dds::Reader<msg::TrackFrame>> track_reader;
    if (subscribe_tracks) {
      track_reader = bus.make_reader<msg::TrackFrame>([&](msg::TrackFrame&& frame) {
        const TimeNs now = panoptes::wall_now_ns();
        std::lock_guard lock(recorded.mutex);
        recorded.tracks.push_back({{now}, frame.source_camera(), frame.source_frame(), frame.publish_ns()});
      });
    }

    const TimeNs epoch = (panoptes::wall_now_ns() / panoptes::kNsPerSecond + 3) * panoptes::kNsPerSecond;
    const TimeNs measure_from = epoch + panoptes::seconds_to_ns(warmup_s);
    const TimeNs measure_to = measure_from + panoptes::seconds_to_ns(duration_s);
    const double run_s = warmup_s + duration_s + 4;
    std::fprintf(stderr,
                 "bench_latency: estimator_node and %zu camera_nodes (%s), body '%s', DDS domain %d; %.0f s "
                 "warm-up, %.0f s measured; logs in %s\n",
                 scene.cameras().size(), scene_file.c_str(), body.c_str(), domain, warmup_s, duration_s,
                 run_dir.c_str());
    std::vector<std::unique_ptr<panoptes::ChildProcess>> children;
    std::vector<std::string> estimator_argv{(bin_dir / "estimator_node").string(),
                                            "--calibration",
                                            calibration.string(),
                                            "--bodies",
                                            bodies_file.string(),
                                            "--dds-profile",
                                            profile,
                                            "--latency-probe",
                                            "--duration",
                                            std::to_string(run_s + 2)};
    if (latency_window_ms >= 0) {
      estimator_argv.push_back("--latency-window-ms");
      estimator_argv.push_back(std::to_string(latency_window_ms));
    }
    for (std::string& argument : security_argv("estimator")) estimator_argv.push_back(std::move(argument));
    children.push_back(std::make_unique<panoptes::ChildProcess>("estimator_node", std::move(estimator_argv),
                                                                run_dir / "estimator_node.log"));
    const std::string source_prefix = "sim:" + scene_file + "#";
    for (const auto& camera : scene.cameras()) {
      const std::string& id = camera.calibration.id;
      std::vector<std::string> camera_argv{(bin_dir / "camera_node").string(),
                                           "--source",
                                           source_prefix + id,
                                           "--sim-epoch-ns",
                                           std::to_string(epoch),
                                           "--dds-profile",
                                           profile,
                                           "--latency-probe",
                                           "--duration",
                                           std::to_string(run_s),
                                           "--quiet"};
      for (std::string& argument : security_argv(id)) camera_argv.push_back(std::move(argument));
      children.push_back(std::make_unique<panoptes::ChildProcess>(
          "camera_node[" + id + "]", std::move(camera_argv), run_dir / (id + ".log")));
    }
    TimeNs next_progress = epoch;
    std::optional<CpuSample> cpu_from, cpu_to;
    while (!panoptes::stop_requested() && panoptes::wall_now_ns() < measure_to + panoptes::kNsPerSecond / 2) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      const TimeNs now = panoptes::wall_now_ns();
      if (!cpu_from && now >= measure_from) cpu_from = sample_cpu();
      if (!cpu_to && now >= measure_to) cpu_to = sample_cpu();
      if (now < next_progress) continue;
      next_progress += panoptes::kNsPerSecond;
      std::size_t poses = 0, echoes = 0, traces = 0;
      {
        std::lock_guard lock(recorded.mutex);
        poses = recorded.poses.size();
        echoes = recorded.echoes.size();
        traces = recorded.traces.size();
      }
      const char* phase = now < measure_from ? "warm-up" : now <= measure_to ? "measuring" : "draining";
      std::fprintf(stderr, "bench_latency: t=%4.1f s %-9s poses %zu, frames traced %zu, probe echoes %zu\n",
                   panoptes::ns_to_seconds(now - epoch), phase, poses, traces, echoes);
    }
    std::fprintf(stderr, "bench_latency: stopping the nodes\n");
    for (auto it = children.rbegin(); it != children.rend(); ++it) (*it)->stop();
    track_reader.reset();
    trace_reader.reset();
    pose_reader.reset();
    echo_reader.reset();

    Results r = join(recorded, measure_from, measure_to);
    if (!samples_file.empty()) {
      std::FILE* out = std::fopen(samples_file.c_str(), "w");
      if (out == nullptr) throw std::runtime_error("cannot write " + samples_file);
      for (const auto& sample : r.samples) std::fprintf(out, "%s\n", sample.dump().c_str());
      std::fclose(out);
    }
    double rate = 0;
    for (const auto& camera : scene.cameras()) rate = std::max(rate, camera.rate_hz);
    const double floor_p99 = r.floor_total.at(0.99);
    const double floor_p50 = r.floor_total.at(0.5);
    nlohmann::json result = {
        {"benchmark", "end-to-end latency, loopback"},
        {"cameras", scene.cameras().size()},
        {"rate_hz", rate},
        {"scene", scene_file},
        {"duration_s", duration_s},
        {"estimator_latency_window_ms",
         latency_window_ms >= 0 ? nlohmann::json(latency_window_ms) : nlohmann::json("default")},
        {"output", "BodyPose '" + body + "' (rt/panoptes/bodies)"},
        {"poses_per_s", static_cast<double>(r.end_to_end.ms.size()) / duration_s},
        {"frames_traced", r.frames_traced},
        {"frames_with_pose", r.frames_with_pose},
        {"poses_unmatched", r.poses_unmatched},
        {"end_to_end_ms", r.end_to_end.json()},
        {"breakdown_ms",
         {{"detection", r.detection.json()},
          {"camera_node_queue_and_publish", r.camera_queue.json()},
          {"transport_camera_to_estimator", r.transport_in.json()},
          {"estimator_queue_update_publish", r.estimator.json()},
          {"estimator_split",
           {{"inbox_and_wakeup", r.estimator_inbox.json()},
            {"update", r.estimator_update.json()},
            {"until_publish", r.estimator_publish.json()}}},
          {"transport_estimator_to_subscriber", r.transport_out.json()}}},
        {"dds_floor_ms",
         {{"two_hops_plus_detection", r.floor_total.json()},
          {"two_hops", r.floor_hops.json()},
          {"hop_camera_to_estimator", r.floor_hop_in.json()},
          {"hop_estimator_to_subscriber", r.floor_hop_out.json()}}},
        {"ratio_vs_dds_floor_p50", floor_p50 > 0 ? r.end_to_end.at(0.5) / floor_p50 : 0.0},
        {"ratio_vs_dds_floor_p99", floor_p99 > 0 ? r.end_to_end.at(0.99) / floor_p99 : 0.0},
        {"cpu_while_measuring", cpu_from && cpu_to ? cpu_json(*cpu_from, *cpu_to) : nlohmann::json()},
        {"dds_domain", domain},
        {"dds_security", security_dir.empty() ? nlohmann::json(false) : nlohmann::json(security_dir)},
        {"logs", run_dir.string()},
    };
    if (subscribe_tracks) {
      result["track_frame_ms"] = {{"end_to_end", r.tracks_end_to_end.json()},
                                  {"transport_estimator_to_subscriber", r.tracks_transport_out.json()}};
    }
    if (json_output) {
      std::printf("%s\n", result.dump(2).c_str());
    } else {
      std::printf(
          "BodyPose end to end p50 %.3f ms p99 %.3f ms; DDS floor + detection p50 %.3f ms p99 %.3f ms; ratio "
          "p99 %.2f\n",
          r.end_to_end.at(0.5), r.end_to_end.at(0.99), floor_p50, floor_p99,
          result["ratio_vs_dds_floor_p99"].get<double>());
    }
    if (r.end_to_end.ms.empty() || r.floor_total.ms.empty()) {
      std::fprintf(stderr, "bench_latency: no %s; see the logs in %s\n",
                   r.end_to_end.ms.empty() ? "BodyPose matched a traced frame" : "probe echo arrived",
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

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_latency", [&] { return run(argc, argv); });
}
