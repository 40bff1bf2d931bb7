// SPDX-License-Identifier: Apache-2.0
#include "panoptes/demo_run/demo_run.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/errors.h"
#include "panoptes/process.h"
#include "panoptes/simulator.h"
#include "panoptes/time.h"

namespace panoptes::demo_run {
namespace {

namespace fs = std::filesystem;

using Child = ChildProcess;

// One estimator_node and one camera_node per simulated camera, logging into `run_dir`.
std::vector<std::unique_ptr<Child>> start_processes(const DemoOptions& options, const Scene& scene,
                                                    const fs::path& calibration_file,
                                                    const fs::path& bodies_file, const fs::path& run_dir,
                                                    TimeNs epoch) {
  const fs::path& bin_dir = options.bin_dir;
  std::vector<std::string> common_dds;
  if (!options.dds_profile.empty()) common_dds = {"--dds-profile", options.dds_profile};
  std::vector<std::unique_ptr<Child>> children;
  std::vector<std::string> estimator_args = {(bin_dir / "estimator_node").string(),
                                             "--calibration",
                                             calibration_file.string(),
                                             "--out-tracks",
                                             (run_dir / "tracks.jsonl").string(),
                                             "--frames",
                                             options.frames};
  if (!bodies_file.empty()) {
    // The scene's rigid bodies: the estimator tracks them and writes their poses beside the tracks.
    for (const std::string& arg : {std::string("--bodies"), bodies_file.string(), std::string("--out-poses"),
                                   (run_dir / "poses.jsonl").string()})
      estimator_args.push_back(arg);
  }
  estimator_args.insert(estimator_args.end(), common_dds.begin(), common_dds.end());
  children.push_back(
      std::make_unique<Child>("estimator_node", estimator_args, run_dir / "estimator_node.log"));
  const std::string source_prefix = "sim:" + options.scene_file + "#";
  for (const auto& camera : scene.cameras()) {
    const std::string& id = camera.calibration.id;
    std::vector<std::string> camera_args = {(bin_dir / "camera_node").string(),
                                            "--source",
                                            source_prefix + id,
                                            "--sim-epoch-ns",
                                            std::to_string(epoch),
                                            "--duration",
                                            std::to_string(options.duration_s + 4.0)};
    camera_args.insert(camera_args.end(), common_dds.begin(), common_dds.end());
    children.push_back(
        std::make_unique<Child>("camera_node[" + id + "]", camera_args, run_dir / (id + ".log")));
  }
  return children;
}

// Watches as an application would (tracks and camera status over DDS), printing a line a second,
// until the scene ends, a process fails or a stop is requested. Returns the exit code so far.
int watch(const std::string& dds_profile, const std::vector<std::unique_ptr<Child>>& children, TimeNs epoch,
          TimeNs end, const fs::path& run_dir, std::vector<TrackRecord>& tracks) {
  std::mutex mutex;
  std::map<std::string, double> camera_fps;
  std::size_t live_tracks = 0;
  dds::BusOptions bus_options;
  bus_options.profile_file = dds_profile;
  bus_options.participant_name = "panoptes_demo";
  int exit_code = kExitOk;
  try {
    dds::Bus bus(bus_options);
    auto track_reader = bus.make_reader<msg::TrackFrame>([&](msg::TrackFrame&& frame) {
      std::lock_guard<std::mutex> lock(mutex);
      for (const auto& track : frame.tracks()) tracks.push_back(dds::from_message(track, frame.stamp_ns()));
      live_tracks = frame.tracks().size();
    });
    auto status_reader = bus.make_reader<msg::CameraStatus>([&](msg::CameraStatus&& status) {
      std::lock_guard<std::mutex> lock(mutex);
      camera_fps[status.camera_id()] = status.fps();
    });

    while (!stop_requested() && wall_now_ns() < end + kNsPerSecond / 2) {
      std::this_thread::sleep_for(std::chrono::seconds(1));
      const TimeNs now = wall_now_ns();
      std::string line;
      char buffer[128];
      std::snprintf(buffer, sizeof buffer, "t=%5.1fs |", ns_to_seconds(now - epoch));
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
        if (child->exit_code() == 0 && now >= end - kNsPerSecond) {
          ++finished;
          continue;
        }
        std::fprintf(stderr, "panoptes_demo: %s exited early (code %d); see its log in %s\n",
                     child->name().c_str(), child->exit_code(), run_dir.c_str());
        request_stop();
        exit_code = kExitFailure;
      }
      if (finished + 1 >= children.size()) break;  // every camera is done; the estimator remains
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_demo: %s\n", error.what());
    exit_code = kExitFailure;
  }
  return exit_code;
}

// The accuracy against the scene's ground truth, printed and optionally written as JSON; exit 1
// under --check unless the demo's targets are met.
int report_accuracy(const Scene& scene, const std::vector<TrackRecord>& tracks, TimeNs epoch,
                    const DemoOptions& options) {
  estimator::EvaluationOptions evaluation_options;
  evaluation_options.epoch_ns = epoch;
  const auto evaluation = estimator::evaluate(scene, tracks, evaluation_options);
  std::printf("\nAccuracy against ground truth (after the first second, tracks as received over DDS):\n%s",
              evaluation.summary().c_str());
  const bool pass = targets_met(evaluation);
  std::printf("demo targets (RMSE < 2 mm, tracked >= 95%%, 0 ID switches): %s\n", pass ? "met" : "NOT met");
  if (!options.summary_json.empty()) {
    std::ofstream out(options.summary_json);
    out << summary_json(evaluation, options.scene_file, options.duration_s, scene.cameras().size()) << "\n";
    if (!out) {
      std::fprintf(stderr, "panoptes_demo: cannot write %s\n", options.summary_json.c_str());
      return kExitFailure;
    }
  }
  return options.check && !pass ? kExitFailure : kExitOk;
}

// The scene, loaded; any failure is the input's.
Scene load_scene(const std::string& file) {
  return as_input_error([&] { return Scene::load(file); });
}

}  // namespace

bool targets_met(const estimator::Evaluation& evaluation) {
  return evaluation.worst_marker_rmse_m < 0.002 && evaluation.min_tracked_fraction >= 0.95 &&
         evaluation.id_switch_count == 0 && evaluation.instants > 0;
}

std::string summary_json(const estimator::Evaluation& evaluation, const std::string& scene_file,
                         double duration_s, std::size_t cameras) {
  auto json = nlohmann::json::parse(evaluation.to_json());
  json["scene"] = scene_file;
  json["duration_s"] = duration_s;
  json["cameras"] = cameras;
  json["targets_met"] = targets_met(evaluation);
  return json.dump(2);
}

int run_demo(DemoOptions options) {
  const Scene scene = load_scene(options.scene_file);
  const double scene_s = ns_to_seconds(scene.duration_ns());
  if (options.duration_s > scene_s) {
    std::printf(
        "note: the scene lasts %.1f s; the demo runs for that long (raise `duration:` in the scene for "
        "more)\n",
        scene_s);
    options.duration_s = scene_s;
  }
  const fs::path run_dir = options.log_dir.empty()
                               ? fs::temp_directory_path() / ("panoptes-demo-" + std::to_string(getpid()))
                               : fs::path(options.log_dir);
  fs::create_directories(run_dir);
  const fs::path calibration_file = run_dir / "calibration.yaml";
  save_calibration(scene.calibration(), calibration_file);
  fs::path bodies_file;
  if (!scene.body_definitions().empty()) {
    bodies_file = run_dir / "bodies.yaml";
    save_bodies(scene.body_definitions(), bodies_file);
  }

  // Scene time 0 a little in the future, so that every process has started and discovered the
  // others before the first frame.
  const TimeNs epoch = (wall_now_ns() / kNsPerSecond + 3) * kNsPerSecond;
  const TimeNs end = epoch + seconds_to_ns(options.duration_s);

  std::printf("Panoptes demo: %zu simulated cameras, %zu markers, %.0f s (scene %s)\n",
              scene.cameras().size(), scene.marker_names().size(), options.duration_s,
              options.scene_file.c_str());
  std::printf("logs and recordings in %s\n", run_dir.c_str());

  std::vector<std::unique_ptr<Child>> children;
  try {
    children = start_processes(options, scene, calibration_file, bodies_file, run_dir, epoch);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_demo: %s\n", error.what());
    return kExitFailure;
  }

  // Watch as an application would: subscribe to tracks and camera status.
  std::vector<TrackRecord> tracks;
  const int exit_code = watch(options.dds_profile, children, epoch, end, run_dir, tracks);
  for (auto it = children.rbegin(); it != children.rend(); ++it) (*it)->stop(std::chrono::seconds(5));
  children.clear();
  if (exit_code != kExitOk) return exit_code;

  return report_accuracy(scene, tracks, epoch, options);
}

}  // namespace panoptes::demo_run
