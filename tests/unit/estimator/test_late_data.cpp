// SPDX-License-Identifier: Apache-2.0
// Late data (issue 4): frames delivered out of stamp order are all used, by rewinding to a
// checkpoint and replaying (seed 003 §2.2.4.2), and the tracks are as good as with in-order
// delivery. The demo scene's four asynchronous cameras, seeded.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <random>

#include "panoptes/estimator/inbox.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/eval/evaluation.h"
#include "panoptes/simulator.h"
#include "walk8_scene.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000;

struct Delivered {
  FeatureFrame frame;
  TimeNs received_ns = 0;
};

std::vector<Delivered> simulate(const Scene& scene, double late_fraction, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Delivered> frames;
  for (const auto& camera : scene.cameras()) {
    const CameraSimulator simulator(scene, camera.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < scene.duration_ns(); ++k) {
      FeatureFrame frame = simulator.features(k);
      frame.stamp_ns += kEpoch;
      // 2 ms of transport; a late frame 5-30 ms more.
      TimeNs delay = 2'000'000;
      if (uniform(random) < late_fraction) delay += static_cast<TimeNs>((5.0 + 25.0 * uniform(random)) * 1e6);
      frames.push_back({std::move(frame), kEpoch + simulator.frame_time_ns(k) + delay});
    }
  }
  return frames;
}

struct RunResult {
  Evaluation evaluation;
  TrackerStats stats;
  std::map<std::string, CameraCounters> counters;
};

// Delivers frames in arrival order through the live inbox with `window_ms`, like estimator_node.
// `expire_idle_ms` > 0: as the live estimator, a gap in delivery longer than that expires the
// tracks at the newest stamp plus the gap (Tracker::expire) before the next frame.
RunResult run(const Scene& scene, std::vector<Delivered> frames, double window_ms,
              double expire_idle_ms = 0) {
  std::stable_sort(frames.begin(), frames.end(),
                   [](const Delivered& a, const Delivered& b) { return a.received_ns < b.received_ns; });
  Tracker tracker;
  tracker.set_calibration(scene.calibration());
  FrameInbox inbox(4096, static_cast<TimeNs>(window_ms * 1e6));
  std::vector<TrackRecord> records;
  auto handle = [&](const FeatureFrame& frame) {
    if (tracker.process(frame) == FrameOutcome::kProcessed) {
      for (const auto& track : tracker.current_tracks()) records.push_back(track);
    }
  };
  TimeNs previous_ns = 0;
  for (auto& delivered : frames) {
    const TimeNs idle_ns = delivered.received_ns - previous_ns;
    if (expire_idle_ms > 0 && previous_ns != 0 && idle_ns > static_cast<TimeNs>(expire_idle_ms * 1e6))
      tracker.expire(tracker.last_stamp_ns() + idle_ns);
    previous_ns = delivered.received_ns;
    inbox.push(std::move(delivered.frame));
    for (const auto& frame : inbox.pop_due(delivered.received_ns)) handle(frame);
  }
  for (const auto& frame : inbox.drain()) handle(frame);
  EvaluationOptions options;
  options.epoch_ns = kEpoch;
  return {evaluate(scene, records, options), tracker.stats(), tracker.camera_counters()};
}

TEST(LateData, TenPercentOfFramesFiveToThirtyMsLateAreAllUsedAndAccuracyHolds) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  const auto in_order = run(scene, simulate(scene, 0.0, 11), 5.0);
  const auto late_frames = simulate(scene, 0.10, 11);
  for (double window_ms : {0.0, 5.0, 20.0}) {
    const auto late = run(scene, late_frames, window_ms);
    std::uint64_t frames = 0;
    for (const auto& [camera, c] : late.counters) {
      EXPECT_EQ(c.used, c.frames) << camera << " window " << window_ms << " ms";
      EXPECT_EQ(c.too_late, 0u) << camera;
      frames += c.frames;
    }
    EXPECT_EQ(late.stats.frames_too_late, 0u);
    // With a 5 ms window or none about 10% of frames come after it and are replayed.
    if (window_ms <= 5.0) {
      EXPECT_GT(late.stats.frames_late, frames / 20);
    }
    std::printf(
        "window %.0f ms: RMSE in order %.4f mm, with 10%% late %.4f mm (%+.2f%%), %llu late frames "
        "replayed, %llu replays, min tracked %.4f\n",
        window_ms, in_order.evaluation.rmse_m * 1e3, late.evaluation.rmse_m * 1e3,
        100.0 * (late.evaluation.rmse_m / in_order.evaluation.rmse_m - 1.0),
        static_cast<unsigned long long>(late.stats.frames_late),
        static_cast<unsigned long long>(late.stats.replays), late.evaluation.min_tracked_fraction);
    EXPECT_LE(late.evaluation.rmse_m, 1.05 * in_order.evaluation.rmse_m);
    EXPECT_GE(late.evaluation.min_tracked_fraction, 0.99);
    EXPECT_EQ(late.evaluation.id_switch_count, 0u);
  }
}

