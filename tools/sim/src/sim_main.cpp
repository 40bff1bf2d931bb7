// SPDX-License-Identifier: Apache-2.0
// panoptes_sim: writes what a simulated scene's cameras would see (calibration, features, images)
// and the ground truth, for offline tests and evaluation. Scene format: docs/simulator.md.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/jsonl.h"
#include "panoptes/landmarks_file.h"
#include "panoptes/pgm.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/sim_ptz/sim_ptz.h"
#include "panoptes/simulator.h"

namespace fs = std::filesystem;
using namespace panoptes;

namespace {

constexpr TimeNs kDefaultEpochNs = 1'700'000'000'000'000'000;
constexpr TimeNs kTruthStepNs = 10 * kNsPerMillisecond;

// JsonlWriter appends; a rerun into the same directory must replace, not extend, old output.
JsonlWriter fresh_jsonl(const fs::path& path) {
  fs::remove(path);
  return JsonlWriter(path);
}

// Frames whose mid-exposure lies in [0, duration) of scene time.
nlohmann::json truth_line(const Scene& scene, TimeNs scene_time_ns, TimeNs epoch_ns) {
  nlohmann::json line;
  line["stamp_ns"] = epoch_ns + scene_time_ns;
  nlohmann::json markers = nlohmann::json::array();
  for (const MarkerTruth& marker : scene.markers_at(scene_time_ns)) {
    if (!marker.valid) continue;
    markers.push_back({{"name", marker.name}, {"p", {marker.p.x(), marker.p.y(), marker.p.z()}}});
  }
  line["markers"] = std::move(markers);
  nlohmann::json bodies = nlohmann::json::array();
  for (const BodyTruth& body : scene.bodies_at(scene_time_ns)) {
    const RigidTransform& T = body.T_world_body;
    bodies.push_back({{"name", body.name},
                      {"p", {T.t.x(), T.t.y(), T.t.z()}},
                      {"q", {T.q.x(), T.q.y(), T.q.z(), T.q.w()}}});
  }
  line["bodies"] = std::move(bodies);
  const std::vector<ChainTruth> chain_truths = scene.chains_at(scene_time_ns);
  if (chain_truths.empty()) return line;
  nlohmann::json chains = nlohmann::json::array();
  for (const ChainTruth& chain : chain_truths) {
    nlohmann::json markers_json = nlohmann::json::array();
    for (const Eigen::Vector3d& p : chain.markers) markers_json.push_back({p.x(), p.y(), p.z()});
    chains.push_back({{"name", chain.name},
                      {"angles", chain.angles},
                      {"markers", std::move(markers_json)},
                      {"tip", {chain.tip.x(), chain.tip.y(), chain.tip.z()}}});
  }
  line["chains"] = std::move(chains);
  return line;
}

struct Options {
  std::string scene;
  std::string out;
  std::string out_dir;
  std::string camera;
  TimeNs epoch_ns = kDefaultEpochNs;
  double duration_s = 0.0;  // 0: the scene's
  std::int64_t frames = 1;
  std::int64_t first = 0;
};

int run_calibration(const Options& options) {
  const Scene scene = Scene::load(options.scene);
  save_calibration(scene.calibration(), options.out);
  std::cout << "wrote " << scene.cameras().size() << " cameras to " << options.out << "\n";
  return 0;
}

int run_features(const Options& options) {
  const Scene scene = Scene::load(options.scene);
  const TimeNs duration_ns =
      options.duration_s > 0.0 ? seconds_to_ns(options.duration_s) : scene.duration_ns();
  const fs::path dir = options.out_dir;
  fs::create_directories(dir);
  save_calibration(scene.calibration(), dir / "calibration.yaml");
  if (!scene.body_definitions().empty()) save_bodies(scene.body_definitions(), dir / "bodies.yaml");
  if (!scene.landmarks().empty())
    save_landmarks(scene.landmarks(), dir / "landmarks.yaml", scene.rig_markers());

  for (const SimCameraConfig& config : scene.cameras()) {
    const CameraSimulator camera(scene, config.calibration.id);
    const fs::path path = dir / (config.calibration.id + ".jsonl");
    JsonlWriter writer = fresh_jsonl(path);
    std::int64_t frames = 0;
    std::size_t blobs = 0;
    std::size_t markers = 0;
    std::size_t false_blobs = 0;
    std::size_t late = 0;
    const TimeNs on_time_delay = config.exposure_ns / 2 + config.latency_ns;
    const CameraSimulator::FrameRange range = camera.frames_in(0, duration_ns);
    for (std::int64_t k = range.first; k < range.end; ++k) {
      FeatureFrame frame = camera.features(k);
      frame.stamp_ns += options.epoch_ns;
      frame.received_ns += options.epoch_ns;
      blobs += frame.blobs.size();
      markers += camera.visible_markers(k).size();
      false_blobs += static_cast<std::size_t>(camera.false_blob_count(k));
      if (frame.received_ns - options.epoch_ns > camera.frame_time_ns(k) + on_time_delay) ++late;
      writer.write(frame);
      ++frames;
    }
    writer.flush();
    // Spots merged away: every marker spot and false blob is one blob unless it merged.
    const std::size_t merged = markers + false_blobs - blobs;
    const double per_frame = frames > 0 ? 1.0 / static_cast<double>(frames) : 0.0;
    char stats[160];
    std::snprintf(stats, sizeof stats,
                  " (per frame: %.2f markers, %.2f false blobs, %.3f spots merged away; %zu late frames)",
                  static_cast<double>(markers) * per_frame, static_cast<double>(false_blobs) * per_frame,
                  static_cast<double>(merged) * per_frame, late);
    std::cout << config.calibration.id << ": " << frames << " frames, " << blobs << " blobs" << stats
              << " -> " << path.string() << std::endl;
  }

  const fs::path truth_path = dir / "truth.jsonl";
  JsonlWriter truth = fresh_jsonl(truth_path);
  std::int64_t lines = 0;
  for (TimeNs t = 0; t <= duration_ns; t += kTruthStepNs, ++lines) {
    truth.write_line(truth_line(scene, t, options.epoch_ns).dump());
  }
  truth.flush();
  std::cout << "truth: " << lines << " lines -> " << truth_path.string() << std::endl;
  return 0;
}

int run_render(const Options& options) {
  const Scene scene = Scene::load(options.scene);
  if (scene.find_camera(options.camera) == nullptr) {
    std::cerr << "panoptes_sim: " << options.scene << ": no camera '" << options.camera << "'\n";
    return 2;
  }
  const CameraSimulator camera(scene, options.camera);
  const fs::path dir = options.out_dir;
  fs::create_directories(dir);
  JsonlWriter truth = fresh_jsonl(dir / "features_truth.jsonl");
  double render_seconds = 0.0;
  for (std::int64_t k = options.first; k < options.first + options.frames; ++k) {
    const auto start = std::chrono::steady_clock::now();
    const Image image = camera.render(k);
    render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%06lld.pgm", static_cast<long long>(k));
    write_pgm(image, dir / name);
    FeatureFrame frame = camera.features(k);
    frame.stamp_ns += options.epoch_ns;
    frame.received_ns += options.epoch_ns;
    truth.write(frame);
  }
  truth.flush();
  std::printf("%s: %lld frames of %dx%d (%d bit) -> %s; render %.3f ms/frame\n", options.camera.c_str(),
              static_cast<long long>(options.frames), camera.config().calibration.intrinsics.width,
              camera.config().calibration.intrinsics.height, camera.config().bits, dir.string().c_str(),
              1e3 * render_seconds / static_cast<double>(std::max<std::int64_t>(options.frames, 1)));
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{
      "Panoptes simulator: calibration, features, images and ground truth of a scene (docs/simulator.md)",
      "panoptes_sim"};
  app.require_subcommand(1);
  app.option_defaults()->always_capture_default();  // --help shows every default
  Options options;

  CLI::App* calibration =
      app.add_subcommand("calibration", "Write the scene's cameras as a calibration file");
  calibration->add_option("--scene", options.scene, "Scene file (YAML)")->required();
  calibration->add_option("--out", options.out, "Calibration file to write (YAML)")->required();

  CLI::App* features = app.add_subcommand("features",
                                          "Write ideal features per camera (<id>.jsonl), calibration.yaml, "
                                          "truth.jsonl, bodies.yaml, landmarks.yaml");
  features->add_option("--scene", options.scene, "Scene file (YAML)")->required();
  features->add_option("--out-dir", options.out_dir, "Output directory (created if missing)")->required();
  features->add_option("--epoch-ns", options.epoch_ns, "Absolute stamp of scene time 0 (ns)");
  features->add_option("--duration", options.duration_s, "Seconds of scene time")
      ->check(positive_number())
      ->default_str("the scene's");

  CLI::App* render =
      app.add_subcommand("render", "Render one camera's frames as PGM images plus their features");
  render->add_option("--scene", options.scene, "Scene file (YAML)")->required();
  render->add_option("--camera", options.camera, "Camera id")->required();
  render->add_option("--frames", options.frames, "Number of frames")->required()->check(positive_number());
  render->add_option("--first", options.first, "First frame index");
  render->add_option("--out-dir", options.out_dir, "Output directory (created if missing)")->required();
  render->add_option("--epoch-ns", options.epoch_ns, "Absolute stamp of scene time 0 (ns)");

  sim_tool::PtzRunOptions ptz_options;
  CLI::App* ptz = sim_tool::add_ptz_subcommand(app, ptz_options);

  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;

  if (calibration->parsed()) return run_calibration(options);
  if (features->parsed()) return run_features(options);
  if (ptz->parsed()) return sim_tool::run_ptz(ptz_options);
  return run_render(options);
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_sim", [&] { return run(argc, argv); });
}
