// SPDX-License-Identifier: Apache-2.0
// panoptes_demo: the main job. Starts one camera_node per simulated camera and one estimator_node
// over Fast DDS (loopback profile), watches the tracks as an application would, and ends with the
// accuracy against ground truth.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/domain.h"
#include "panoptes/eval/evaluation.h"
#include "panoptes/process.h"
#include "panoptes/simulator.h"
#include "panoptes/time.h"

namespace {

namespace fs = std::filesystem;
using panoptes::TimeNs;

fs::path executable_dir() {
  std::error_code error;
  return fs::read_symlink("/proc/self/exe", error).parent_path();
}

using Child = panoptes::ChildProcess;

// One estimator_node and one camera_node per simulated camera, logging into `run_dir`.
std::vector<std::unique_ptr<Child>> start_processes(const fs::path& bin_dir, const panoptes::Scene& scene,
                                                    const std::string& scene_file,
                                                    const fs::path& calibration_file,
                                                    const fs::path& bodies_file,
                                                    const std::string& dds_profile, const fs::path& run_dir,
                                                    TimeNs epoch, double duration_s) {
  std::vector<std::string> common_dds;
  if (!dds_profile.empty()) common_dds = {"--dds-profile", dds_profile};
  std::vector<std::unique_ptr<Child>> children;
  std::vector<std::string> estimator_args = {(bin_dir / "estimator_node").string(), "--calibration",
                                             calibration_file.string(), "--out-tracks",
                                             (run_dir / "tracks.jsonl").string()};
  if (!bodies_file.empty()) {
    // The scene's rigid bodies: the estimator tracks them and writes their poses beside the tracks.
    for (const std::string& arg : {std::string("--bodies"), bodies_file.string(), std::string("--out-poses"),
                                   (run_dir / "poses.jsonl").string()})
      estimator_args.push_back(arg);
  }
  estimator_args.insert(estimator_args.end(), common_dds.begin(), common_dds.end());
  children.push_back(
      std::make_unique<Child>("estimator_node", estimator_args, run_dir / "estimator_node.log"));
  const std::string source_prefix = "sim:" + scene_file + "#";
  for (const auto& camera : scene.cameras()) {
    const std::string& id = camera.calibration.id;
    std::vector<std::string> camera_args = {(bin_dir / "camera_node").string(),
                                            "--source",
                                            source_prefix + id,
                                            "--sim-epoch-ns",
                                            std::to_string(epoch),
                                            "--duration",
                                            std::to_string(duration_s + 4.0)};
    camera_args.insert(camera_args.end(), common_dds.begin(), common_dds.end());
    children.push_back(
        std::make_unique<Child>("camera_node[" + id + "]", camera_args, run_dir / (id + ".log")));
  }
  return children;
}

// Watches as an application would (tracks and camera status over DDS), printing a line a second,
// until the scene ends, a process fails or a stop is requested. Returns the exit code so far.
int watch(const std::string& dds_profile, const std::vector<std::unique_ptr<Child>>& children, TimeNs epoch,
          TimeNs end, const fs::path& run_dir, std::vector<panoptes::TrackRecord>& tracks) {
  std::mutex mutex;
  std::map<std::string, double> camera_fps;
  std::size_t live_tracks = 0;
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = dds_profile;
  bus_options.participant_name = "panoptes_demo";
  int exit_code = panoptes::kExitOk;
  try {
    panoptes::dds::Bus bus(bus_options);
    auto track_reader = bus.make_reader<panoptes::msg::TrackFrame>([&](panoptes::msg::TrackFrame&& frame) {
      std::lock_guard<std::mutex> lock(mutex);
      for (const auto& track : frame.tracks())
        tracks.push_back(panoptes::dds::from_message(track, frame.stamp_ns()));
      live_tracks = frame.tracks().size();
    });
    auto status_reader =
        bus.make_reader<panoptes::msg::CameraStatus>([&](panoptes::msg::CameraStatus&& status) {
          std::lock_guard<std::mutex> lock(mutex);
          camera_fps[status.camera_id()] = status.fps();
        });

    while (!panoptes::stop_requested() && panoptes::wall_now_ns() < end + panoptes::kNsPerSecond / 2) {
      std::this_thread::sleep_for(std::chrono::seconds(1));
      const TimeNs now = panoptes::wall_now_ns();
      std::string line;
      char buffer[128];
      std::snprintf(buffer, sizeof buffer, "t=%5.1fs |", panoptes::ns_to_seconds(now - epoch));
      line = buffer;
      {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& [id, fps] : camera_fps) {
          std::snprintf(buffer, sizeof buffer, " %s %.0f fps", id.c_str(), fps);
          line += buffer;
        }
        std::snprintf(buffer, sizeof buffer, " | tracks %zu | records %zu", live_tracks, tracks.size());
        line += buffer;
      }
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
      // A camera whose scene has ended exits with 0; any other exit is a failure.
      std::size_t finished = 0;
      for (auto& child : children) {
        if (child->running()) continue;
        if (child->exit_code() == 0 && now >= end - panoptes::kNsPerSecond) {
          ++finished;
          continue;
        }
        std::fprintf(stderr, "panoptes_demo: %s exited early (code %d); see its log in %s\n",
                     child->name().c_str(), child->exit_code(), run_dir.c_str());
        panoptes::request_stop();
        exit_code = panoptes::kExitFailure;
      }
      if (finished + 1 >= children.size()) break;  // every camera is done; the estimator remains
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_demo: %s\n", error.what());
    exit_code = panoptes::kExitFailure;
  }
  return exit_code;
}

// The accuracy against the scene's ground truth, printed and optionally written as JSON; exit 1
// under --check unless the demo's targets are met.
int report_accuracy(const panoptes::Scene& scene, const std::vector<panoptes::TrackRecord>& tracks,
                    TimeNs epoch, const std::string& scene_file, double duration_s,
                    const std::string& summary_json, bool check) {
  panoptes::estimator::EvaluationOptions options;
  options.epoch_ns = epoch;
  const auto evaluation = panoptes::estimator::evaluate(scene, tracks, options);
  std::printf("\nAccuracy against ground truth (after the first second, tracks as received over DDS):\n%s",
              evaluation.summary().c_str());
  const bool pass = evaluation.worst_marker_rmse_m < 0.002 && evaluation.min_tracked_fraction >= 0.95 &&
                    evaluation.id_switch_count == 0 && evaluation.instants > 0;
  std::printf("demo targets (RMSE < 2 mm, tracked >= 95%%, 0 ID switches): %s\n", pass ? "met" : "NOT met");
  if (!summary_json.empty()) {
    auto json = nlohmann::json::parse(evaluation.to_json());
    json["scene"] = scene_file;
    json["duration_s"] = duration_s;
    json["cameras"] = scene.cameras().size();
    json["targets_met"] = pass;
    std::ofstream out(summary_json);
    out << json.dump(2) << "\n";
    if (!out) {
      std::fprintf(stderr, "panoptes_demo: cannot write %s\n", summary_json.c_str());
      return panoptes::kExitFailure;
    }
  }
  return check && !pass ? panoptes::kExitFailure : panoptes::kExitOk;
}

int run(int argc, char** argv) {
  const fs::path bin_dir = executable_dir();
  std::string scene_file = (bin_dir / "../../deploy/scenes/demo.yaml").lexically_normal().string();
  if (!fs::exists(scene_file)) scene_file = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml";
  double duration_s = 20.0;
  std::string summary_json;
  std::string dds_profile;
  std::string log_dir;
  bool check = false;
  CLI::App app{"panoptes_demo: simulated multi-camera tracking over DDS, with accuracy against ground truth",
               "panoptes_demo"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--scene", scene_file, "simulator scene");
  app.add_option("--duration", duration_s, "seconds of tracking")->check(CLI::Range(2.0, 3600.0));
  app.add_option("--summary-json", summary_json, "write the accuracy summary as JSON to this file");
  app.add_option("--dds-profile", dds_profile, "Fast DDS XML profile")
      ->default_str("deploy/dds/loopback.xml");
  app.add_option("--log-dir", log_dir, "keep process logs and recorded tracks here")
      ->default_str("a temporary folder");
  app.add_flag(
      "--check", check,
      "exit 1 unless every marker meets the demo's targets (RMSE < 2 mm, >= 95% tracked, 0 ID switches)");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  // A bad $PANOPTES_DOMAIN or DDS profile is a usage error (exit 2) here, not an early exit of
  // every child.
  panoptes::dds::resolve_domain();
  panoptes::dds::resolve_profile_file(dds_profile);

  panoptes::install_stop_handlers();
  std::optional<panoptes::Scene> scene;
  try {
    scene.emplace(panoptes::Scene::load(scene_file));
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_demo: %s\n", error.what());
    return panoptes::kExitBadInput;
  }
  const double scene_s = panoptes::ns_to_seconds(scene->duration_ns());
  if (duration_s > scene_s) {
    std::printf(
        "note: the scene lasts %.1f s; the demo runs for that long (raise `duration:` in the scene for "
        "more)\n",
        scene_s);
    duration_s = scene_s;
  }
  const fs::path run_dir = log_dir.empty()
                               ? fs::temp_directory_path() / ("panoptes-demo-" + std::to_string(getpid()))
                               : fs::path(log_dir);
  fs::create_directories(run_dir);
  const fs::path calibration_file = run_dir / "calibration.yaml";
  panoptes::save_calibration(scene->calibration(), calibration_file);
  fs::path bodies_file;
  if (!scene->body_definitions().empty()) {
    bodies_file = run_dir / "bodies.yaml";
    panoptes::save_bodies(scene->body_definitions(), bodies_file);
  }

  // Scene time 0 a little in the future, so that every process has started and discovered the
  // others before the first frame.
  const TimeNs epoch = (panoptes::wall_now_ns() / panoptes::kNsPerSecond + 3) * panoptes::kNsPerSecond;
  const TimeNs end = epoch + panoptes::seconds_to_ns(duration_s);

  std::printf("Panoptes demo: %zu simulated cameras, %zu markers, %.0f s (scene %s)\n",
              scene->cameras().size(), scene->marker_names().size(), duration_s, scene_file.c_str());
  std::printf("logs and recordings in %s\n", run_dir.c_str());

  std::vector<std::unique_ptr<Child>> children;
  try {
    children = start_processes(bin_dir, *scene, scene_file, calibration_file, bodies_file, dds_profile,
                               run_dir, epoch, duration_s);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_demo: %s\n", error.what());
    return panoptes::kExitFailure;
  }

  // Watch as an application would: subscribe to tracks and camera status.
  std::vector<panoptes::TrackRecord> tracks;
  const int exit_code = watch(dds_profile, children, epoch, end, run_dir, tracks);
  for (auto it = children.rbegin(); it != children.rend(); ++it) (*it)->stop(std::chrono::seconds(5));
  children.clear();
  if (exit_code != panoptes::kExitOk) return exit_code;

  return report_accuracy(*scene, tracks, epoch, scene_file, duration_s, summary_json, check);
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_demo", [&] { return run(argc, argv); });
}
