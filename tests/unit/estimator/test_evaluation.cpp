// SPDX-License-Identifier: Apache-2.0
// The evaluation of tracks against simulator ground truth, on hand-made track lists.
#include <cmath>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "panoptes/eval/evaluation.h"
#include "panoptes/simulator.h"

namespace panoptes::estimator {
namespace {

const char* kScene = R"(
seed: 1
duration: 3.0
cameras:
  - id: cam0
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    look_at: {eye: [3, 0, 1], target: [0, 0, 1]}
    rate: 100
markers:
  - name: a
    path: {type: static, position: [0, 0, 1]}
  - name: b
    path: {type: static, position: [0.5, 0, 1]}
)";

TrackRecord record(TimeNs stamp, std::int64_t id, const Eigen::Vector3d& p) {
  TrackRecord track;
  track.stamp_ns = stamp;
  track.id = id;
  track.p = p;
  return track;
}

// Judged from the first record (epoch 1000 ns, no warm-up); instant k is 10 ms after k - 1.
EvaluationOptions from_the_start() {
  EvaluationOptions options;
  options.epoch_ns = 1000;
  options.warmup_ns = 0;
  return options;
}
TimeNs instant(const EvaluationOptions& options, int k) {
  return options.epoch_ns + k * 10'000'000LL;
}

// A switch to a track that was another marker's is a swap; a switch to a new track (the marker's
// own was lost) is not. Here a's and b's tracks exchange markers at k = 40, and a takes a new track
// at k = 70.
TEST(Evaluation, TellsSwapsFromNewTracks) {
  const Scene scene = Scene::from_yaml_string(kScene);
  const EvaluationOptions options = from_the_start();
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 100; ++k) {
    const TimeNs stamp = instant(options, k);
    const bool exchanged = k >= 40;
    const std::int64_t on_a = k >= 70 ? 9 : (exchanged ? 2 : 1);
    tracks.push_back(record(stamp, on_a, Eigen::Vector3d(0, 0, 1)));
    tracks.push_back(record(stamp, exchanged ? 1 : 2, Eigen::Vector3d(0.5, 0, 1)));
  }
  const auto result = evaluate(scene, tracks, options);
  ASSERT_EQ(result.markers[0].id_switches.size(), 2u);
  EXPECT_TRUE(result.markers[0].id_switches[0].swap);   // 1 -> 2, b's track
  EXPECT_FALSE(result.markers[0].id_switches[1].swap);  // 2 -> 9, a new track
  ASSERT_EQ(result.markers[1].id_switches.size(), 1u);
  EXPECT_TRUE(result.markers[1].id_switches[0].swap);  // 2 -> 1, a's track
  EXPECT_EQ(result.id_switch_count, 3u);
  EXPECT_EQ(result.id_swap_count, 2u);
  const auto json = nlohmann::json::parse(result.to_json());
  EXPECT_EQ(json["id_swaps"], 2);
  EXPECT_EQ(json["id_switch_events"][0]["swap"], true);
  EXPECT_NE(result.summary().find("ID switches 3 (swaps 2)"), std::string::npos) << result.summary();
}

