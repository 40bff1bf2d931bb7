// SPDX-License-Identifier: Apache-2.0
// panoptes_plan: camera placement for a studio (seed 003 Ch. 4; docs/planner.md). Places cameras
// on a room's mounting surfaces to minimise the occlusion-aware quality metric, or evaluates an
// existing calibration, and writes a calibration file of the plan plus a report.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/errors.h"
#include "panoptes/plan_io/plan_report.h"
#include "panoptes/plan_io/room_file.h"
#include "panoptes/planner/optimizer.h"

namespace fs = std::filesystem;
using namespace panoptes;
using namespace panoptes::planner;

namespace {

struct Arguments {
  fs::path room;
  int cameras = 0;
  fs::path existing;  // --existing / --evaluate
  bool evaluate_only = false;
  bool remove_one = false;
  fs::path out;
  fs::path report;
  fs::path scene_template;
  fs::path scene_out;
  int evaluations = 4000;
  double seconds = 60.0;
  bool cpu_clock = false;
  int starts = 3;
  std::uint64_t seed = 1;
  int threads = 1;
  bool quiet = false;
  std::string objective;  // empty: the room file's (objective key), else its default
};

std::vector<PlannedCamera> load_existing(const fs::path& path, const Room& room) {
  const SystemCalibration calibration = load_calibration(path);
  std::vector<PlannedCamera> cameras;
  for (const auto& camera : calibration.cameras) {
    if (!camera.T_world_cam)
      throw ConfigError(path.string(), "cameras." + camera.id,
                        "has no pose (T_world_cam): cannot be planned around");
    PlannedCamera planned;
    planned.id = camera.id;
    planned.model = camera.model();
    planned.lens = "existing";
    planned.min_depth_m = room.lenses.front().min_depth_m;  // documented: the first lens's depth range
    planned.max_depth_m = room.lenses.front().max_depth_m;
    cameras.push_back(planned);
  }
  if (cameras.empty()) throw ConfigError(path.string(), "cameras", "lists no camera");
  return cameras;
}

void save_plan(const std::vector<PlannedCamera>& cameras, const fs::path& path) {
  SystemCalibration calibration;
  for (const auto& camera : cameras) {
    CameraCalibration c;
    c.id = camera.id;
    c.intrinsics = camera.model.intrinsics();
    c.T_world_cam = camera.model.T_world_cam();
    c.nominal_intrinsics = true;  // a plan's lens, not a chessboard calibration
    calibration.cameras.push_back(c);
  }
  save_calibration(calibration, path);
}

// The template scene (docs/simulator.md) with its cameras replaced by `cameras`: the planned studio
// as panoptes_sim runs it. Rates and the other camera keys come from the template's first camera;
// phases are spread over one frame period; a relative trc.file is made absolute, unless it starts
// with an environment variable.
void save_scene(const std::vector<PlannedCamera>& cameras, const fs::path& template_path,
                const fs::path& path) {
  YAML::Node scene = YAML::Clone(load_yaml_file(template_path));
  YAML::Node first;
  if (scene["cameras"] && scene["cameras"].IsSequence() && scene["cameras"].size() > 0)
    first = scene["cameras"][0];
  const double rate = first && first["rate"] ? first["rate"].as<double>() : 100.0;
  YAML::Node list(YAML::NodeType::Sequence);
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const auto& K = cameras[c].model.intrinsics();
    const RigidTransform& T = cameras[c].model.T_world_cam();
    YAML::Node camera;
    if (first)
      for (const auto& key : first)
        if (key.first.as<std::string>() != "look_at" && key.first.as<std::string>() != "T_world_cam")
          camera[key.first.as<std::string>()] = YAML::Clone(key.second);
    camera["id"] = cameras[c].id;
    camera["width"] = K.width;
    camera["height"] = K.height;
    camera["K"] = std::vector<double>{K.fx, K.fy, K.cx, K.cy};
    camera["T_world_cam"]["q"] = std::vector<double>{T.q.x(), T.q.y(), T.q.z(), T.q.w()};
    camera["T_world_cam"]["t"] = std::vector<double>{T.t.x(), T.t.y(), T.t.z()};
    camera["rate"] = rate;
    camera["phase"] = static_cast<double>(c) / (rate * static_cast<double>(cameras.size()));
    list.push_back(camera);
  }
  scene["cameras"] = list;
  if (scene["trc"] && scene["trc"]["file"]) {
    const std::string file = scene["trc"]["file"].as<std::string>();
    const fs::path trc = file;
    // A file that starts with ${NAME} is whatever the environment says when the scene is run
    // (docs/simulator.md): often an absolute path, so it is kept as written (issue 32).
    if (trc.is_relative() && !file.starts_with("${"))
      scene["trc"]["file"] = fs::absolute(template_path.parent_path() / trc).lexically_normal().string();
  }
  std::ofstream out(path, std::ios::trunc);
  out << "# Written by panoptes_plan from " << template_path.string() << " (docs/planner.md)\n"
      << scene << "\n";
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
}

