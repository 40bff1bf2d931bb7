// SPDX-License-Identifier: Apache-2.0
// The surface tracker on issue 22's LumiPoint scene (seeded): a 3 × 1 m wall seen by three
// asynchronous 100 Hz cameras with overlapping views, five laser spots moving at up to 3 m/s with
// pen-up/pen-down every 0.3–2 s, 0.2 px centroid noise. Every stroke must begin and end within
// 20 ms of the truth, none split or merged (overlaps give one stroke, not two), position RMSE
// ≤ 0.5 mm on the surface. Also: what it counts and drops.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "panoptes/surface/surface_tracker.h"
#include "surface_scene.h"

namespace panoptes::surface {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct TruthStroke {
  int spot = 0;
  double begin_s = 0, end_s = 0;
};

// A spot's path: two sinusoids per axis, bounded inside the wall, at most 3 m/s.
struct SpotPath {
  double omega[2][2]{}, phase[2][2]{};
  Eigen::Vector2d at(double t) const {
    const double x = 1.5 + 1.3 * (0.6 * std::sin(omega[0][0] * t + phase[0][0]) +
                                  0.4 * std::sin(omega[0][1] * t + phase[0][1]));
    const double y = 0.5 + 0.4 * (0.6 * std::sin(omega[1][0] * t + phase[1][0]) +
                                  0.4 * std::sin(omega[1][1] * t + phase[1][1]));
    return {x, y};
  }
};

struct Scene {
  SurfacePlane plane = testing::wall(3.0, 1.0);
  std::vector<CameraModel> cameras;
  std::vector<SpotPath> paths;
  std::vector<TruthStroke> strokes;
  double duration_s = 60.0;

