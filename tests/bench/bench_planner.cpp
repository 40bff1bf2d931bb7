// SPDX-License-Identifier: Apache-2.0
// bench_planner: the placement metric's cost (issue 19): 16 cameras on a ring around a 4 x 4 x 2 m
// volume, 10 000 points, 64 occluder planes, both resolution models, one thread and --threads;
// then, side by side on one thread, a full evaluation against the incremental metric's cost of
// moving one camera (what the optimiser pays per evaluation).
//   bench_planner [--points 10000] [--planes 64] [--cameras 16] [--threads 2] [--repeat 3]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <numbers>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/planner/incremental_metric.h"
#include "panoptes/planner/metric.h"

using namespace panoptes;
using namespace panoptes::planner;

// Each camera in turn moved 0.3 m along the ring's tangent and back, full evaluation vs incremental.
static void compare_one_camera_moves(const std::vector<PlannedCamera>& rig, const SampleSet& samples,
                                     const Lens& lens, int repeat) {
  MetricOptions metric;
  IncrementalMetric incremental(samples, {}, metric, rig.size());
  for (std::size_t c = 0; c < rig.size(); ++c) incremental.place(c, rig[c]);
  std::vector<PlannedCamera> moved_rig = rig;
  double full = 1e30, moved = 1e30, q_full = 0, q_moved = 0;
  for (int r = 0; r < repeat; ++r) {
    const auto begin = std::chrono::steady_clock::now();
    for (std::size_t c = 0; c < rig.size(); ++c) {
      const Eigen::Vector3d centre = rig[c].model.center_world();
      moved_rig[c] =
          make_camera(rig[c].id, lens,
                      centre + 0.3 * Eigen::Vector3d(-centre.y(), centre.x(), 0).normalized(), {0, 0, 0.9});
      q_full = evaluate(moved_rig, samples, {}, metric).quality;
      moved_rig[c] = rig[c];
    }
    const auto middle = std::chrono::steady_clock::now();
    for (std::size_t c = 0; c < rig.size(); ++c) {
      const Eigen::Vector3d centre = rig[c].model.center_world();
      q_moved = incremental.place(
          c,
          make_camera(rig[c].id, lens,
                      centre + 0.3 * Eigen::Vector3d(-centre.y(), centre.x(), 0).normalized(), {0, 0, 0.9}));
      incremental.undo();
    }
    const auto end = std::chrono::steady_clock::now();
    const double n = static_cast<double>(rig.size());
    full = std::min(full, std::chrono::duration<double>(middle - begin).count() / n);
    moved = std::min(moved, std::chrono::duration<double>(end - middle).count() / n);
  }
  std::printf(
      "one camera moved (covariance, 1 thread): full evaluation %.4f s, incremental %.4f s (%.1fx); "
      "quality of the last move %.6g vs %.6g m\n",
      full, moved, full / moved, q_full, q_moved);
}

static int run_command_line(int argc, char** argv) {
  CLI::App app{"bench_planner: cost of the camera placement metric (docs/benchmarks.md)"};
  int points = 10000, planes = 64, cameras = 16, threads = 2, repeat = 3;
  app.add_option("--points", points, "sample points")->capture_default_str();
  app.add_option("--planes", planes, "occluder planes per point")->capture_default_str();
  app.add_option("--cameras", cameras, "cameras on the ring")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--threads", threads, "threads of the second measurement")->capture_default_str();
  app.add_option("--repeat", repeat, "best of this many runs")->capture_default_str();
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
  compare_one_camera_moves(rig, samples, lens, repeat);
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run_command_line(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_planner: %s\n", error.what());
    return 1;
  }
}