// The demo scene's first 600 frames in stamp order.
std::vector<FeatureFrame> first_frames(const Scene& scene, std::size_t n) {
  auto frames = simulate(scene, 0.0, 3);
  std::stable_sort(frames.begin(), frames.end(), [](const Delivered& a, const Delivered& b) {
    return a.frame.stamp_ns < b.frame.stamp_ns;
  });
  frames.resize(n);
  std::vector<FeatureFrame> out;
  for (auto& d : frames) out.push_back(std::move(d.frame));
  return out;
}

void expect_same_tracks(const Tracker& a_tracker, const Tracker& b_tracker) {
  const auto a = a_tracker.current_tracks();
  const auto b = b_tracker.current_tracks();
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_NEAR((a[i].p - b[i].p).norm(), 0.0, 1e-9);
  }
}

// Parameter: the dense checkpoint window. Each test compares a tracker fed out of order with one
// fed the same frames in order.
class LateReplay : public ::testing::TestWithParam<TimeNs> {
 protected:
  void SetUp() override {
    frames = first_frames(scene, 600);
    TrackerOptions options;
    options.dense_checkpoint_window_ns = GetParam();
    in_order = Tracker(options);
    tested = Tracker(options);
    in_order.set_calibration(scene.calibration());
    tested.set_calibration(scene.calibration());
    for (const auto& frame : frames) in_order.process(frame);
  }

  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  std::vector<FeatureFrame> frames;
  Tracker in_order, tested;
};

TEST_P(LateReplay, GivesTheSameStateAsInOrderProcessing) {
  // The final state after late frames equals the state of processing everything in order,
  // whatever the checkpoints' spacing.
  Tracker& shuffled = tested;
  // Hold every 7th frame back by three frames.
  std::vector<std::size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t i = 7; i + 3 < order.size(); i += 7)
    std::rotate(order.begin() + i, order.begin() + i + 1, order.begin() + i + 4);
  for (std::size_t i : order) shuffled.process(frames[i]);
  const TrackerStats& stats = shuffled.stats();
  EXPECT_GT(stats.frames_late, 50u);
  expect_same_tracks(in_order, shuffled);
  // The frames replayed after a late one kept their first association (re-gated only).
  EXPECT_GT(stats.replayed_reassociated, (stats.replayed_frames - stats.frames_late) / 2);
  if (GetParam() > 0) {
    // A checkpoint before each recent frame: a frame three frames late replays four.
    EXPECT_EQ(shuffled.stats().replayed_frames, 4 * shuffled.stats().replays);
  } else {
    EXPECT_GT(shuffled.stats().replayed_frames, 4 * shuffled.stats().replays);
  }
}

TEST_P(LateReplay, ABurstOfLateFramesCostsOneReplay) {
  Tracker& bursts = tested;
  // Every 40 frames, five frames (of different cameras) arrive only after the five that follow
  // them, together and shuffled, with one frame newer than all: one batch, one replay.
  std::mt19937_64 random(5);
  std::size_t i = 0, expected_late = 0, expected_replays = 0;
  for (; i + 10 < frames.size(); i += 40) {
    for (std::size_t k = i + 5; k < i + 10; ++k) bursts.process(frames[k]);
    std::vector<FeatureFrame> burst(frames.begin() + static_cast<std::ptrdiff_t>(i),
                                    frames.begin() + static_cast<std::ptrdiff_t>(i + 5));
    std::shuffle(burst.begin(), burst.end(), random);
    const std::size_t next = std::min(i + 40, frames.size());
    for (std::size_t k = i + 10; k < next; ++k) burst.push_back(frames[k]);
    const auto outcomes = bursts.process_batch(burst);
    ASSERT_EQ(outcomes.size(), burst.size());
    for (std::size_t k = 0; k < 5; ++k) EXPECT_EQ(outcomes[k], FrameOutcome::kLateReplayed);
    for (std::size_t k = 5; k < burst.size(); ++k) EXPECT_EQ(outcomes[k], FrameOutcome::kProcessed);
    expected_late += 5;
    ++expected_replays;
  }
  for (; i < frames.size(); ++i) bursts.process(frames[i]);
  EXPECT_EQ(bursts.stats().frames_late, expected_late);
  EXPECT_EQ(bursts.stats().replays, expected_replays);
  expect_same_tracks(in_order, bursts);
}