void print_evaluation(const Evaluation& e, const MetricOptions& metric, std::size_t cameras) {
  std::printf("quality %.6g m (resolution only %.6g m), P(at least %d of %zu cameras see a point) %.4f\n",
              e.quality, e.resolution_only, metric.k_cameras, cameras, e.p_at_least_k);
  std::printf("uncertainty where at least %d cameras see a point %.6g m\n", metric.k_cameras,
              e.seen_uncertainty);
  std::printf("cameras seeing a point:");
  for (std::size_t n = 0; n < e.visible_histogram.size(); ++n)
    std::printf(" %zu: %.3f", n, e.visible_histogram[n]);
  std::printf("\n");
}

// The tracker's predicted error (docs/planner.md, "Validation against the tracker").
void print_tracking(const TrackingPrediction& t) {
  std::printf("predicted tracker RMSE %.6g m, with two-view ambiguity %.6g m\n", t.rmse_m,
              t.rmse_with_ambiguity_m);
  std::printf("predicted tracker RMSE with gaps charged (objective tracker_rmse) %.6g m\n",
              t.rmse_gaps_charged_m);
  std::printf(
      "marker-time seen by one camera %.4f, by two %.4f, by two with a rival in the epipolar band %.4f; "
      "confirmable %.4f of what two or more see\n",
      t.one_view_share, t.two_view_share, t.ambiguous_share, t.confirmable_share);
}

int run(const Arguments& args) {
  RoomFile file = load_room(args.room);
  file.metric.threads = args.threads;
  if (!args.objective.empty()) file.objective = *objective_from_name(args.objective);  // checked by CLI11
  const SampleSet samples =
      draw_samples(file.room, file.occluders, file.sample_points, file.sample_directions, file.sample_seed);
  std::vector<PlannedCamera> fixed;
  if (!args.existing.empty()) fixed = load_existing(args.existing, file.room);

  ReportInput report;
  report.room = &file.room;
  report.samples = &samples;
  report.metric = file.metric;
  report.objective = objective_name(file.objective);
  if (args.evaluate_only || args.remove_one) {
    report.title = "Camera layout: " + args.existing.filename().string();
    report.cameras = fixed;
    report.evaluation = evaluate(fixed, samples, file.room.obstacles, file.metric);
  } else {
    PlanOptions options;
    options.cameras = args.cameras;
    options.fixed = fixed;
    options.evaluations = args.evaluations;
    options.seconds = args.seconds;
    options.cpu_clock = args.cpu_clock;
    options.starts = args.starts;
    options.seed = args.seed;
    options.objective = file.objective;
    options.tracker = file.tracker;
    if (!args.quiet)
      options.progress = [&args](const PlanProgress& p) {
        const std::string phase =
            p.start < args.starts ? "start " + std::to_string(p.start + 1) + "/" + std::to_string(args.starts)
                                  : "refining";
        std::fprintf(stderr, "\rplan: %d/%d evaluations, %s, best %.6g m, %.1f s   ", p.evaluations,
                     args.evaluations, phase.c_str(), p.best, p.seconds);
      };
    const PlanResult result = plan(file.room, samples, file.metric, options);
    if (!args.quiet) std::fprintf(stderr, "\n");
    std::printf("placed %d camera(s)%s in %d evaluations, %.1f s (%.1f CPU s)%s\n", args.cameras,
                fixed.empty() ? "" : (" beside " + std::to_string(fixed.size()) + " existing").c_str(),
                result.evaluations, result.seconds, result.cpu_seconds,
                result.stopped_by_time ? " (stopped by --seconds: not reproducible)" : "");
    std::printf("objective %s %.6g m\n", objective_name(file.objective), result.objective_value);
    report.title = "Camera plan: " + std::to_string(result.cameras.size()) + " cameras";
    report.cameras = result.cameras;
    report.evaluation = result.evaluation;
    report.history = result.history;
    char notes[200];
    std::snprintf(notes, sizeof notes, "Objective %s; %d evaluations, %d starts, seed %llu, %.1f s.",
                  objective_name(file.objective), result.evaluations, args.starts,
                  static_cast<unsigned long long>(args.seed), result.seconds);
    report.notes = notes;
    if (!args.out.empty()) {
      save_plan(result.cameras, args.out);
      std::printf("wrote %s\n", args.out.string().c_str());
    }
  }
  print_evaluation(report.evaluation, file.metric, report.cameras.size());
  report.tracking = predict_tracking(report.cameras, samples, file.room.obstacles, file.metric, file.tracker);
  print_tracking(report.tracking);
  if (args.remove_one || !args.report.empty()) {
    report.removal_costs = removal_costs(report.cameras, samples, file.room.obstacles, file.metric,
                                         file.objective, file.tracker);
  }
  if (args.remove_one) {
    std::vector<std::size_t> order(report.cameras.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](auto a, auto b) { return report.removal_costs[a] < report.removal_costs[b]; });
    const double with_all = file.objective == Objective::kQuality ? report.evaluation.quality
                                                                  : report.tracking.rmse_gaps_charged_m;
    std::printf("objective %s without each camera (cheapest to remove first):\n",
                objective_name(file.objective));
    for (const std::size_t c : order)
      std::printf("  %-12s %.6g m (%+.1f%%)\n", report.cameras[c].id.c_str(), report.removal_costs[c],
                  100.0 * (report.removal_costs[c] / with_all - 1.0));
  }
  if (!args.scene_out.empty()) {
    save_scene(report.cameras, args.scene_template, args.scene_out);
    std::printf("wrote %s\n", args.scene_out.string().c_str());
  }
  if (!args.report.empty()) {
    write_report(report, args.report);
    std::printf("wrote %s\n", (args.report / "report.html").string().c_str());
  }
  return kExitOk;
}

}  // namespace