  bool pen_down(int spot, double t) const {
    return std::any_of(strokes.begin(), strokes.end(),
                       [&](const TruthStroke& s) { return s.spot == spot && t >= s.begin_s && t < s.end_s; });
  }
};

Scene make_scene(unsigned seed) {
  Scene scene;
  for (const double x : {0.5, 1.5, 2.5})
    scene.cameras.push_back(testing::camera_facing({x, -2.0, 0.5}, {x, 0.0, 0.5}, 1829.0));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> omega(0.8, 2.2), phase(0, 2 * kPi), pen(0.3, 2.0), coin(0, 1);
  for (int spot = 0; spot < 5; ++spot) {
    SpotPath path;
    for (auto& axis : path.omega)
      for (double& w : axis) w = omega(rng);
    for (auto& axis : path.phase)
      for (double& p : axis) p = phase(rng);
    scene.paths.push_back(path);
    bool down = coin(rng) < 0.5;
    for (double t = 0.0; t < scene.duration_s;) {
      const double length = pen(rng);
      if (down && t + length < scene.duration_s - 0.1) scene.strokes.push_back({spot, t, t + length});
      t += length;
      down = !down;
    }
  }
  return scene;
}

struct TrackedRun {
  std::vector<StrokeEvent> events;
  std::map<std::uint32_t, double> end_emitted_s;  // when each End event was returned
  SurfaceCounters counters;
};

// A tracker for the scene's wall, every camera mapped through its calibration.
SurfaceTracker plane_tracker(const Scene& scene) {
  std::vector<ImageToSurface> mappings;
  for (const auto& camera : scene.cameras)
    mappings.push_back(ImageToSurface::from_plane(camera, scene.plane));
  return SurfaceTracker(scene.plane, mappings);
}

TrackedRun track(const Scene& scene, unsigned noise_seed) {
  SurfaceTracker tracker = plane_tracker(scene);
  std::mt19937 rng(noise_seed);
  std::normal_distribution<double> noise(0.0, 0.2);
  TrackedRun run;
  const TimeNs period = 10'000'000;  // 100 Hz, phases 0, 3.3, 6.7 ms: asynchronous
  for (TimeNs frame_start = 0; frame_start < static_cast<TimeNs>(scene.duration_s * 1e9);
       frame_start += period)
    for (int c = 0; c < 3; ++c) {
      const TimeNs stamp = frame_start + c * period / 3;
      const double t = static_cast<double>(stamp) * 1e-9;
      std::vector<Eigen::Vector2d> pixels;
      for (int spot = 0; spot < 5; ++spot) {
        if (!scene.pen_down(spot, t)) continue;
        const auto pixel = scene.cameras[static_cast<std::size_t>(c)].project(
            scene.plane.at(scene.paths[static_cast<std::size_t>(spot)].at(t)));
        if (pixel && scene.cameras[static_cast<std::size_t>(c)].in_image(*pixel))
          pixels.push_back(*pixel + Eigen::Vector2d(noise(rng), noise(rng)));
      }
      for (const auto& event : tracker.add_frame(c, stamp, pixels)) {
        if (event.phase == StrokePhase::kEnd) run.end_emitted_s[event.stroke_id] = t;
        run.events.push_back(event);
      }
    }
  for (const auto& event : tracker.end_silent(static_cast<TimeNs>((scene.duration_s + 1.0) * 1e9)))
    run.events.push_back(event);
  run.counters = tracker.counters();
  return run;
}

TEST(SurfaceTracker, LumiPointSceneStrokesBeginEndAndStayWhole) {
  const Scene scene = make_scene(22);
  const TrackedRun run = track(scene, 7);

  // Which truth stroke each stroke's updates belong to (the pen-down spot nearest the estimate).
  std::map<std::uint32_t, std::map<int, int>> votes;  // stroke id → truth stroke → updates
  double squared_error = 0;
  int updates = 0, far_updates = 0;
  for (const auto& e : run.events) {
    if (e.phase != StrokePhase::kContinue) continue;
    const double t = static_cast<double>(e.stamp_ns) * 1e-9;
    int best = -1;
    double best_distance = 1e9;
    for (std::size_t s = 0; s < scene.strokes.size(); ++s) {
      const auto& stroke = scene.strokes[s];
      if (t < stroke.begin_s || t >= stroke.end_s) continue;
      const double d = (scene.paths[static_cast<std::size_t>(stroke.spot)].at(t) - e.position).norm();
      if (d < best_distance) best_distance = d, best = static_cast<int>(s);
    }
    if (best < 0 || best_distance > 0.01) {
      ++far_updates;
      continue;
    }
    ++votes[e.stroke_id][best];
    squared_error += best_distance * best_distance;
    ++updates;
  }
  std::map<int, std::vector<std::uint32_t>> ids_of_truth;
  int merged = 0;
  for (const auto& [id, by_truth] : votes) {
    const auto majority = std::max_element(by_truth.begin(), by_truth.end(),
                                           [](const auto& a, const auto& b) { return a.second < b.second; });
    ids_of_truth[majority->first].push_back(id);
    if (by_truth.size() > 1) ++merged;
  }
  int split = 0, missed = 0, begins_ok = 0, ends_ok = 0;
  std::map<std::uint32_t, TimeNs> begin_of, end_of;
  for (const auto& e : run.events) {
    if (e.phase == StrokePhase::kBegin) begin_of[e.stroke_id] = e.stamp_ns;
    if (e.phase == StrokePhase::kEnd) end_of[e.stroke_id] = e.stamp_ns;
  }
  double max_begin_ms = 0, max_end_ms = 0, max_end_delay_ms = 0;
  for (std::size_t s = 0; s < scene.strokes.size(); ++s) {
    const auto found = ids_of_truth.find(static_cast<int>(s));
    if (found == ids_of_truth.end()) {
      ++missed;
      continue;
    }
    if (found->second.size() > 1) ++split;
    const std::uint32_t id = found->second.front();
    const double begin_ms =
        std::abs(static_cast<double>(begin_of[id]) * 1e-6 - scene.strokes[s].begin_s * 1e3);
    const double end_ms = std::abs(static_cast<double>(end_of[id]) * 1e-6 - scene.strokes[s].end_s * 1e3);
    begins_ok += begin_ms <= 20.0 ? 1 : 0;
    ends_ok += end_ms <= 20.0 ? 1 : 0;
    max_begin_ms = std::max(max_begin_ms, begin_ms);
    max_end_ms = std::max(max_end_ms, end_ms);
    if (run.end_emitted_s.count(id) != 0)
      max_end_delay_ms =
          std::max(max_end_delay_ms, (run.end_emitted_s.at(id) - scene.strokes[s].end_s) * 1e3);
  }
  const double n = static_cast<double>(scene.strokes.size());
  const double rmse_mm = 1e3 * std::sqrt(squared_error / std::max(updates, 1));
  std::printf("strokes %zu, stroke ids %zu, missed %d, split %d, merged %d, updates %d (%d off any stroke)\n",
              scene.strokes.size(), votes.size(), missed, split, merged, updates, far_updates);
  std::printf(
      "begin within 20 ms %.1f%% (worst %.1f ms), end within 20 ms %.1f%% (worst %.1f ms), end reported "
      "%.1f ms after pen-up at worst; position RMSE %.3f mm\n",
      100 * begins_ok / n, max_begin_ms, 100 * ends_ok / n, max_end_ms, max_end_delay_ms, rmse_mm);
  std::printf("counters: frames %llu spots %llu off-surface %llu duplicates %llu unconfirmed %llu\n",
              static_cast<unsigned long long>(run.counters.frames),
              static_cast<unsigned long long>(run.counters.spots),
              static_cast<unsigned long long>(run.counters.off_surface),
              static_cast<unsigned long long>(run.counters.duplicate_spots),
              static_cast<unsigned long long>(run.counters.unconfirmed_dropped));
  ASSERT_GE(scene.strokes.size(), 100U);  // the scene is what it claims to be
  EXPECT_EQ(missed, 0);
  EXPECT_EQ(split, 0);
  EXPECT_EQ(merged, 0);
  EXPECT_EQ(votes.size(), scene.strokes.size());  // no duplicate strokes where cameras overlap
  EXPECT_GE(begins_ok, 0.99 * n);
  EXPECT_GE(ends_ok, 0.99 * n);
  EXPECT_LE(rmse_mm, 0.5);
  EXPECT_EQ(far_updates, 0);
  EXPECT_EQ(run.counters.strokes_begun, run.counters.strokes_ended);
}

TEST(SurfaceTracker, CountsAndDropsWhatItCannotUse) {
  const Scene scene = make_scene(1);
  SurfaceTracker tracker = plane_tracker(scene);
  const auto pixel_of = [&](int camera, const Eigen::Vector2d& st) {
    return *scene.cameras[static_cast<std::size_t>(camera)].project(scene.plane.at(st));
  };
  // A spot beyond the wall's edge (seen by the camera, outside the surface) is ignored.
  const std::vector<Eigen::Vector2d> off = {pixel_of(0, {-0.1, 0.5})};
  EXPECT_TRUE(tracker.add_frame(0, 1'000'000, off).empty());
  EXPECT_EQ(tracker.counters().off_surface, 1U);
  // A stroke begins after two updates, from two cameras.
  const std::vector<Eigen::Vector2d> a = {pixel_of(0, {1.0, 0.5})}, b = {pixel_of(1, {1.0, 0.5})};
  EXPECT_TRUE(tracker.add_frame(0, 2'000'000, a).empty());
  const auto events = tracker.add_frame(1, 5'000'000, b);
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].phase, StrokePhase::kBegin);
  EXPECT_EQ(events[0].stamp_ns, 2'000'000);
  EXPECT_EQ(events[1].phase, StrokePhase::kContinue);
  EXPECT_EQ(events[1].cameras, 2);  // both cameras updated it within end_after_ns
  // An older frame, an unknown camera, NaN pixels: counted, nothing else changes.
  EXPECT_TRUE(tracker.add_frame(2, 4'000'000, a).empty());
  EXPECT_EQ(tracker.counters().late_frames, 1U);
  EXPECT_TRUE(tracker.add_frame(7, 6'000'000, a).empty());
  EXPECT_EQ(tracker.counters().unknown_camera, 1U);
  const std::vector<Eigen::Vector2d> nan = {Eigen::Vector2d(std::nan(""), 3.0)};
  EXPECT_TRUE(tracker.add_frame(2, 6'000'000, nan).empty());
  EXPECT_EQ(tracker.counters().unmappable, 1U);
  EXPECT_EQ(tracker.active_strokes(), 1U);
  // Silence ends it, stamped with its last update.
  const auto ended = tracker.end_silent(100'000'000);
  ASSERT_EQ(ended.size(), 1U);
  EXPECT_EQ(ended[0].phase, StrokePhase::kEnd);
  EXPECT_EQ(ended[0].cameras, 2);
  EXPECT_EQ(ended[0].stamp_ns, 5'000'000);
  EXPECT_EQ(tracker.active_strokes(), 0U);
}