TEST_P(LateReplay, FramesReplayedWhileTracksAreBornAreAssociatedFromScratch) {
  // The second frame arrives after 38 newer ones, while the first tracks are being initiated:
  // replayed frames whose tracks have changed since (created, confirmed) cannot keep their first
  // association; they are associated again, and the state is still that of in-order processing.
  std::vector<std::size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  std::rotate(order.begin() + 1, order.begin() + 2, order.begin() + 40);
  for (std::size_t i : order) tested.process(frames[i]);
  const TrackerStats& stats = tested.stats();
  EXPECT_EQ(stats.frames_late, 1u);
  EXPECT_EQ(stats.replayed_frames, 39u);
  EXPECT_LT(stats.replayed_reassociated, 38u);
  expect_same_tracks(in_order, tested);
}

TEST_P(LateReplay, AssociatingReplaysFromScratchGivesTheSameState) {
  // The shortcut off: every replayed frame is gated and assigned again, with the same result.
  TrackerOptions options = tested.options();
  options.reuse_replay_associations = false;
  Tracker full(options);
  full.set_calibration(scene.calibration());
  // Hold every 9th frame back by two frames.
  std::vector<std::size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t i = 4; i + 2 < order.size(); i += 9)
    std::rotate(order.begin() + i, order.begin() + i + 1, order.begin() + i + 3);
  for (std::size_t i : order) full.process(frames[i]);
  EXPECT_GT(full.stats().frames_late, 50u);
  EXPECT_EQ(full.stats().replayed_reassociated, 0u);
  expect_same_tracks(in_order, full);
}

INSTANTIATE_TEST_SUITE_P(CheckpointSpacing, LateReplay, ::testing::Values(TimeNs{0}, TimeNs{50'000'000}),
                         [](const auto& info) { return info.param == 0 ? "SparseOnly" : "Dense50ms"; });

TEST(LateData, FramesBeyondTheRewindHorizonAreCountedPerCamera) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  auto frames = first_frames(scene, 600);
  TrackerOptions options;
  options.rewind_horizon_ns = 50'000'000;
  Tracker tracker(options);
  tracker.set_calibration(scene.calibration());
  const FeatureFrame held = frames[10];
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (i != 10) tracker.process(frames[i]);
  }
  EXPECT_EQ(tracker.process(held), FrameOutcome::kTooLate);
  EXPECT_EQ(tracker.stats().frames_too_late, 1u);
  EXPECT_EQ(tracker.camera_counters().at(held.camera_id).too_late, 1u);
}

// Track ids across a rewind (docs/estimator.md): an id, once out, stays on one marker. While the
// tracks are being born every camera's frames arrive 0-40 ms late in a random order (a starved
// estimator's start), so replays create tracks again, often in another order than the first pass.
// Each record's marker is the nearest true one; no id may ever be on two markers.
// Which marker each confirmed track id is on (the nearest within 20 mm), and how often an id
// moved to another marker.
struct IdFollower {
  std::map<std::int64_t, std::string> marker_of;
  std::size_t records = 0, moved = 0;

  void observe(const Tracker& tracker, const Scene& scene) {
    const auto truth = scene.markers_at(tracker.last_stamp_ns() - kEpoch);
    for (const auto& track : tracker.current_tracks()) {
      if (track.status != TrackStatus::kConfirmed) continue;
      const MarkerTruth* nearest = nullptr;
      for (const auto& marker : truth) {
        if ((marker.p - track.p).norm() < 0.02) nearest = &marker;
      }
      if (nearest == nullptr) continue;
      ++records;
      const auto [it, inserted] = marker_of.emplace(track.id, nearest->name);
      if (!inserted && it->second != nearest->name) {
        ++moved;
        it->second = nearest->name;
      }
    }
  }
};