static int run_command_line(int argc, char** argv) {
  CLI::App app{"panoptes_plan: camera placement for a studio, seed 003 Ch. 4 (docs/planner.md)",
               "panoptes_plan"};
  app.get_formatter()->column_width(34);
  Arguments args;
  app.add_option("--room", args.room,
                 "room file: volume, mounts, obstacles, lenses, metric (docs/planner.md)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--cameras", args.cameras, "cameras to place")->check(CLI::Range(1, 64));
  app.add_option("--existing", args.existing, "calibration file of a rig to add --cameras to")
      ->check(CLI::ExistingFile);
  app.add_option("--evaluate", args.existing, "calibration file to evaluate instead of planning")
      ->check(CLI::ExistingFile);
  app.add_flag("--remove-one", args.remove_one,
               "with --evaluate: the quality without each camera, cheapest first");
  app.add_option("--out", args.out,
                 "calibration file of the plan (panoptes_sim, the demo and calibrate read it)");
  app.add_option("--scene-template", args.scene_template,
                 "a simulator scene whose cameras --scene-out replaces")
      ->check(CLI::ExistingFile);
  app.add_option("--scene-out", args.scene_out,
                 "the template scene with the plan's cameras (panoptes_sim runs it)");
  app.add_option("--report", args.report, "directory for report.html, top.png, side.png, history.png");
  app.add_option("--evaluations", args.evaluations, "metric evaluations the search may spend")
      ->capture_default_str()
      ->check(CLI::Range(10, 100000000));
  app.add_option("--seconds", args.seconds, "time cap; a run it cuts is not reproducible")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1e6));
  app.add_flag("--cpu-clock", args.cpu_clock,
               "--seconds counts this process's CPU time (on a loaded machine), not wall time");
  app.add_option("--starts", args.starts, "independent greedy starts before the iterated search")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--seed", args.seed, "search seed (the samples have their own, in the room file)")
      ->capture_default_str();
  app.add_option("--threads", args.threads, "threads evaluating the metric")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--objective", args.objective,
                 "what the search and --remove-one minimise: q (the seed's quality) or tracker_rmse (the "
                 "predicted tracker RMSE, gaps charged); overrides the room file's objective key")
      ->default_str(objective_name(RoomFile{}.objective))
      ->check(CLI::IsMember({"q", "tracker_rmse"}));
  app.add_flag("--quiet", args.quiet, "no progress line");
  if (const auto code = parse_command_line(app, argc, argv, [&] {
        args.evaluate_only = app.count("--evaluate") > 0;
        if (args.evaluate_only && (app.count("--existing") > 0 || app.count("--cameras") > 0))
          throw CLI::ValidationError("--evaluate", "takes no --existing or --cameras");
        if (args.remove_one && !args.evaluate_only)
          throw CLI::ValidationError("--remove-one", "needs --evaluate");
        if (app.count("--scene-out") != app.count("--scene-template"))
          throw CLI::ValidationError("--scene-out", "and --scene-template go together");
        if (!args.evaluate_only && args.cameras == 0)
          throw CLI::ValidationError("--cameras", "required unless --evaluate is given");
      }))
    return *code;
  try {
    return run(args);
  } catch (const std::invalid_argument& error) {  // the planner refusing the room: name the file
    throw ConfigError(args.room.string(), "", error.what());
  }
}

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_plan", [&] { return run_command_line(argc, argv); });
}
