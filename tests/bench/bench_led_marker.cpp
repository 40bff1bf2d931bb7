// SPDX-License-Identifier: Apache-2.0
// bench_led_marker: time per 7-LED marker pose on one thread (seed 004 §4.1 reports ~0.6 ms per
// additional marker; goal <= 0.05 ms). Precomputed synthetic frames of the paper's marker
// (2048 x 2048 camera, f = 1600 px, 0.5-7.5 m, tilts 20-76 degrees, 0.1 px centroid noise, points
// shuffled) are processed by LedMarkerDetector::detect_cluster (identification, cross-ratio,
// homography, LM, second minimum, pointer LED, final LM); then whole frames with three markers by
// LedMarkerDetector::detect (adds k-means), reported per marker.
//   bench_led_marker [--json] [--frames <n>] [--repeat <n>] [--seed <n>]
// With --json the last line of output is one JSON object (docs/benchmarks.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <numeric>
#include <random>
#include <vector>

#include <CLI/CLI.hpp>

#include "led_marker_fixtures.h"
#include "panoptes/cli.h"
#include "panoptes/estimator/led_marker.h"
#include "panoptes/process.h"

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using panoptes::RigidTransform;
namespace est = panoptes::estimator;

using panoptes::led_marker_fixtures::kFocal;
using panoptes::led_marker_fixtures::paper_leds;
const auto make_pose = panoptes::led_marker_fixtures::marker_pose;

void add_marker(const est::LedMarkerModel& model, const RigidTransform& T, std::mt19937_64& rng,
                std::vector<Vector2d>& out) {
  std::normal_distribution<double> noise(0.0, 0.1 / kFocal);
  for (const Vector3d& p : model.leds()) {
    const Vector3d q = T.apply(p);
    out.push_back(q.head<2>() / q.z() + Vector2d(noise(rng), noise(rng)));
  }
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int run(int argc, char** argv) {
  CLI::App app{"bench_led_marker: time per 7-LED marker pose (identification + pose), one thread",
               "bench_led_marker"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  bool json = false;
  int frames = 2000, repeat = 20;
  std::uint64_t seed = 1;
  app.add_flag("--json", json, "print one JSON object on the last line");
  app.add_option("--frames", frames, "synthetic frames per pass")->check(CLI::PositiveNumber);
  app.add_option("--repeat", repeat, "passes over the frames")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "random seed");
  if (auto code = panoptes::parse_command_line(app, argc, argv)) return *code;

  const std::vector<est::LedMarkerModel> models = {
      est::LedMarkerModel::from_points("a", paper_leds(0.0759, 0.0379)),
      est::LedMarkerModel::from_points("b", paper_leds(0.0720, 0.0320)),
      est::LedMarkerModel::from_points("c", paper_leds(0.0800, 0.0450))};
  const est::LedMarkerDetector detector(models);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);

  // Single markers, shuffled.
  std::vector<std::vector<Vector2d>> singles;
  for (int k = 0; k < frames; ++k) {
    const double s = double(k) / std::max(1, frames - 1), z = 0.5 + 7.0 * s;
    const double tilt = (20 + (s < 0.25 ? 56 : 30) * u(rng)) * M_PI / 180;
    std::vector<Vector2d> p;
    add_marker(models[0],
               make_pose(0.1 * z * (u(rng) - 0.5), 0.1 * z * (u(rng) - 0.5), z, tilt, 2 * M_PI * u(rng),
                         2 * M_PI * u(rng)),
               rng, p);
    std::shuffle(p.begin(), p.end(), rng);
    singles.push_back(std::move(p));
  }
  // Frames with three markers side by side.
  std::vector<std::vector<Vector2d>> triples;
  for (int k = 0; k < frames; ++k) {
    const double z = 1.0 + 3.0 * u(rng);
    std::vector<Vector2d> p;
    for (int m = 0; m < 3; ++m)
      add_marker(models[m],
                 make_pose((m - 1) * 0.3 * z, 0.05 * z * (u(rng) - 0.5), z, (20 + 30 * u(rng)) * M_PI / 180,
                           2 * M_PI * u(rng), 2 * M_PI * u(rng)),
                 rng, p);
    std::shuffle(p.begin(), p.end(), rng);
    triples.push_back(std::move(p));
  }

  const std::array<int, 7> cluster = {0, 1, 2, 3, 4, 5, 6};
  std::size_t found_single = 0, found_triple = 0;
  std::vector<double> pass_single, pass_triple;
  for (int r = 0; r < repeat; ++r) {
    std::size_t found = 0;
    double t0 = now_s();
    for (const auto& p : singles) found += detector.detect_cluster(p, cluster).has_value();
    pass_single.push_back((now_s() - t0) / frames);
    found_single = found;
    found = 0;
    t0 = now_s();
    for (const auto& p : triples) found += detector.detect(p).size();
    pass_triple.push_back((now_s() - t0) / (3.0 * frames));
    found_triple = found;
  }
  std::sort(pass_single.begin(), pass_single.end());
  std::sort(pass_triple.begin(), pass_triple.end());
  const double single_ms = pass_single[pass_single.size() / 2] * 1e3;
  const double triple_ms = pass_triple[pass_triple.size() / 2] * 1e3;
  std::printf(
      "single marker (identification + cross-ratio + pose): %.4f ms per marker (median of %d passes), "
      "%zu/%d found\n",
      single_ms, repeat, found_single, frames);
  std::printf("three markers per frame (k-means + the above):       %.4f ms per marker, %zu/%d found\n",
              triple_ms, found_triple, 3 * frames);
  std::printf("seed 004: ~0.6 ms per marker; goal <= 0.05 ms\n");
  if (json)
    std::printf(
        "{\"frames\": %d, \"repeat\": %d, \"ms_per_marker\": %.5f, \"ms_per_marker_with_kmeans\": %.5f, "
        "\"found\": %zu, \"found_with_kmeans\": %zu}\n",
        frames, repeat, single_ms, triple_ms, found_single, found_triple);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_led_marker", [&] { return run(argc, argv); });
}