TEST(LateData, TrackIdsStayOnTheirMarkersWhenReplaysCreateTracksAgain) {
  // The walk8 scene's first second: 41 markers on a person, eight cameras, clutter.
  const Scene scene = walk8_scene(1.0, 8);
  struct Moves {
    std::size_t moved = 0, records = 0, replays = 0;
  };
  // `late_ms`: every frame of the first 300 ms arrives up to that much late.
  const auto run_seeds = [&](double late_ms) {
    Moves m;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      auto frames = simulate(scene, 0.0, seed);
      std::mt19937_64 random(seed);
      std::uniform_real_distribution<double> uniform(0.0, late_ms * 1e6);
      for (auto& delivered : frames) {
        if (delivered.frame.stamp_ns - kEpoch < 300'000'000)
          delivered.received_ns += static_cast<TimeNs>(uniform(random));
      }
      std::stable_sort(frames.begin(), frames.end(),
                       [](const Delivered& a, const Delivered& b) { return a.received_ns < b.received_ns; });
      Tracker tracker;
      tracker.set_calibration(scene.calibration());
      IdFollower follower;
      for (auto& delivered : frames) {
        if (tracker.process(delivered.frame) != FrameOutcome::kProcessed) continue;
        follower.observe(tracker, scene);
      }
      m.records += follower.records;
      m.moved += follower.moved;
      m.replays += tracker.stats().replays;
    }
    std::printf(
        "3 seeds, first 300 ms up to %.0f ms late: %zu confirmed records on markers, %zu times an id moved "
        "to another marker, %zu replays\n",
        late_ms, m.records, m.moved, m.replays);
    return m;
  };
  const Moves in_order = run_seeds(0.0);
  const Moves late = run_seeds(40.0);
  EXPECT_GT(late.replays, 100u);
  EXPECT_GT(late.records, 10000u);
  // Restoring the id counter with the state (before): 55 moves here, against 0 in order; with ids
  // reused within 15 mm: 1 (30 mm: 5, 50 mm: 7, close foot markers took each other's ids).
  EXPECT_LE(late.moved, in_order.moved + 2);
}

// Ids over 12 stalls of every camera (0, 50, 100, 150 and 250 ms at 0.8, 1.2 and 1.6 s) of the walk8
// scene: how often an id moved to another marker with and without a stall, and the new ids.
struct StallScores {
  std::size_t moved = 0, records = 0, moved_without_stall = 0, new_ids = 0;
};

StallScores ids_over_stalls(const TrackerOptions& options) {
  // A loaded machine stalls every camera at once (test_live_labels: the camera_nodes dropped their
  // frames in the queue for 46-150 ms): the walk's 41 tracks coast, then take blobs again.
  const Scene scene = walk8_scene(2.0, 8);
  StallScores scores;
  std::size_t ids_without_stall = 0;
  for (const double gap_ms : {0.0, 50.0, 100.0, 150.0, 250.0}) {
    for (const double at_s : {0.8, 1.2, 1.6}) {
      auto frames = simulate(scene, 0.0, 1);
      std::stable_sort(frames.begin(), frames.end(),
                       [](const Delivered& a, const Delivered& b) { return a.received_ns < b.received_ns; });
      Tracker tracker(options);
      tracker.set_calibration(scene.calibration());
      IdFollower follower;
      for (const auto& delivered : frames) {
        const double t = 1e-9 * static_cast<double>(delivered.frame.stamp_ns - kEpoch);
        if (t >= at_s && t < at_s + 1e-3 * gap_ms) continue;
        if (tracker.process(delivered.frame) != FrameOutcome::kProcessed) continue;
        follower.observe(tracker, scene);
      }
      std::printf(
          "every camera stalled %.0f ms at %.1f s: an id moved to another marker %zu times; %zu ids on "
          "markers; %llu input pause(s), %llu track(s) reacquired\n",
          gap_ms, at_s, follower.moved, follower.marker_of.size(),
          static_cast<unsigned long long>(tracker.stats().input_pauses),
          static_cast<unsigned long long>(tracker.stats().tracks_reacquired));
      // The pause is seen (no frame of any camera for 25 ms and 8 usual intervals), only there.
      EXPECT_EQ(tracker.stats().input_pauses, gap_ms > 0 ? 1u : 0u) << gap_ms << " ms at " << at_s << " s";
      scores.records += follower.records;
      (gap_ms > 0 ? scores.moved : scores.moved_without_stall) += follower.moved;
      if (gap_ms == 0) ids_without_stall = follower.marker_of.size();
      if (gap_ms > 0 && follower.marker_of.size() > ids_without_stall)
        scores.new_ids += follower.marker_of.size() - ids_without_stall;
    }
  }
  std::printf("over the 12 stalls: %zu moves, %zu new ids\n", scores.moved, scores.new_ids);
  return scores;
}