TEST(Evaluation, MeasuresErrorCoverageAndIdSwitches) {
  const Scene scene = Scene::from_yaml_string(kScene);
  const EvaluationOptions options = from_the_start();
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 100; ++k) {
    const TimeNs stamp = instant(options, k);
    // One identity switch at k = 50; 1 mm off.
    tracks.push_back(record(stamp, k < 50 ? 1 : 7, Eigen::Vector3d(0.001, 0, 1)));
    if (k % 2 == 0) tracks.push_back(record(stamp, 2, Eigen::Vector3d(0.5, 0, 1)));  // b half of the time
    tracks.push_back(record(stamp, 3, Eigen::Vector3d(2, 2, 2)));                    // far from every marker
  }
  const auto result = evaluate(scene, tracks, options);
  ASSERT_EQ(result.markers.size(), 2u);
  EXPECT_NEAR(result.markers[0].rmse_m, 0.001, 1e-9);
  EXPECT_DOUBLE_EQ(result.markers[0].tracked_fraction(), 1.0);
  ASSERT_EQ(result.markers[0].id_switches.size(), 1u);
  EXPECT_EQ(result.markers[0].id_switches[0].from_id, 1);
  EXPECT_EQ(result.markers[0].id_switches[0].to_id, 7);
  EXPECT_EQ(result.markers[0].id_switches[0].stamp_ns, 1000 + 500'000'000);
  EXPECT_NEAR(result.markers[0].id_switches[0].t_s, 0.5, 1e-12);
  EXPECT_NEAR(result.markers[1].tracked_fraction(), 0.5, 1e-12);
  EXPECT_NEAR(result.markers[1].rmse_m, 0.0, 1e-12);
  ASSERT_EQ(result.false_tracks.size(), 1u);
  EXPECT_EQ(result.false_tracks[0], 3);
  EXPECT_EQ(result.id_switch_count, 1u);
  EXPECT_EQ(result.id_swap_count, 0u);  // 7 is a new track
  EXPECT_NE(result.to_json().find("\"id_switches\""), std::string::npos);
  // Overall: 100 samples of 1 mm and 50 of 0 mm.
  EXPECT_NEAR(result.rmse_m, 0.001 * std::sqrt(100.0 / 150.0), 1e-12);
  EXPECT_NEAR(result.max_error_m, 0.001, 1e-12);
  EXPECT_NEAR(result.worst_marker_rmse_m, 0.001, 1e-12);
  // Records: 100 + 50 + 100, the 100 ghosts false.
  EXPECT_EQ(result.records, 250u);
  EXPECT_EQ(result.false_records, 100u);
  EXPECT_EQ(result.duplicate_records, 0u);
  EXPECT_NEAR(result.false_record_fraction(), 0.4, 1e-12);
  ASSERT_EQ(result.false_record_ids.size(), 1u);
  EXPECT_EQ(result.false_record_ids[0].id, 3);
  EXPECT_EQ(result.false_record_ids[0].records, 100u);
  EXPECT_EQ(result.false_record_ids[0].false_records, 100u);
}

TEST(Evaluation, WarmupAndInstantsAfterTheSceneAreNotJudged) {
  const Scene scene = Scene::from_yaml_string(kScene);
  EvaluationOptions options;
  options.epoch_ns = 5'000'000'000;
  options.warmup_ns = 1'000'000'000;
  std::vector<TrackRecord> tracks;
  // Before the warmup: ghosts, which must not count.
  for (int k = 0; k < 50; ++k) tracks.push_back(record(options.epoch_ns + k * 10'000'000LL, 9, {5, 5, 5}));
  for (int k = 100; k < 200; ++k) tracks.push_back(record(options.epoch_ns + k * 10'000'000LL, 1, {0, 0, 1}));
  // After the scene's 3 s.
  tracks.push_back(record(options.epoch_ns + 3'500'000'000LL, 9, {5, 5, 5}));
  const auto result = evaluate(scene, tracks, options);
  EXPECT_EQ(result.instants, 100u);
  EXPECT_EQ(result.records, 100u);
  EXPECT_EQ(result.false_records, 0u);
  EXPECT_EQ(result.markers[0].steps, 100u);
  EXPECT_EQ(result.max_instant_gap_ns, 10'000'000);
}

// --warmup and --until (until_ns) judge a window of the scene: errors outside it do not count.
TEST(Evaluation, UntilEndsTheJudgedWindow) {
  const Scene scene = Scene::from_yaml_string(kScene);
  EvaluationOptions options;
  options.warmup_ns = 1'000'000'000;
  options.until_ns = 2'000'000'000;
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 300; ++k) {  // 1 mm off in [1, 2] s, 10 mm off elsewhere
    const bool inside = k >= 100 && k <= 200;
    tracks.push_back(record(k * 10'000'000LL, 1, {inside ? 0.001 : 0.01, 0, 1}));
  }
  const auto result = evaluate(scene, tracks, options);
  EXPECT_EQ(result.instants, 101u);  // 1.00 s to 2.00 s, both ends judged
  EXPECT_NEAR(result.markers[0].rmse_m, 0.001, 1e-12);
  options.until_ns = std::numeric_limits<TimeNs>::max();  // the default: to the scene's end
  EXPECT_EQ(evaluate(scene, tracks, options).instants, 200u);
}

// A tracks file has no line for a frame at which no track was published. With judge_every_frame
// every camera frame is an instant: such frames count as untracked (a single thrown ball whose
// track was unpublished at each catch was never judged there, and its coverage read 100 %).
TEST(Evaluation, EveryFrameJudgesFramesWithoutRecords) {
  const Scene scene = Scene::from_yaml_string(kScene);
  EvaluationOptions options = from_the_start();
  options.until_ns = kNsPerSecond;  // cam0's frames at 0, 10, ..., 1000 ms: 101
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 100; k += 2) tracks.push_back(record(instant(options, k), 1, {0, 0, 1}));
  const auto records_only = evaluate(scene, tracks, options);
  EXPECT_EQ(records_only.instants, 50u);
  EXPECT_DOUBLE_EQ(records_only.markers[0].tracked_fraction(), 1.0);
  options.judge_every_frame = true;
  const auto every_frame = evaluate(scene, tracks, options);
  EXPECT_EQ(every_frame.instants, 101u);
  EXPECT_EQ(every_frame.markers[0].steps, 101u);
  EXPECT_EQ(every_frame.markers[0].tracked, 50u);
  EXPECT_EQ(every_frame.records, 50u);
  EXPECT_EQ(every_frame.false_records, 0u);
  EXPECT_EQ(every_frame.id_switch_count, 0u);
  // A record between two frames is judged as well, once.
  tracks.push_back(record(instant(options, 3) + 5'000'000, 1, {0, 0, 1}));
  EXPECT_EQ(evaluate(scene, tracks, options).instants, 102u);
}

