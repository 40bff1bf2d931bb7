// SPDX-License-Identifier: Apache-2.0
// A 2-marker bar (seed 000 §4.5.8; issue 6): its ends look alike, each camera labels them by
// continuity in runs, and the solver reconciles the runs across cameras (bar_labels.h).
#include <gtest/gtest.h>

#include "calib_expect.h"

namespace panoptes::calib::testing {
namespace {

const WandDefinition kBar{{0.0, 0.5}};
constexpr const char* kBarMarkers = "[[-0.25, 0, 0], [0.25, 0, 0]]";

// +1 if `frame` labels the bar's ends as the scene does, -1 if reversed, 0 if too close to tell.
int truth_order(const Scene& scene, std::size_t camera, const WandFrame& frame) {
  const auto& config = scene.cameras()[camera];
  const auto markers = scene.markers_at(frame.stamp_ns - kEpoch - config.clock_offset_ns);
  std::vector<Eigen::Vector2d> truth;
  for (const auto& marker : markers)
    if (marker.name.rfind("wand/", 0) == 0)
      if (auto p = config.calibration.model().project(marker.p)) truth.push_back(*p);
  if (truth.size() != 2 || frame.pixels.size() != 2) return 0;
  const double same = (frame.pixels[0] - truth[0]).norm() + (frame.pixels[1] - truth[1]).norm();
  const double swapped = (frame.pixels[0] - truth[1]).norm() + (frame.pixels[1] - truth[0]).norm();
  if (std::abs(same - swapped) < 2.0) return 0;
  return same < swapped ? 1 : -1;
}

// Splits `camera`'s track into runs at 0.05 s gaps every 1.5 s (as an occlusion would) and
// reverses the labels of every other run.
void flip_every_other_run(std::vector<CameraWandTrack>& tracks, std::size_t camera) {
  auto& frames = tracks[camera].frames;
  const auto piece = [](const WandFrame& f) {
    return static_cast<int>((f.stamp_ns - kEpoch) / 1'500'000'000);
  };
  std::erase_if(frames, [&](const WandFrame& f) {
    return (f.stamp_ns - kEpoch) % 1'500'000'000 < 50'000'000 && piece(f) > 0;
  });
  for (auto& frame : frames) {
    frame.label_run = 1000 * piece(frame) + frame.label_run;
    if (piece(frame) % 2 == 1) std::swap(frame.pixels[0], frame.pixels[1]);
  }
}

SceneSpec bar_room() {
  SceneSpec spec = room8();
  spec.wand_markers = kBarMarkers;
  return spec;
}

TEST(TwoMarkerBar, RunsStartAtGapsAndWhereTheEndsCannotBeToldApart) {
  CameraIntrinsics k;
  k.width = 1280;
  k.height = 1024;
  k.fx = k.fy = 700;
  k.cx = 640;
  k.cy = 512;
  std::vector<FeatureFrame> frames;
  const auto add = [&](int index, Eigen::Vector2d a, Eigen::Vector2d b) {
    FeatureFrame frame;
    frame.camera_id = "cam";
    frame.stamp_ns = kEpoch + static_cast<TimeNs>(index) * 10'000'000;
    frame.blobs.resize(2);
    frame.blobs[0].x = a.x();
    frame.blobs[0].y = a.y();
    frame.blobs[1].x = b.x();
    frame.blobs[1].y = b.y();
    frames.push_back(frame);
  };
  // Frames 0-9: a long bar moving right, one run (the blobs' order alternates: labels follow the
  // motion, not the order). Then a 10-frame gap: a new run. Then the bar turns end-on, both ends
  // within a few pixels of each other: another new run.
  for (int i = 0; i < 10; ++i) {
    const Eigen::Vector2d a(300 + 3 * i, 500), b(500 + 3 * i, 520);
    i % 2 ? add(i, a, b) : add(i, b, a);
  }
  for (int i = 20; i < 25; ++i) add(i, {400 + 3 * i, 500}, {600 + 3 * i, 500});
  add(25, {700, 500}, {702, 501});
  for (int i = 26; i < 30; ++i) add(i, {700, 500 - 2 * (i - 25)}, {702, 501 + 2 * (i - 25)});
  const CameraWandTrack track = extract_wand_track("cam", frames, k, kBar);
  ASSERT_EQ(track.frames.size(), 20u);
  for (int i = 1; i < 10; ++i) {
    EXPECT_EQ(track.frames[i].label_run, track.frames[0].label_run);
    EXPECT_LT((track.frames[i].pixels[0] - track.frames[i - 1].pixels[0]).norm(), 10.0) << "frame " << i;
  }
  EXPECT_NE(track.frames[10].label_run, track.frames[9].label_run);  // after the gap
  EXPECT_EQ(track.frames[14].label_run, track.frames[10].label_run);
  EXPECT_NE(track.frames[15].label_run, track.frames[14].label_run);  // a jump to an end-on bar
  EXPECT_NE(track.frames[16].label_run, track.frames[15].label_run);  // ends 2 px apart: ambiguous
}

// Resolution against the truth: one camera's runs deliberately reversed every other run.
TEST(TwoMarkerBar, ReversedRunsOfOneCameraAreReconciledWithTheTruth) {
  SceneSpec spec = bar_room();
  spec.duration_s = 10;
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  std::vector<CameraIntrinsics> intrinsics;
  for (const auto& config : scene.cameras()) intrinsics.push_back(config.calibration.intrinsics);
  auto tracks = simulate_tracks(scene, kBar, intrinsics);
  flip_every_other_run(tracks, 3);
  std::size_t before = 0;
  int reversed_before = 0;
  for (const auto& frame : tracks[3].frames) reversed_before += truth_order(scene, 3, frame) < 0 ? 1 : 0;
  for (const auto& track : tracks) before += track.frames.size();
  const BarLabelReport report = resolve_bar_labels(tracks, intrinsics);
  std::printf(
      "  runs %d, reversed %d, dropped %d (%d frames), camera pairs %d, votes %d, conflicting %d; "
      "cam3 frames reversed against the truth before: %d\n",
      report.runs, report.flipped_runs, report.dropped_runs, report.dropped_frames, report.camera_pairs,
      report.votes, report.conflicting_votes, reversed_before);
  EXPECT_GT(reversed_before, 100);  // the damage was real
  EXPECT_EQ(report.camera_pairs, 28);
  EXPECT_GE(report.flipped_runs, 3);
  EXPECT_LE(report.conflicting_votes, report.votes / 100);
  std::size_t after = 0;
  int agree = 0, reversed = 0;
  for (std::size_t c = 0; c < tracks.size(); ++c)
    for (const auto& frame : tracks[c].frames) {
      ++after;
      const int order = truth_order(scene, c, frame);
      agree += order > 0 ? 1 : 0;
      reversed += order < 0 ? 1 : 0;
    }
  // All frames agree with the truth, or all are reversed (the bar's ends have no names).
  std::printf("  frames kept %zu of %zu; agreeing with the truth %d, reversed %d\n", after, before, agree,
              reversed);
  EXPECT_EQ(std::min(agree, reversed), 0);
  EXPECT_GE(static_cast<double>(after), 0.97 * static_cast<double>(before));
}

// The 8-camera room with a 2-marker bar: the same position and rotation goals as the 3-marker
// wand, with and without one camera's runs reversed.
TEST(TwoMarkerBar, EightCameraRoomCalibrates) {
  const Scene scene = Scene::from_yaml_string(scene_yaml(bar_room()));
  for (const bool damaged : {false, true}) {
    const Measured m = solve_and_measure(scene, kBar, SolveOptions{}, 0.0, [&](auto& tracks) {
      if (damaged) flip_every_other_run(tracks, 3);
    });
    print(damaged ? "bar, cam3 runs reversed" : "bar", m);
    ASSERT_TRUE(m.result.bar_labels.has_value());
    const auto& labels = *m.result.bar_labels;
    std::printf("  bar ends: %d runs, %d reversed, %d dropped (%d frames), %d of %d votes conflicting\n",
                labels.runs, labels.flipped_runs, labels.dropped_runs, labels.dropped_frames,
                labels.conflicting_votes, labels.votes);
    expect_room_goals(m);
  }
}

// A 3-marker wand with its middle marker in the middle is as ambiguous as a 2-marker bar: it used
// to be skipped in every frame without a previous one, now its runs are reconciled the same way.
TEST(TwoMarkerBar, SymmetricThreeMarkerWandCalibrates) {
  SceneSpec spec = room8();
  spec.wand_markers = "[[-0.25, 0, 0], [0, 0, 0], [0.25, 0, 0]]";
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  const WandDefinition symmetric{{0.0, 0.25, 0.5}};
  ASSERT_TRUE(symmetric.ends_indistinguishable());
  EXPECT_FALSE(WandDefinition({{0.0, 0.18, 0.5}}).ends_indistinguishable());
  const Measured m = solve_and_measure(scene, symmetric, SolveOptions{});
  print("symmetric 3-marker wand", m);
  ASSERT_TRUE(m.result.bar_labels.has_value());
  EXPECT_EQ(m.result.bar_labels->conflicting_votes, 0);
  expect_room_goals(m);
}

}  // namespace
}  // namespace panoptes::calib::testing
