// SPDX-License-Identifier: Apache-2.0
// The body filter against a synchronous snapshot solve on a grid (issue 35 item 4; docs/bodies.md,
// "The grid"): rigs x constellations x speeds, every cell with the default configuration. The
// snapshot solves each body at every instant of a synchronous copy of the rig from all its
// cameras at once; the filter gets the asynchronous rig, one camera frame at a time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <vector>

#include "body_scene_fixtures.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/simulator.h"

namespace panoptes::estimator {
namespace {

using namespace body_fixtures;  // the shared scene helpers (body_scene_fixtures.h)

struct GridCamera {
  const char* eye;
  const char* target;
  int rate;
  const char* phase;
};

struct GridRig {
  const char* name;
  std::vector<GridCamera> cameras;
};

// Three layouts around a volume centred near (0, 0, 1): a ring of six at 3.2 m (the issue's
// rig), four in the corners of a room, eight on a ceiling. Rates 90-120 Hz, different phases.
const std::vector<GridRig>& grid_rigs() {
  static const std::vector<GridRig> rigs = {
      {"ring6",
       {{"[3.2, 0.0, 2.2]", "[0, 0, 1.0]", 90, "0.0"},
        {"[1.6, 2.77, 2.0]", "[0, 0, 1.0]", 100, "0.0031"},
        {"[-1.6, 2.77, 2.4]", "[0, 0, 1.0]", 110, "0.0057"},
        {"[-3.2, 0.0, 2.1]", "[0, 0, 1.0]", 120, "0.0013"},
        {"[-1.6, -2.77, 2.3]", "[0, 0, 1.0]", 95, "0.0079"},
        {"[1.6, -2.77, 2.0]", "[0, 0, 1.0]", 105, "0.0042"}}},
      {"corner4",
       {{"[2.6, 2.4, 2.5]", "[0, 0, 0.9]", 100, "0.0"},
        {"[-2.5, 2.6, 2.4]", "[0, 0, 0.9]", 120, "0.0047"},
        {"[-2.6, -2.5, 2.6]", "[0, 0, 0.9]", 110, "0.0021"},
        {"[2.5, -2.6, 2.3]", "[0, 0, 0.9]", 90, "0.0066"}}},
      {"ceiling8",
       {{"[2.2, 0.0, 3.0]", "[0.3, 0, 1.0]", 100, "0.0"},
        {"[1.6, 1.6, 3.0]", "[0.2, 0.2, 1.0]", 110, "0.0023"},
        {"[0.0, 2.2, 3.0]", "[0, 0.3, 1.0]", 120, "0.0051"},
        {"[-1.6, 1.6, 3.0]", "[-0.2, 0.2, 1.0]", 90, "0.0017"},
        {"[-2.2, 0.0, 3.0]", "[-0.3, 0, 1.0]", 95, "0.0074"},
        {"[-1.6, -1.6, 3.0]", "[-0.2, -0.2, 1.0]", 105, "0.0038"},
        {"[0.0, -2.2, 3.0]", "[0, -0.3, 1.0]", 115, "0.0062"},
        {"[1.6, -1.6, 3.0]", "[0.2, -0.2, 1.0]", 100, "0.0089"}}},
  };
  return rigs;
}

struct GridConstellations {
  const char* name;
  std::vector<SceneBody> bodies;
};

// Issue 16's three bodies with their oscillations in phase (as the grid was measured).
std::vector<SceneBody> small_bodies_in_phase() {
  std::vector<SceneBody> bodies = small_fast_bodies();
  for (SceneBody& body : bodies) body.rot_phase = "[0, 0, 0]";
  return bodies;
}

// "small": issue 16's three bodies, 8-12 cm; "large": a head (4 markers, 19 cm), a tool (5, 22 cm)
// and a six-marker frame (25 cm). Each body moves on a Lissajous path and oscillates about three
// axes; the frequencies are those at 2 rad/s and scale with the cell's speed.
const std::vector<GridConstellations>& grid_constellations() {
  static const std::vector<GridConstellations> sets = {
      {"small", small_bodies_in_phase()},
      {"large",
       {{"head",
         "[[0.0, 0.0, 0.0], [0.16, 0.0, 0.02], [0.05, 0.19, 0.0], [-0.07, 0.08, 0.10]]",
         "[0.4, 0.3, 1.1]",
         {0.25, 0.2, 0.1},
         {1.2, 1.0, 1.4},
         "[0, 1, 2]",
         {0.3, 0.3, 0.3},
         {0.65, 0.7, 0.55},
         "[0, 0, 0]",
         "[0, 0, 0, 1]"},
        {"tool",
         "[[0.0, 0.0, 0.0], [0.22, 0.0, 0.0], [0.09, 0.12, 0.0], [-0.07, 0.15, 0.04], [0.15, -0.08, 0.09]]",
         "[-0.4, 0.2, 1.0]",
         {0.2, 0.25, 0.1},
         {1.1, 1.25, 1.5},
         "[2, 0.3, 1]",
         {0.35, 0.25, 0.3},
         {0.6, 0.75, 0.6},
         "[0, 0, 0]",
         "[0.0, 0.0, 0.7071068, 0.7071068]"},
        {"frame",
         "[[0.0, 0.0, 0.0], [0.25, 0.0, 0.0], [0.0, 0.18, 0.0], [0.21, 0.16, 0.03], [0.11, -0.05, 0.08], "
         "[-0.04, 0.09, 0.12]]",
         "[0.0, -0.45, 0.9]",
         {0.22, 0.15, 0.1},
         {1.25, 1.45, 1.3},
         "[0.7, 2.2, 0.1]",
         {0.28, 0.32, 0.25},
         {0.75, 0.55, 0.7},
         "[0, 0, 0]",
         "[0, 0, 0, 1]"}}},
  };
  return sets;
}

// A cell's scene: `speed_radps` is the bodies' peak angular rate (bodies_yaml), the peak linear
// acceleration about 10 m/s² per rad/s (5, 20 and 40 m/s² at 0.5, 2 and 4 rad/s). `synchronous`:
// every camera at 100 Hz with phase 0 (the snapshot's rig).
std::string grid_scene(const GridRig& rig, const GridConstellations& set, double speed_radps,
                       bool synchronous, double duration_s, int seed) {
  std::string yaml =
      "seed: " + std::to_string(seed) + "\nduration: " + std::to_string(duration_s) + R"(
defaults:
  width: 1280
  height: 1024
  K: [1000.0, 1000.0, 639.5, 511.5]
  pixel_noise: 1.0
  centroid_noise: )" +
      std::string(std::getenv("BODY_GRID_CENTROID_NOISE") ? std::getenv("BODY_GRID_CENTROID_NOISE") : "0.1") +
      R"(
cameras:
)";
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const GridCamera& camera = rig.cameras[c];
    yaml += "  - {id: c" + std::to_string(c) + ", look_at: {eye: " + camera.eye +
            ", target: " + camera.target +
            "}, rate: " + (synchronous ? std::string("100") : std::to_string(camera.rate)) +
            ", phase: " + (synchronous ? "0.0" : camera.phase) + "}\n";
  }
  return yaml + bodies_yaml(set.bodies, speed_radps);
}