TEST(Evaluation, DuplicateTracksOnOneMarkerAreFalseRecords) {
  const Scene scene = Scene::from_yaml_string(kScene);
  EvaluationOptions options;
  options.warmup_ns = 0;
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 20; ++k) {
    const TimeNs stamp = k * 10'000'000LL;
    tracks.push_back(record(stamp, 1, {0.0005, 0, 1}));
    tracks.push_back(record(stamp, 2, {0.004, 0, 1}));  // the same marker, further off: a duplicate
  }
  const auto result = evaluate(scene, tracks, options);
  EXPECT_EQ(result.markers[0].tracked, 20u);
  EXPECT_NEAR(result.markers[0].rmse_m, 0.0005, 1e-12);  // the nearer track is the match
  EXPECT_EQ(result.false_records, 20u);
  EXPECT_EQ(result.duplicate_records, 20u);
  ASSERT_EQ(result.false_record_ids.size(), 1u);
  EXPECT_EQ(result.false_record_ids[0].id, 2);
  EXPECT_EQ(result.false_tracks, std::vector<std::int64_t>{2});
  EXPECT_TRUE(result.markers[0].id_switches.empty());
}

// Two cameras at right angles. "both" (at the origin) is seen by both; "solo" (2.5 m along x) only
// by cam0, since it lies 40 degrees off cam1's axis; "mover" starts 0.1 m above the origin and
// moves along +x at 1 m/s, leaving cam1's image (x = 319.5 + 600 x / 3 > 639.5) at t = 1.6 s.
const char* kTwoCameras = R"(
seed: 3
duration: 3.0
defaults:
  width: 640
  height: 480
  K: [600, 600, 319.5, 239.5]
  rate: 100
cameras:
  - id: cam0
    look_at: {eye: [3, 0, 1], target: [0, 0, 1]}
  - id: cam1
    look_at: {eye: [0, 3, 1], target: [0, 0, 1]}
    rate: 90
    phase: 0.004
markers:
  - name: both
    path: {type: static, position: [0, 0, 1]}
  - name: solo
    path: {type: static, position: [2.5, 0, 1]}
  - name: mover
    path: {type: linear, start: [0, 0, 1.1], velocity: [1, 0, 0]}
)";

// Trackable by brute force: cameras with any frame (of the scene, so at or after its start)
// showing the marker in (t - window, t].
bool trackable_by_brute_force(const Scene& scene, int marker, TimeNs t, TimeNs window) {
  int cameras = 0;
  for (const SimCameraConfig& config : scene.cameras()) {
    const CameraSimulator camera(scene, config.calibration.id);
    bool shown = false;
    for (std::int64_t k = 0; k < 400 && !shown; ++k) {
      const TimeNs frame_time = camera.frame_time_ns(k);
      if (frame_time <= t - window || frame_time > t) continue;
      const std::vector<int> visible = camera.visible_markers(k);
      shown = std::find(visible.begin(), visible.end(), marker) != visible.end();
    }
    cameras += shown ? 1 : 0;
  }
  return cameras >= 2;
}