TEST(LateData, IdsStayOnTheirMarkersAfterEveryCameraStalled) {
  const StallScores scores = ids_over_stalls(TrackerOptions{});
  EXPECT_GT(scores.records, 60000u);
  // Measured (2026-12-01): tracks that coasted through the pause are held back and initiation
  // finds their markers again (docs/estimator.md, "After every camera stalled"): 10 moves over
  // the 12 stalls (the nine of 100-250 ms: 117 before, when the first frames after the pause
  // paired tracks and blobs; now 7), 0 without a stall, at the price of new ids (258) for the
  // markers whose reacquisition was ambiguous. 6 moves and 233 new ids at stop 100; with group
  // returns (stop 101) 6 and 136.
  EXPECT_LE(scores.moved, scores.moved_without_stall + 14);
}

// Group returns (tracker.reacquire_group): after a stall every marker comes back at once as a new
// track, and the new tracks stand in for one another's neighbours, placed by their distances
// (docs/estimator.md, "Group returns"). Without them: 6 moves and 233 new ids; with them 6 and 136.
TEST(LateData, GroupReturnsKeepIdsAfterEveryCameraStalled) {
  TrackerOptions off;
  off.reacquire_group = false;
  const StallScores without = ids_over_stalls(off);
  const StallScores with = ids_over_stalls(TrackerOptions{});
  EXPECT_LE(with.new_ids * 4, without.new_ids * 3) << with.new_ids << " new ids against " << without.new_ids;
  EXPECT_LE(with.moved, without.moved + 1);
}

TEST(LateData, IdsOutliveALongStallOfEveryCamera) {
  // A hostile participant's flood on a loaded two-core machine held every camera's frames for
  // 0.43-0.58 s (test_hostile, the demo under attack): the pause is not counted against the
  // tracks (deleted after delete_after_ns of silence outside it), and the three markers' new
  // tracks take their held-back ids again, the clearest first (docs/estimator.md, "After every
  // camera stalled"). Before, every track was deleted and all three came back under new ids.
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  const auto all = simulate(scene, 0.0, 5);
  for (const double gap_ms : {300.0, 450.0, 600.0}) {
    for (const double at_s : {1.5, 3.0, 4.5}) {
      std::vector<Delivered> frames;
      for (const auto& delivered : all) {
        const double t = 1e-9 * static_cast<double>(delivered.frame.stamp_ns - kEpoch);
        if (t < 6.0 && (t < at_s || t >= at_s + 1e-3 * gap_ms)) frames.push_back(delivered);
      }
      const auto result = run(scene, std::move(frames), 5.0);
      std::printf(
          "every camera stalled %.0f ms at %.1f s: %zu ID switches, %llu reacquired, min tracked %.4f\n",
          gap_ms, at_s, result.evaluation.id_switch_count,
          static_cast<unsigned long long>(result.stats.tracks_reacquired),
          result.evaluation.min_tracked_fraction);
      EXPECT_EQ(result.stats.input_pauses, 1u) << gap_ms << " ms at " << at_s << " s";
      EXPECT_EQ(result.evaluation.id_switch_count, 0u) << gap_ms << " ms at " << at_s << " s";
      EXPECT_EQ(result.stats.tracks_reacquired, 3u) << gap_ms << " ms at " << at_s << " s";
    }
  }
}