struct CellResult {
  std::string cell;
  double speed = 0;
  double ratio_p = 0, ratio_a = 0, tracked = 0;
  std::size_t wrong = 0;
};

// The candidates docs/bodies.md measured, by environment variable (unset: the defaults); with
// any of them set the test reports without judging.
bool experiment_options(TrackerOptions& options) {
  bool any = false;
  const auto number = [&](const char* name, auto& field, double scale) {
    if (const char* v = std::getenv(name)) {
      field = static_cast<std::remove_reference_t<decltype(field)>>(std::atof(v) * scale);
      any = true;
    }
  };
  number("BODY_GRID_JERK", options.bodies.noise.jerk, 1.0);
  number("BODY_GRID_ANGULAR_JERK", options.bodies.noise.angular_jerk, 1.0);
  number("BODY_GRID_SIGMA_PX", options.bodies.measurement_noise_px, 1.0);
  number("BODY_GRID_MAX_SCALE", options.bodies.process_noise_max_scale, 1.0);
  number("BODY_GRID_ADAPT_GAIN", options.bodies.process_noise_adapt_gain, 1.0);
  number("BODY_GRID_ADAPT_WEIGHT", options.bodies.process_noise_adapt_weight, 1.0);
  number("BODY_GRID_ADAPT_CORRELATION", options.bodies.process_noise_adapt_correlation, 1.0);
  return any || std::getenv("BODY_GRID_CENTROID_NOISE") != nullptr;
}