TEST(Evaluation, CoverageCountsOnlyMarkerTimeThatTwoCamerasSaw) {
  const Scene scene = Scene::from_yaml_string(kTwoCameras);
  EvaluationOptions options;
  options.warmup_ns = 0;
  options.keep_series = true;
  std::vector<TrackRecord> tracks;
  const int instants = 250;  // 0 to 2.49 s
  for (int k = 0; k < instants; ++k) {
    const TimeNs stamp = k * 10'000'000LL;
    const double t = k * 0.01;
    if (k % 4 != 0) tracks.push_back(record(stamp, 1, {0, 0, 1}));  // "both": tracked 3/4 of the time
    tracks.push_back(record(stamp, 2, {2.5, 0, 1}));                // "solo": always
    if (t < 2.0) tracks.push_back(record(stamp, 3, {t, 0, 1.1}));   // "mover": until 2 s
  }
  const auto result = evaluate(scene, tracks, options);
  ASSERT_EQ(result.instants, static_cast<std::size_t>(instants));
  const MarkerEvaluation& both = result.markers[0];
  const MarkerEvaluation& solo = result.markers[1];
  const MarkerEvaluation& mover = result.markers[2];

  // "both": trackable once each camera has had a frame (cam1's first is at 4 ms).
  EXPECT_EQ(both.trackable, static_cast<std::size_t>(instants - 1));
  EXPECT_NEAR(both.coverage(), 0.75, 0.01);
  // "solo" was tracked but never trackable: it does not count against (or for) coverage.
  EXPECT_EQ(solo.trackable, 0u);
  EXPECT_EQ(solo.tracked, static_cast<std::size_t>(instants));
  EXPECT_DOUBLE_EQ(solo.coverage(), 1.0);
  // "mover": trackable until cam1 loses it at 1.6 s plus the 100 ms window; tracked all that time.
  std::size_t last_trackable = 0;
  for (std::size_t i = 0; i < result.series.scene_time_ns.size(); ++i) {
    const std::uint8_t flags = result.series.flags[2][i];
    const bool trackable = (flags & EvaluationSeries::kTrackable) != 0;
    if (trackable) last_trackable = i;
    // The same decision as counting frames by hand.
    EXPECT_EQ(trackable,
              trackable_by_brute_force(scene, 2, result.series.scene_time_ns[i], options.trackable_window_ns))
        << "instant " << i;
  }
  EXPECT_GE(last_trackable, 169u);
  EXPECT_LE(last_trackable, 171u);
  EXPECT_EQ(mover.trackable, mover.tracked_trackable);
  EXPECT_DOUBLE_EQ(mover.coverage(), 1.0);

  EXPECT_EQ(result.trackable, both.trackable + mover.trackable);
  EXPECT_EQ(result.tracked_trackable, both.tracked_trackable + mover.tracked_trackable);
  EXPECT_NEAR(result.min_coverage, both.coverage(), 1e-12);
  // With two cameras every trackable instant is at the edge: seen by exactly two.
  EXPECT_EQ(result.edge_trackable, result.trackable);
  EXPECT_EQ(result.edge_tracked, result.tracked_trackable);
  EXPECT_NEAR(result.edge_coverage(), result.coverage(), 1e-12);
  EXPECT_NEAR(result.coverage(),
              static_cast<double>(both.tracked_trackable + mover.tracked_trackable) /
                  static_cast<double>(both.trackable + mover.trackable),
              1e-12);

  // A shorter window ends the mover's trackable time sooner.
  options.trackable_window_ns = 20'000'000;
  const auto short_window = evaluate(scene, tracks, options);
  EXPECT_LT(short_window.markers[2].trackable, mover.trackable);
  EXPECT_GE(short_window.markers[2].trackable, 160u);

  // The series: errors where tracked, NaN where not.
  EXPECT_TRUE(std::isnan(result.series.error_m[0][0]));  // k = 0: untracked
  EXPECT_NEAR(result.series.error_m[0][1], 0.0, 1e-9);
  EXPECT_EQ(result.series.flags[0][1],
            EvaluationSeries::kHasTruth | EvaluationSeries::kTrackable | EvaluationSeries::kTracked);
  EXPECT_EQ(result.series.flags[1][1], EvaluationSeries::kHasTruth | EvaluationSeries::kTracked);
}