// A stall from `at` to `end` of the first 6 s of `all`: frames stamped in [lost_at, lost_end) lost,
// the stall's other frames held and delivered after it, each camera's `spacing` after the previous
// camera's (in camera order, each camera's in stamp order).
struct Stall {
  TimeNs at = 0, end = 0, lost_at = 0, lost_end = 0, spacing = 0;
};
std::vector<Delivered> with_stall(const Scene& scene, const std::vector<Delivered>& all, const Stall& stall) {
  std::map<std::string, TimeNs> camera_index;
  for (const auto& camera : scene.cameras())
    camera_index.emplace(camera.calibration.id, static_cast<TimeNs>(camera_index.size()));
  std::vector<Delivered> frames;
  for (const auto& delivered : all) {
    const TimeNs stamp = delivered.frame.stamp_ns;
    if (stamp >= kEpoch + 6'000'000'000 || (stamp >= stall.lost_at && stamp < stall.lost_end)) continue;
    frames.push_back(delivered);
    if (stamp >= stall.at && stamp < stall.end)
      frames.back().received_ns = stall.end + 2'000'000 +
                                  camera_index.at(delivered.frame.camera_id) * stall.spacing +
                                  (stamp - stall.at) / 1000;
  }
  return frames;
}

TEST(LateData, IdsOutliveAStallWhoseFramesComeBackOneCameraAtATime) {
  // test_hostile under the suite's load (stop 82): the rogue's FeatureFrames of 10^6 blobs held the
  // estimator's receive thread for about 190 ms; frames of every camera from part of that time were
  // lost (66 ms: an input pause) and the rest came in one burst, one camera's after another's, so
  // the others' were late and replayed. The markers' new tracks were confirmed before the replay
  // under new ids; the replay made them again from the undone ones, which were then no longer
  // candidates to take the held-back ids (only tracks made under a new id were): all three markers
  // kept new ids (checked offline against a recording: 121 of 180 such stalls). Now an undone new
  // track stays a candidate when the replay confirms it again.
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  const auto all = simulate(scene, 0.0, 5);
  std::size_t cells = 0, failed = 0;
  for (const double stall_ms : {120.0, 190.0, 300.0}) {
    for (const double lost_from : {0.0, 1.0 / 3.0, 2.0 / 3.0}) {  // the lost third of the stall
      for (const double at_s : {1.5, 2.25, 3.0, 3.75, 4.5}) {
        const auto at = kEpoch + static_cast<TimeNs>(at_s * 1e9);
        const auto end = at + static_cast<TimeNs>(stall_ms * 1e6);
        const auto lost_at = at + static_cast<TimeNs>(lost_from * stall_ms * 1e6);
        const auto lost_end = lost_at + static_cast<TimeNs>(stall_ms / 3.0 * 1e6);
        // One camera's held frames after another's, 1 ms apart.
        const auto result = run(scene, with_stall(scene, all, {at, end, lost_at, lost_end, 1'000'000}), 0.0);
        ++cells;
        const bool ok = result.stats.input_pauses == 1 && result.evaluation.id_switch_count == 0;
        failed += !ok;
        if (!ok)
          std::printf(
              "stall %.0f ms at %.2f s, frames lost from %.0f %% of it: %llu input pauses, %zu ID switches, "
              "%llu reacquired\n",
              stall_ms, at_s, 100.0 * lost_from, static_cast<unsigned long long>(result.stats.input_pauses),
              result.evaluation.id_switch_count,
              static_cast<unsigned long long>(result.stats.tracks_reacquired));
      }
    }
  }
  std::printf("%zu of %zu stalls with frames back one camera at a time changed an id\n", failed, cells);
  EXPECT_EQ(failed, 0u);
}

TEST(LateData, IdsOutliveAStallWhoseCamerasComeBackFarApart) {
  // test_hostile in a warm suite run (stop 84): every camera lost for 0.5 s, one for 0.7 s, a 670
  // ms gap in the published stamps, and the three markers came back under new ids. Here a stall of
  // 450 or 670 ms whose first half or three quarters of frames are lost and the rest held, each
  // camera's held frames 100 or 200 ms after the previous camera's. The first camera's frames
  // alone ended the input pause, so the tracks' silence and their reach from where two cameras
  // last saw them counted from there: they were deleted, or the markers' new tracks were out of
  // their reach, before enough cameras' frames came (20 of these 80 cells changed ids, all of the
  // 670 ms stalls with half their frames lost: 6-9 switches each, new ids for about 90 ms). Now a
  // pause lasts until as many cameras as confirm a track have delivered again (docs/estimator.md,
  // "After every camera stalled").
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  const auto all = simulate(scene, 0.0, 5);
  std::size_t cells = 0, failed = 0;
  for (const double stall_ms : {450.0, 670.0}) {
    for (const double lost_part : {0.5, 0.75}) {
      for (const TimeNs spacing : {TimeNs{100'000'000}, TimeNs{200'000'000}}) {
        for (const double at_s : {1.5, 2.25, 3.0, 3.75, 4.5}) {
          for (const double expire_ms : {0.0, 300.0}) {
            const auto at = kEpoch + static_cast<TimeNs>(at_s * 1e9);
            const auto end = at + static_cast<TimeNs>(stall_ms * 1e6);
            const auto lost_end = at + static_cast<TimeNs>(lost_part * stall_ms * 1e6);
            const auto result =
                run(scene, with_stall(scene, all, {at, end, at, lost_end, spacing}), 5.0, expire_ms);
            ++cells;
            const bool ok = result.evaluation.id_switch_count == 0;
            failed += !ok;
            if (!ok)
              std::printf(
                  "stall %.0f ms at %.2f s, first %.0f %% lost, cameras %lld ms apart, expiry %.0f ms: %zu "
                  "ID "
                  "switches, %llu reacquired\n",
                  stall_ms, at_s, 100.0 * lost_part, static_cast<long long>(spacing / 1'000'000), expire_ms,
                  result.evaluation.id_switch_count,
                  static_cast<unsigned long long>(result.stats.tracks_reacquired));
          }
        }
      }
    }
  }
  std::printf("%zu of %zu stalls with cameras back far apart changed an id\n", failed, cells);
  EXPECT_EQ(failed, 0u);
}

TEST(LateData, IdsOutliveAStallLongerThanTheLiveDeletion) {
  // test_hostile (stop 74): the rogue's FeatureFrames of 10^6 blobs held every camera's frames
  // for 0.9 s, the live estimator removed every track after 0.8 s without a frame (expire), and
  // the demo's three markers came back under new ids. Now expire() keeps the confirmed tracks
  // aside and they return when frames come back within 3 s; the markers' new tracks take their
  // ids when the match is clear (reacquire_by_assignment), and no id ever goes to another marker.
  // Before: 3 new ids in every cell (expire deleted the tracks).
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml");
  const auto all = simulate(scene, 0.0, 5);
  std::size_t switches = 0;
  for (const double gap_ms : {900.0, 1200.0, 2000.0, 4000.0}) {
    for (const double at_s : {1.5, 3.0, 4.5}) {
      std::vector<Delivered> frames;
      for (const auto& delivered : all) {
        const double t = 1e-9 * static_cast<double>(delivered.frame.stamp_ns - kEpoch);
        if (t < 8.0 && (t < at_s || t >= at_s + 1e-3 * gap_ms)) frames.push_back(delivered);
      }
      const auto result = run(scene, std::move(frames), 5.0, 800.0);
      std::printf(
          "every camera stalled %.0f ms at %.1f s, tracks expired after 800 ms: %zu ID switches (%zu swaps), "
          "%llu reacquired\n",
          gap_ms, at_s, result.evaluation.id_switch_count, result.evaluation.id_swap_count,
          static_cast<unsigned long long>(result.stats.tracks_reacquired));
      if (at_s + 1e-3 * gap_ms < 8.0) {  // frames came back before the end
        EXPECT_EQ(result.stats.input_pauses, 1u) << gap_ms << " ms at " << at_s << " s";
      }
      EXPECT_EQ(result.evaluation.id_swap_count, 0u) << gap_ms << " ms at " << at_s << " s";
      if (gap_ms == 900.0) {
        EXPECT_EQ(result.evaluation.id_switch_count, 0u) << "900 ms at " << at_s << " s";
      }
      if (gap_ms < 3000.0) switches += result.evaluation.id_switch_count;
    }
  }
  // Measured (2026-12-02): 0 switches at 900 ms, 2, 3, 3 at 1200 ms, 3, 3, 2 at 2000 ms (new ids
  // where the match is not clear: the demo's markers move about a metre in that time).
  EXPECT_LE(switches, 16u);
}

}  // namespace
}  // namespace panoptes::estimator