// A camera whose frames arrive late (and are dropped) does not end the strokes only it sees, while
// the other cameras' frames move on; silence from every camera that saw it does.
TEST(SurfaceTracker, ADelayedCameraDoesNotEndItsStrokes) {
  const Scene scene = make_scene(1);
  SurfaceTracker tracker = plane_tracker(scene);
  const auto spot_at = [&](double s) {
    return std::vector<Eigen::Vector2d>{*scene.cameras[0].project(scene.plane.at({s, 0.5}))};
  };
  const std::vector<Eigen::Vector2d> none;
  constexpr TimeNs kMs = 1'000'000;
  tracker.add_frame(0, 0, spot_at(0.30));
  ASSERT_EQ(tracker.add_frame(0, 10 * kMs, spot_at(0.31)).front().phase, StrokePhase::kBegin);
  // Camera 1 (which does not see the spot) goes on for 60 ms; camera 0's frames of that time come
  // late and are dropped.
  for (TimeNs t = 13; t <= 73; t += 10) EXPECT_TRUE(tracker.add_frame(1, t * kMs, none).empty()) << t;
  EXPECT_TRUE(tracker.add_frame(0, 40 * kMs, spot_at(0.34)).empty());
  EXPECT_EQ(tracker.counters().late_frames, 1U);
  const auto resumed = tracker.add_frame(0, 80 * kMs, spot_at(0.38));
  ASSERT_EQ(resumed.size(), 1U);
  EXPECT_EQ(resumed[0].phase, StrokePhase::kContinue);
  EXPECT_EQ(resumed[0].stroke_id, 1U);
  // Pen up: camera 0 sends frames without it; 30 ms after the last update the stroke ends.
  EXPECT_TRUE(tracker.add_frame(0, 100 * kMs, none).empty());
  const auto ended = tracker.add_frame(0, 120 * kMs, none);
  ASSERT_EQ(ended.size(), 1U);
  EXPECT_EQ(ended[0].phase, StrokePhase::kEnd);
  EXPECT_EQ(ended[0].stamp_ns, 80 * kMs);
  EXPECT_EQ(tracker.counters().strokes_begun, 1U);
}

}  // namespace
}  // namespace panoptes::surface