TEST(Evaluation, JsonHoldsEveryMetric) {
  const Scene scene = Scene::from_yaml_string(kTwoCameras);
  EvaluationOptions options;
  options.epoch_ns = 1'700'000'000'000'000'000;
  options.warmup_ns = 0;
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 100; ++k) {
    const TimeNs stamp = options.epoch_ns + k * 10'000'000LL;
    tracks.push_back(record(stamp, k < 30 ? 4 : 5, {0, 0, 1.002}));
    if (k >= 60) tracks.push_back(record(stamp, 8, {0, 0, 1.001}));  // takes "both" over from 5
    tracks.push_back(record(stamp, 6, {-1, -1, 0}));
  }
  const auto result = evaluate(scene, tracks, options);
  const auto json = nlohmann::json::parse(result.to_json());
  for (const char* key : {"instants",
                          "track_ids",
                          "rmse_mm",
                          "max_error_mm",
                          "worst_marker_rmse_mm",
                          "min_tracked_fraction",
                          "trackable",
                          "tracked_trackable",
                          "coverage",
                          "min_coverage",
                          "id_switches",
                          "id_swaps",
                          "records",
                          "false_records",
                          "false_record_fraction",
                          "duplicate_records",
                          "false_tracks",
                          "false_record_ids",
                          "max_instant_gap_ms",
                          "id_switch_events",
                          "options",
                          "markers"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json["id_switches"], 2);
  ASSERT_EQ(json["id_switch_events"].size(), 2u);
  EXPECT_EQ(json["id_switch_events"][0]["marker"], "both");
  EXPECT_EQ(json["id_switch_events"][0]["from"], 4);
  EXPECT_EQ(json["id_switch_events"][0]["to"], 5);
  EXPECT_NEAR(json["id_switch_events"][0]["t_s"].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(json["id_switch_events"][1]["from"], 5);
  EXPECT_EQ(json["id_switch_events"][1]["to"], 8);
  EXPECT_EQ(json["id_switch_events"][1]["stamp_ns"], options.epoch_ns + 600'000'000);
  // 40 duplicates from id 5 once 8 is nearer, 100 ghosts from 6.
  EXPECT_EQ(json["false_records"], 140);
  EXPECT_EQ(json["duplicate_records"], 40);
  EXPECT_EQ(json["false_tracks"], nlohmann::json::array({5, 6}));  // 5 was mostly a duplicate
  ASSERT_EQ(json["false_record_ids"].size(), 2u);
  EXPECT_EQ(json["false_record_ids"][0]["id"], 5);
  EXPECT_EQ(json["false_record_ids"][0]["records"], 70);
  EXPECT_EQ(json["false_record_ids"][0]["false_records"], 40);
  EXPECT_NEAR(json["max_error_mm"].get<double>(), 2.0, 1e-9);
  EXPECT_NEAR(json["options"]["trackable_window_ms"].get<double>(), 100.0, 1e-12);
  const auto& markers = json["markers"];
  ASSERT_EQ(markers.size(), 3u);
  EXPECT_EQ(markers[0]["name"], "both");
  EXPECT_EQ(markers[0]["id_switches"].size(), 2u);
  EXPECT_TRUE(markers[1]["coverage"].is_null());                  // "solo" was never trackable
  EXPECT_NEAR(markers[2]["coverage"].get<double>(), 0.0, 1e-12);  // "mover" was never tracked
  EXPECT_NEAR(json["coverage"].get<double>(), result.coverage(), 1e-12);
  EXPECT_LT(result.coverage(), 0.7);

  // The summary lists the switches, indented so that only table rows start with a marker name.
  const std::string summary = result.summary();
  EXPECT_NE(summary.find("  ID switch at 0.300 s: both 4 -> 5"), std::string::npos) << summary;
  EXPECT_EQ(summary.rfind("all: ", std::string::npos), summary.rfind('\n', summary.size() - 2) + 1);
}

}  // namespace
}  // namespace panoptes::estimator