// Every cell of the grid with `options`; one line per body, then the worst cell per speed.
std::vector<CellResult> run_grid(const TrackerOptions& options, const char* label) {
  std::printf(
      "%s\ncell (rig/set/speed/body)      | peak a m/s² w rad/s | filter: tracked wrong, mm deg | "
      "snapshot: solved, mm deg | ratio mm deg\n",
      label);
  std::vector<CellResult> cells;
  for (const GridRig& rig : grid_rigs()) {
    for (const GridConstellations& set : grid_constellations()) {
      for (const double speed : {0.5, 2.0, 4.0}) {
        const Scene async_scene = Scene::from_yaml_string(grid_scene(rig, set, speed, false, 6.0, 71));
        const Scene sync_scene = Scene::from_yaml_string(grid_scene(rig, set, speed, true, 6.0, 71));
        EXPECT_TRUE(distinguishability_warnings(async_scene.body_definitions()).empty()) << set.name;
        const auto snapshot = run_snapshot(sync_scene, 0.5);
        const SceneRun filter = run_scene(async_scene, 0.5, {}, 0, 0, 1e9, options);
        EXPECT_EQ(filter.bodies.size(), set.bodies.size()) << rig.name << "/" << set.name;
        for (const auto& [name, f] : filter.bodies) {
          const BodyErrors& s = snapshot.at(name);
          const auto [accel, rate] = peak_motion(async_scene, name);
          char cell[96];
          std::snprintf(cell, sizeof cell, "%s/%s/%.1f/%s", rig.name, set.name, speed, name.c_str());
          const CellResult r{cell,        speed,  f.rmse_mm() / s.rmse_mm(), f.rmse_deg() / s.rmse_deg(),
                             f.tracked(), f.wrong};
          std::printf("%-30s | %5.1f %5.2f | %6.2f%% %3zu, %.4f %.4f | %6.2f%%, %.4f %.4f | %.3f %.3f\n",
                      cell, accel, rate, 100.0 * f.tracked(), f.wrong, f.rmse_mm(), f.rmse_deg(),
                      100.0 * s.tracked(), s.rmse_mm(), s.rmse_deg(), r.ratio_p, r.ratio_a);
          EXPECT_GE(s.tracked(), 0.98) << cell;  // the reference really runs
          EXPECT_EQ(s.wrong, 0u) << cell;
          EXPECT_NEAR(rate, speed, 0.1 * speed + 0.05) << cell;  // the scene is what it says
          EXPECT_LE(accel, 10.5 * speed) << cell;
          cells.push_back(r);
        }
      }
    }
  }
  return cells;
}

struct Worst {
  double ratio_p = 0, ratio_a = 0, tracked = 1;
};

Worst worst_at(const std::vector<CellResult>& cells, double speed, const char* label) {
  Worst w;
  std::string cell_p, cell_a, cell_t;
  for (const CellResult& c : cells) {
    if (c.speed != speed) continue;
    if (c.ratio_p > w.ratio_p) w.ratio_p = c.ratio_p, cell_p = c.cell;
    if (c.ratio_a > w.ratio_a) w.ratio_a = c.ratio_a, cell_a = c.cell;
    if (c.tracked < w.tracked) w.tracked = c.tracked, cell_t = c.cell;
  }
  std::printf("%s, %.1f rad/s: worst position %.3f (%s), orientation %.3f (%s), tracked %.2f%% (%s)\n", label,
              speed, w.ratio_p, cell_p.c_str(), w.ratio_a, cell_a.c_str(), 100.0 * w.tracked, cell_t.c_str());
  return w;
}

// Issue 35 item 4: position ≤ 0.8× and orientation ≤ 0.6× the snapshot, ≥ 98% tracked, at every
// speed. A causal filter has to extrapolate to the newest frame and cannot reach that in position
// (docs/bodies.md, "The grid"); with 20 ms of smoothing it is met in every cell (orientation at
// 4 rad/s 0.575×, since the smoother has its own filter). The bounds without smoothing are today's
// figures with a margin.
struct Bound {
  double speed, ratio_p, ratio_a, tracked;
};

void check_grid(int smoothing_ms, const std::vector<Bound>& bounds) {
  TrackerOptions options;
  const bool experiment = experiment_options(options);
  options.bodies.smoothing_ns = smoothing_ms * kNsPerMillisecond;
  const std::string label = std::string(experiment ? "body grid (candidate)" : "body grid (defaults)") +
                            ", smoothing " + std::to_string(smoothing_ms) + " ms";
  const auto cells = run_grid(options, label.c_str());
  EXPECT_EQ(cells.size(), 3u * 3u * 6u);
  for (const Bound& b : bounds) {
    const Worst w = worst_at(cells, b.speed, label.c_str());
    if (experiment) continue;
    EXPECT_LE(w.ratio_p, b.ratio_p) << b.speed;
    EXPECT_LE(w.ratio_a, b.ratio_a) << b.speed;
    EXPECT_GE(w.tracked, b.tracked) << b.speed;
  }
}

TEST(BodyGrid, FilterAgainstTheSynchronousSnapshotOnRigsConstellationsAndSpeeds) {
  check_grid(0, {{0.5, 1.15, 0.9, 0.99}, {2.0, 1.75, 1.05, 0.99}, {4.0, 2.0, 1.45, 0.99}});
}

TEST(BodyGrid, SmoothedFilterAgainstTheSynchronousSnapshotOnRigsConstellationsAndSpeeds) {
  check_grid(20, {{0.5, 0.8, 0.6, 0.98}, {2.0, 0.8, 0.6, 0.98}, {4.0, 0.8, 0.6, 0.98}});
}

}  // namespace
}  // namespace panoptes::estimator
