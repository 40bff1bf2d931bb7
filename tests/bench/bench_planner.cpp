// SPDX-License-Identifier: Apache-2.0
// bench_planner: the placement metric's cost (issue 19): 16 cameras on a ring around a 4 x 4 x 2 m
// volume, 10 000 points, 64 occluder planes, both resolution models, one thread and --threads;
// then, side by side on one thread, a full evaluation against the incremental metric's cost of
// moving one camera (what the optimiser pays per evaluation), for both objectives (q and
// tracker_rmse), and the search's evaluations per CPU second with each objective.
//   bench_planner [--points 10000] [--planes 64] [--cameras 16] [--threads 2] [--repeat 3]
//                 [--plan-evaluations 3000]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <numbers>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/planner/incremental_metric.h"
#include "panoptes/planner/metric.h"
#include "panoptes/planner/optimizer.h"

using namespace panoptes;
using namespace panoptes::planner;

static double cpu_seconds() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

// Each camera in turn moved 0.3 m along the ring's tangent and back, full evaluation vs
// incremental, for `objective`; CPU seconds per move, best of `repeat`.
static void compare_one_camera_moves(const std::vector<PlannedCamera>& rig, const SampleSet& samples,
                                     const Lens& lens, int repeat, Objective objective) {
  const MetricOptions metric;
  const TrackerModel tracker;
  IncrementalMetric incremental(samples, {}, metric, rig.size(), objective, tracker);
  for (std::size_t c = 0; c < rig.size(); ++c) incremental.place(c, rig[c]);
  const auto moved_camera = [&](std::size_t c) {
    const Eigen::Vector3d centre = rig[c].model.center_world();
    return make_camera(rig[c].id, lens,
                       centre + 0.3 * Eigen::Vector3d(-centre.y(), centre.x(), 0).normalized(), {0, 0, 0.9});
  };
  std::vector<PlannedCamera> moved_rig = rig;
  double full = 1e30, moved = 1e30, value_full = 0, value_moved = 0;
  for (int r = 0; r < repeat; ++r) {
    const double begin = cpu_seconds();
    for (std::size_t c = 0; c < rig.size(); ++c) {
      moved_rig[c] = moved_camera(c);
      value_full = objective_value(moved_rig, samples, {}, metric, objective, tracker);
      moved_rig[c] = rig[c];
    }
    const double middle = cpu_seconds();
    for (std::size_t c = 0; c < rig.size(); ++c) {
      value_moved = incremental.place(c, moved_camera(c));
      incremental.undo();
    }
    const double end = cpu_seconds();
    const double n = static_cast<double>(rig.size());
    full = std::min(full, (middle - begin) / n);
    moved = std::min(moved, (end - middle) / n);
  }
  std::printf(
      "%-12s one camera moved (1 thread): full evaluation %.4f CPU s (%.1f/CPU s), incremental %.4f CPU s "
      "(%.1f/CPU s, %.1fx); value of the last move %.9g vs %.9g m\n",
      objective_name(objective), full, 1.0 / full, moved, 1.0 / moved, full / moved, value_full, value_moved);
}

// The search itself (greedy starts, per-camera evolution strategy, iterated local search) on the
// ring's room with its walls as mounts: evaluations per CPU second with `objective`.
static void plan_rate(Room room, const SampleSet& samples, const Lens& lens, int cameras, int evaluations,
                      Objective objective) {
  const Eigen::Vector3d low(-4.5, -4.5, 2.2), span(9.0, 9.0, 0.0), up(0, 0, 0.8);
  room.mounts = {{"south", low, {span.x(), 0, 0}, up},
                 {"west", low, {0, span.y(), 0}, up},
                 {"north", low + Eigen::Vector3d(0, span.y(), 0), {span.x(), 0, 0}, up},
                 {"east", low + Eigen::Vector3d(span.x(), 0, 0), {0, span.y(), 0}, up}};
  room.lenses = {lens};
  PlanOptions options;
  options.cameras = cameras;
  options.evaluations = evaluations;
  options.seconds = 1e6;
  options.objective = objective;
  const PlanResult result = plan(room, samples, {}, options);
  std::printf(
      "%-12s search, %d cameras: %d evaluations in %.2f CPU s: %.0f evaluations per CPU s; "
      "plan's q %.6g m, objective %.6g m\n",
      objective_name(objective), cameras, result.evaluations, result.cpu_seconds,
      result.evaluations / result.cpu_seconds, result.evaluation.quality, result.objective_value);
}

static int run_command_line(int argc, char** argv) {
  CLI::App app{"bench_planner: cost of the camera placement metric (docs/benchmarks.md)"};
  int points = 10000, planes = 64, cameras = 16, threads = 2, repeat = 3, plan_evaluations = 3000;
  app.add_option("--points", points, "sample points")->capture_default_str();
  app.add_option("--planes", planes, "occluder planes per point")->capture_default_str();
  app.add_option("--cameras", cameras, "cameras on the ring")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--threads", threads, "threads of the second measurement")->capture_default_str();
  app.add_option("--repeat", repeat, "best of this many runs")->capture_default_str();
  app.add_option("--plan-evaluations", plan_evaluations,
                 "budget of the search measured with each objective (8 cameras, 1500 of the points)")
      ->capture_default_str();
  if (const auto code = parse_command_line(app, argc, argv)) return *code;

  Room room;
  room.volume = {Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(2, 2, 2)};
  const SampleSet samples = draw_samples(room, {planes}, points, 32, 1);
  Lens lens;
  lens.intrinsics.width = 1280;
  lens.intrinsics.height = 1024;
  lens.intrinsics.fx = lens.intrinsics.fy = 800;
  lens.intrinsics.cx = 639.5;
  lens.intrinsics.cy = 511.5;
  std::vector<PlannedCamera> rig;
  for (int c = 0; c < cameras; ++c) {
    const double a = 2.0 * std::numbers::pi * c / cameras;
    rig.push_back(make_camera("c" + std::to_string(c), lens,
                              {4.5 * std::cos(a), 4.5 * std::sin(a), 2.6 + 0.2 * (c % 2)}, {0, 0, 0.9}));
  }
  std::printf(
      "bench_planner: %d cameras x %d points x %d occluder planes (x 32 directions for ray pyramids)\n",
      cameras, points, planes);
  std::printf("%-11s %8s %10s %12s %8s\n", "model", "threads", "seconds", "quality m", "P(>=2)");
  for (const auto model : {ResolutionModel::kCovariance, ResolutionModel::kPyramid}) {
    for (const int t : {1, threads}) {
      MetricOptions metric;
      metric.resolution = model;
      metric.threads = t;
      double best = 1e30;
      Evaluation e;
      for (int r = 0; r < repeat; ++r) {
        const auto begin = std::chrono::steady_clock::now();
        e = evaluate(rig, samples, {}, metric);
        best =
            std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
      }
      std::printf("%-11s %8d %10.3f %12.6g %8.4f\n",
                  model == ResolutionModel::kPyramid ? "pyramid" : "covariance", t, best, e.quality,
                  e.p_at_least_k);
    }
  }
  for (const Objective objective : {Objective::kQuality, Objective::kTrackerRmse})
    compare_one_camera_moves(rig, samples, lens, repeat, objective);
  const SampleSet plan_samples = draw_samples(room, {planes}, std::min(points, 1500), 32, 1);
  for (const Objective objective : {Objective::kQuality, Objective::kTrackerRmse})
    plan_rate(room, plan_samples, lens, 8, plan_evaluations, objective);
  return 0;
}

int main(int argc, char** argv) {
  return panoptes::run_program("bench_planner", [&] { return run_command_line(argc, argv); });
}
