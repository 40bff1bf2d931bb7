// SPDX-License-Identifier: Apache-2.0
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <type_traits>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "panoptes/estimator/inbox.h"
#include "panoptes/estimator/tracker.h"
#include "test_cameras.h"

namespace panoptes::estimator {
namespace {

// Three markers on circles of different radii, speeds ~1 m/s.
Eigen::Vector3d marker_position(int m, double t) {
  const double radius = 0.3 + 0.15 * m;
  const double omega = 1.0 / radius * (m % 2 == 0 ? 1.0 : -1.0);
  return {radius * std::cos(omega * t + m), radius * std::sin(omega * t + m),
          0.8 + 0.3 * m + 0.1 * std::sin(2 * t)};
}

struct SyntheticRun {
  std::vector<CameraCalibration> cameras = make_ring_calibration(4, 3.0, 2.0, true);
  std::vector<FeatureFrame> frames;
};

// Four cameras at 100 Hz, phases 0/2.5/5/7.5 ms, 0.1 px noise; `markers(t, camera)` gives the
// positions that camera sees at scene time t.
template <class Markers>
SyntheticRun make_frames(double duration_s, Markers markers, std::uint64_t seed) {
  SyntheticRun run;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<CameraModel> models;
  for (const auto& c : run.cameras) models.push_back(c.model());
  const TimeNs epoch = 1'700'000'000'000'000'000LL;
  for (int k = 0; k < static_cast<int>(duration_s * 100); ++k) {
    for (std::size_t c = 0; c < models.size(); ++c) {
      const TimeNs t = k * 10'000'000LL + static_cast<TimeNs>(c) * 2'500'000LL;
      FeatureFrame frame;
      frame.camera_id = run.cameras[c].id;
      frame.frame = k;
      frame.stamp_ns = epoch + t;
      for (const Eigen::Vector3d& p : markers(ns_to_seconds(t), static_cast<int>(c))) {
        const auto pixel = models[c].project(p);
        if (!pixel || !models[c].in_image(*pixel)) continue;
        Blob blob;
        blob.x = pixel->x() + noise(rng);
        blob.y = pixel->y() + noise(rng);
        blob.area = 12;
        frame.blobs.push_back(blob);
      }
      std::shuffle(frame.blobs.begin(), frame.blobs.end(), rng);
      run.frames.push_back(frame);
    }
  }
  return run;
}

// The three markers of marker_position(); `visible(m, t)` hides markers, or `visible(m, t, camera)`
// hides them from some cameras only.
template <class Visible>
SyntheticRun make_run(double duration_s, Visible visible, std::uint64_t seed = 1) {
  return make_frames(
      duration_s,
      [&](double t, int camera) {
        std::vector<Eigen::Vector3d> seen;
        for (int m = 0; m < 3; ++m) {
          if constexpr (std::is_invocable_v<Visible, int, double, int>) {
            if (!visible(m, t, camera)) continue;
          } else {
            if (!visible(m, t)) continue;
          }
          seen.push_back(marker_position(m, t));
        }
        return seen;
      },
      seed);
}

TimeNs scene_time(TimeNs stamp) {
  return stamp - 1'700'000'000'000'000'000LL;
}

// Feeds `run` to a tracker with `options`, calling visit(scene time s, track) for each current track
// after every frame; returns the tracker's counters.
template <class Visit>
TrackerStats replay(const SyntheticRun& run, const TrackerOptions& options, Visit visit) {
  Tracker tracker(options);
  tracker.set_calibration(SystemCalibration{run.cameras});
  for (const auto& frame : run.frames) {
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    for (const auto& track : tracker.current_tracks()) visit(t, track);
  }
  return tracker.stats();
}

// For each marker, the ids of the tracks nearest to it (within 5 mm) over the run, and the worst error.
struct Followed {
  std::map<int, std::set<std::int64_t>> ids;
  std::map<int, double> worst_error;
  std::map<int, double> sum2;
  std::map<int, int> matched;
  int instants = 0;
  int extra_tracks = 0;
};

template <class Visible>
Followed follow(Tracker& tracker, const SyntheticRun& run, double judge_after_s, Visible visible) {
  Followed f;
  for (const auto& frame : run.frames) {
    EXPECT_EQ(tracker.process(frame), FrameOutcome::kProcessed);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    if (t < judge_after_s) continue;
    ++f.instants;
    const auto tracks = tracker.current_tracks();
    int matched_now = 0;
    for (int m = 0; m < 3; ++m) {
      for (const auto& track : tracks) {
        const double error = (track.p - marker_position(m, t)).norm();
        if (error < 0.005) {
          f.ids[m].insert(track.id);
          f.worst_error[m] = std::max(f.worst_error[m], error);
          f.sum2[m] += error * error;
          ++f.matched[m];
          ++matched_now;
        }
      }
    }
    int expected = 0;
    for (int m = 0; m < 3; ++m) expected += visible(m, t) ? 1 : 0;
    f.extra_tracks = std::max(f.extra_tracks, static_cast<int>(tracks.size()) - 3);
  }
  return f;
}

TEST(Tracker, InitiatesAndTracksThreeMarkersWithStableIds) {
  auto always = [](int, double) { return true; };
  const auto run = make_run(3.0, always);
  Tracker tracker;
  SystemCalibration calibration{run.cameras};
  tracker.set_calibration(calibration);
  const auto f = follow(tracker, run, 0.3, always);
  for (int m = 0; m < 3; ++m) {
    EXPECT_EQ(f.ids.at(m).size(), 1u) << "marker " << m << " changed identity";
    EXPECT_EQ(f.matched.at(m), f.instants) << "marker " << m << " not tracked at every instant";
    const double rmse = std::sqrt(f.sum2.at(m) / f.matched.at(m));
    std::printf("marker %d: RMSE %.3f mm, worst %.3f mm\n", m, rmse * 1e3, f.worst_error.at(m) * 1e3);
    EXPECT_LT(rmse, 0.8e-3) << "marker " << m;
    EXPECT_LT(f.worst_error.at(m), 3.0e-3) << "marker " << m;
  }
  EXPECT_EQ(f.extra_tracks, 0);
  EXPECT_EQ(tracker.stats().tracks_confirmed, 3u);
}

TEST(Tracker, KeepsIdentityThroughShortOcclusionAndDeletesAfterTimeout) {
  // Marker 1 vanishes from 1.0 s to 1.15 s (coasting), marker 2 for good at 2.0 s.
  auto visible = [](int m, double t) {
    if (m == 1 && t > 1.0 && t < 1.15) return false;
    if (m == 2 && t > 2.0) return false;
    return true;
  };
  const auto run = make_run(3.0, visible, 2);
  // Coasting tracks are published only with the uncertainty limit off (see the next test).
  TrackerOptions options;
  options.publish_max_sigma_m = 0;
  Tracker tracker(options);
  tracker.set_calibration(SystemCalibration{run.cameras});
  std::int64_t id_before = 0;
  std::int64_t id_after = 0;
  bool saw_coasting = false;
  for (const auto& frame : run.frames) {
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    for (const auto& track : tracker.current_tracks()) {
      const double error = (track.p - marker_position(1, t)).norm();
      if (t > 0.9 && t < 1.0 && error < 0.005) id_before = track.id;
      if (t > 1.3 && t < 1.4 && error < 0.005) id_after = track.id;
      if (t > 1.06 && t < 1.14 && track.status == TrackStatus::kCoasting) saw_coasting = true;
    }
  }
  EXPECT_NE(id_before, 0);
  EXPECT_EQ(id_before, id_after) << "marker 1 was given a new identity after a 150 ms occlusion";
  EXPECT_TRUE(saw_coasting);
  // Marker 2's track is gone 0.3 s after it disappeared; two remain.
  EXPECT_EQ(tracker.current_tracks().size(), 2u);
  EXPECT_GE(tracker.stats().tracks_deleted, 1u);
}

// A coasting track's widened gate can take a neighbour's blobs; the two tracks then meet on the
// neighbour and the duplicate merge keeps one. It used to keep the one with more updates: the older,
// coasting one, so the neighbour, followed all along, changed id (a shank marker hidden for 0.8 s
// took its neighbour's identity and name, test_label_occlusion seed 3). Here marker A (tracked
// from the start) moves at 0.3 m/s towards B (static, tracked from 0.5 s) and vanishes 3 cm short
// of it; its coasting track runs into B. With reacquire_sigma_m (the default) a track that uncertain
// takes no blob at all, so there is nothing to merge (next test); the merge rule is tested without.
struct CoastIntoNeighbour {
  std::set<std::int64_t> ids_on_b;
  std::int64_t id_of_a = 0;
  TrackerStats stats;
};

CoastIntoNeighbour coast_into_neighbour(const TrackerOptions& options) {
  const Eigen::Vector3d b(0.1, 0.2, 1.0);
  const auto a = [&](double t) { return Eigen::Vector3d(b.x() - 0.35 + 0.3 * t, b.y(), b.z()); };
  const double hidden_from = 0.32 / 0.3;
  const auto run = make_frames(
      2.0,
      [&](double t, int) {
        std::vector<Eigen::Vector3d> seen;
        if (t < hidden_from) seen.push_back(a(t));
        if (t >= 0.5) seen.push_back(b);
        return seen;
      },
      4);
  CoastIntoNeighbour result;
  result.stats = replay(run, options, [&](double t, const TrackRecord& track) {
    if (t > 0.7 && (track.p - b).norm() < 0.005) result.ids_on_b.insert(track.id);
    if (t > 0.9 && t < hidden_from && (track.p - a(t)).norm() < 0.005) result.id_of_a = track.id;
  });
  return result;
}

TEST(Tracker, AMergeKeepsTheTrackThatFollowedTheMarkerNotTheOneBackFromACoast) {
  TrackerOptions options;
  options.reacquire_sigma_m = 0;  // coasting tracks take blobs in their gates
  const auto r = coast_into_neighbour(options);
  std::printf("ids on B: %zu (A's track %lld), merged %llu\n", r.ids_on_b.size(),
              static_cast<long long>(r.id_of_a), static_cast<unsigned long long>(r.stats.tracks_merged));
  EXPECT_NE(r.id_of_a, 0);
  EXPECT_GE(r.stats.tracks_merged, 1u) << "the coasting track should have met B's";
  EXPECT_EQ(r.ids_on_b.size(), 1u) << "B changed id when A's coasting track met it";
  EXPECT_EQ(r.ids_on_b.count(r.id_of_a), 0u) << "A's identity moved onto B";
}

// The default (reacquire_sigma_m): A's track, held back once its prediction is uncertain, takes
// none of B's blobs; B keeps its one id and nothing needs merging.
TEST(Tracker, AHeldBackTrackTakesNoBlobOfItsNeighbour) {
  const auto r = coast_into_neighbour(TrackerOptions{});
  std::printf("ids on B: %zu (A's track %lld), merged %llu\n", r.ids_on_b.size(),
              static_cast<long long>(r.id_of_a), static_cast<unsigned long long>(r.stats.tracks_merged));
  EXPECT_NE(r.id_of_a, 0);
  EXPECT_EQ(r.stats.tracks_merged, 0u);
  EXPECT_EQ(r.ids_on_b.size(), 1u);
  EXPECT_EQ(r.ids_on_b.count(r.id_of_a), 0u);
}

// Reacquisition (reacquire_sigma_m, issue 35 item 3): a marker hidden for 250 ms comes back through
// initiation and takes its held-back track's id once confirmed; two markers 4 cm apart hidden
// together come back too close to tell apart, and neither takes the other's id (new ids instead).
TEST(Tracker, ReacquiresAMarkerUnderItsIdAndNeverGivesANeighboursId) {
  const auto position = [](int m, double t) -> Eigen::Vector3d {
    if (m == 1) return marker_position(0, t) + Eigen::Vector3d(0, 0, 0.04);
    return marker_position(m, t);
  };
  const auto visible = [](int m, double t) {
    if (m < 2) return t < 1.0 || t > 1.25;
    return t < 1.5 || t > 1.75;
  };
  const auto run = make_frames(
      2.5,
      [&](double t, int) {
        std::vector<Eigen::Vector3d> seen;
        for (int m = 0; m < 3; ++m)
          if (visible(m, t)) seen.push_back(position(m, t));
        return seen;
      },
      5);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  std::map<int, std::set<std::int64_t>> before, after;
  for (const auto& frame : run.frames) {
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    for (const auto& track : tracker.current_tracks()) {
      for (int m = 0; m < 3; ++m) {
        if ((track.p - position(m, t)).norm() > 0.005) continue;
        const double hidden_until = m < 2 ? 1.25 : 1.75;
        if (t > 0.5 && t < hidden_until - 0.25) before[m].insert(track.id);
        if (t > hidden_until + 0.1) after[m].insert(track.id);
      }
    }
  }
  std::printf("reacquired %llu; marker 2 ids before %zu, after %zu\n",
              static_cast<unsigned long long>(tracker.stats().tracks_reacquired), before[2].size(),
              after[2].size());
  for (int m = 0; m < 3; ++m) {
    ASSERT_EQ(before[m].size(), 1u) << "marker " << m;
    ASSERT_EQ(after[m].size(), 1u) << "marker " << m;
  }
  EXPECT_EQ(*after[2].begin(), *before[2].begin()) << "marker 2 back from 250 ms out of view under a new id";
  EXPECT_GE(tracker.stats().tracks_reacquired, 1u);
  EXPECT_EQ(after[0].count(*before[1].begin()), 0u) << "marker 0 took marker 1's id";
  EXPECT_EQ(after[1].count(*before[0].begin()), 0u) << "marker 1 took marker 0's id";
}

// reacquire_max_seen_distance_m (issue 35 item 3, stop 69): marker A, still, leaves every view at
// t = 1.0 s, and at its place marker C moves off at 1.5 m/s across camera 0's view, seen by camera 0
// alone until 1.2 s, then by none until 1.3 s, then by all four. A's track follows C's blob in
// camera 0 and is held back where C went; C's confirmed track is 0.45 m from where two cameras last
// placed A, and takes a new id. Without the test it takes A's (a marker given another's identity).
TEST(Tracker, AHeldBackTrackThatOneCameraDraggedAwayGivesItsIdToNoOtherMarker) {
  const Eigen::Vector3d a(0.1, 0.0, 1.0);
  const Eigen::Vector3d across(-std::sin(0.3), std::cos(0.3), 0.0);  // square to camera 0's axis
  const auto c_position = [&](double t) -> Eigen::Vector3d { return a + 1.5 * (t - 1.0) * across; };
  const auto run = make_frames(
      1.8,
      [&](double t, int camera) {
        std::vector<Eigen::Vector3d> seen{marker_position(2, t)};  // a third marker, far off, all along
        if (t < 1.0)
          seen.push_back(a);
        else if ((t < 1.2 && camera == 0) || t >= 1.3)
          seen.push_back(c_position(t));
        return seen;
      },
      7);
  const auto ids = [&](const TrackerOptions& options) {
    std::set<std::int64_t> on_a, on_c;
    replay(run, options, [&](double t, const TrackRecord& track) {
      if (t > 0.5 && t < 1.0 && (track.p - a).norm() < 0.005) on_a.insert(track.id);
      if (t > 1.45 && (track.p - c_position(t)).norm() < 0.005) on_c.insert(track.id);
    });
    return std::make_pair(on_a, on_c);
  };
  const auto [on_a, on_c] = ids(TrackerOptions{});
  ASSERT_EQ(on_a.size(), 1u);
  ASSERT_EQ(on_c.size(), 1u);
  EXPECT_NE(*on_c.begin(), *on_a.begin()) << "marker C took marker A's id";
  TrackerOptions without;
  without.reacquire_max_seen_distance_m = 0;
  const auto [on_a0, on_c0] = ids(without);
  ASSERT_EQ(on_a0.size(), 1u);
  ASSERT_EQ(on_c0.size(), 1u);
  std::printf("C's id: %lld (A's %lld); without the test %lld (A's %lld)\n",
              static_cast<long long>(*on_c.begin()), static_cast<long long>(*on_a.begin()),
              static_cast<long long>(*on_c0.begin()), static_cast<long long>(*on_a0.begin()));
  EXPECT_EQ(*on_c0.begin(), *on_a0.begin()) << "the scene no longer exercises the test";
}

// Reacquisition by neighbours (reacquire_neighbours_m, issue 35 item 3, stop 93): five markers of
// one limb (10-16 cm apart) swing round a circle at 0.75 m/s, turning with it. `hidden` markers
// leave every view for 0.8 s, longer than delete_after_ns (0.3 s): their tracks are deleted and
// they come back 0.6 m away. Returns, per marker, the ids on it before and after, and the counters.
struct LimbRun {
  std::map<int, std::set<std::int64_t>> before, after;
  TrackerStats stats;
};

// Five markers of a limb, 10-17 cm apart, turning rigidly at 1.5 rad/s on a circle of 0.5 m.
Eigen::Vector3d limb_position(int m, double t) {
  static const std::array<Eigen::Vector3d, 5> offsets{
      Eigen::Vector3d(0.10, 0.0, 0.0), Eigen::Vector3d(-0.06, 0.07, 0.0), Eigen::Vector3d(0.0, 0.12, 0.06),
      Eigen::Vector3d(0.05, -0.10, -0.05), Eigen::Vector3d(-0.04, -0.02, 0.15)};
  const double angle = 1.5 * t;
  const Eigen::Vector3d centre(0.5 * std::cos(angle), 0.5 * std::sin(angle), 1.0);
  return centre + Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * offsets[static_cast<std::size_t>(m)];
}

LimbRun run_limb(const std::set<int>& hidden, const TrackerOptions& options) {
  const auto run = make_frames(
      2.6,
      [&](double t, int) {
        std::vector<Eigen::Vector3d> seen;
        for (int m = 0; m < 5; ++m)
          if (!hidden.contains(m) || t < 1.0 || t >= 1.8) seen.push_back(limb_position(m, t));
        return seen;
      },
      11);
  LimbRun out;
  out.stats = replay(run, options, [&](double t, const TrackRecord& track) {
    for (int m = 0; m < 5; ++m) {
      if ((track.p - limb_position(m, t)).norm() > 0.005) continue;
      if (t > 0.5 && t < 1.0) out.before[m].insert(track.id);
      if (t > 2.0) out.after[m].insert(track.id);
    }
  });
  return out;
}

TEST(Tracker, AMarkerBackAfterItsTrackWasDeletedTakesItsIdWhereItsNeighboursCarriedIt) {
  const LimbRun on = run_limb({0}, TrackerOptions{});
  TrackerOptions off_options;
  off_options.reacquire_neighbours_m = 0;
  const LimbRun off = run_limb({0}, off_options);
  for (const LimbRun* r : {&on, &off}) {
    for (int m = 0; m < 5; ++m) {
      ASSERT_EQ(r->before.at(m).size(), 1u) << "marker " << m;
      ASSERT_EQ(r->after.at(m).size(), 1u) << "marker " << m;
    }
  }
  std::printf("marker 0: id %lld before, %lld after (%llu by neighbours); option off: %lld after\n",
              static_cast<long long>(*on.before.at(0).begin()),
              static_cast<long long>(*on.after.at(0).begin()),
              static_cast<unsigned long long>(on.stats.tracks_reacquired_by_neighbours),
              static_cast<long long>(*off.after.at(0).begin()));
  EXPECT_EQ(*on.after.at(0).begin(), *on.before.at(0).begin())
      << "back from 0.8 s out of view under a new id";
  EXPECT_EQ(on.stats.tracks_reacquired_by_neighbours, 1u);
  EXPECT_NE(*off.after.at(0).begin(), *off.before.at(0).begin()) << "the scene no longer exercises the rule";
}

// Two neighbours hidden together come back each under its own id: their carried positions are
// 17 cm apart, and the three markers left in view carry both.
TEST(Tracker, TwoMarkersBackTogetherTakeTheirOwnIdsNotEachOthers) {
  const LimbRun r = run_limb({0, 1}, TrackerOptions{});
  for (int m = 0; m < 5; ++m) {
    ASSERT_EQ(r.before.at(m).size(), 1u) << "marker " << m;
    ASSERT_EQ(r.after.at(m).size(), 1u) << "marker " << m;
  }
  std::printf("reacquired by neighbours: %llu\n",
              static_cast<unsigned long long>(r.stats.tracks_reacquired_by_neighbours));
  EXPECT_EQ(*r.after.at(0).begin(), *r.before.at(0).begin());
  EXPECT_EQ(*r.after.at(1).begin(), *r.before.at(1).begin());
  EXPECT_EQ(r.stats.tracks_reacquired_by_neighbours, 2u);
}

// The limb with marker 0 seen by camera 0 alone from 1.0 to 1.5 s, and camera 1 showing stray(t)
// (if any) from 1.2 to 1.3 s: the two tests below.
template <class Stray>
SyntheticRun limb_with_stray(Stray stray, std::uint64_t seed) {
  return make_frames(
      2.0,
      [&](double t, int camera) {
        std::vector<Eigen::Vector3d> seen;
        for (int m = 1; m < 5; ++m) seen.push_back(limb_position(m, t));
        if (t < 1.0 || t >= 1.5 || camera == 0) seen.push_back(limb_position(0, t));
        if (camera == 1 && t >= 1.2 && t < 1.3)
          if (const std::optional<Eigen::Vector3d> p = stray(t)) seen.push_back(*p);
        return seen;
      },
      seed);
}

// Marker 0's ids before 1.0 s and from 1.6 s, the worst error of the track that had its id over
// 1.0-1.5 s, and a counter of the tracker's (`refused`).
struct OneViewOutcome {
  std::uint64_t refused = 0;
  std::set<std::int64_t> before, after;
  double worst_error = 0;
};

template <class Refused>
OneViewOutcome one_view_outcome(const SyntheticRun& run, const TrackerOptions& options, Refused refused) {
  OneViewOutcome o;
  std::int64_t id = -1;
  o.refused = refused(replay(run, options, [&](double t, const TrackRecord& track) {
    const bool on_marker = (track.p - limb_position(0, t)).norm() < 0.005;
    if (t > 0.5 && t < 1.0 && on_marker) {
      o.before.insert(track.id);
      id = track.id;
    }
    if (t >= 1.0 && t < 1.5 && track.id == id)
      o.worst_error = std::max(o.worst_error, (track.p - limb_position(0, t)).norm());
    if (t > 1.6 && on_marker) o.after.insert(track.id);
  }));
  return o;
}

// Camera 0's centre (make_frames' cameras).
const Eigen::Vector3d kLimbEye(3.0 * std::cos(0.3), 3.0 * std::sin(0.3), 2.0);

// return_max_carried_distance_m (issue 35 item 3, stop 98), after ceiling6/walk/c1/s1's heel: from
// 1.0 s camera 0 alone sees the limb's marker 0, and from 1.2 s to 1.3 s camera 1 sees a stray
// blob on camera 0's ray through it, 0.4 m further along (another marker's, as L.SH3's was for the
// heel); from 1.5 s every camera sees marker 0 again. Marker 0's track, its depth uncertain, gates
// the stray blob. The update would put it 0.4 m from where the four other markers carried it:
// refused, and the track stays on marker 0. With the option off it takes the stray blob.
TEST(Tracker, AOneViewTrackTakesNoSecondViewFarFromWhereItsNeighboursCarriedIt) {
  const auto run = limb_with_stray(
      [](double t) -> std::optional<Eigen::Vector3d> {
        const Eigen::Vector3d marker = limb_position(0, t);
        return marker + 0.4 * (marker - kLimbEye).normalized();
      },
      14);
  EXPECT_EQ(TrackerOptions{}.return_max_carried_distance_m, 0.3);  // the default since stop 98
  const auto outcome = [&](double distance_m) {
    TrackerOptions options;
    options.return_max_carried_distance_m = distance_m;
    return one_view_outcome(run, options, [](const TrackerStats& s) { return s.returns_far_from_carried; });
  };
  const OneViewOutcome with = outcome(0.3);
  const OneViewOutcome without = outcome(0);
  std::printf(
      "marker 0's track 1.0-1.5 s: refused %llu second views, worst error %.3f m; option off %.3f m\n",
      static_cast<unsigned long long>(with.refused), with.worst_error, without.worst_error);
  ASSERT_EQ(with.before.size(), 1u);
  ASSERT_EQ(without.before.size(), 1u);
  EXPECT_GE(with.refused, 1u);
  EXPECT_EQ(without.refused, 0u);
  EXPECT_LT(with.worst_error, 0.05);
  EXPECT_EQ(with.after, with.before) << "marker 0 keeps its id";
  EXPECT_GT(without.worst_error, 0.2) << "the scene no longer exercises the option";
}

// return_fresh_max_jump_m (issue 35 item 3, stop 99), after ceiling4/walk/c1/s2's knee (12 s): from
// 1.0 s camera 0 alone sees the limb's marker 0, and from 1.2 s to 1.3 s every frame of camera 1 has
// one false blob on camera 0's ray through it, 0.6 or 0.9 m further along by turns (a false blob
// lasts one frame; clutter was 1 blob per frame there); from 1.5 s every camera sees marker 0 again.
// Marker 0's track, its depth uncertain, gates the false blobs. None continues a blob of camera
// 1's previous frame, and each would move the track more than 0.5 m, far from where its neighbours
// carried it: refused, and the track only drifts along camera 0's ray (0.13 m: one view has no
// depth). With the option off it takes one and stays 0.6 m off. Both runs publish every record (the
// track's own position is judged) and turn second views near the carried point off, which would
// refuse these blobs too.
TEST(Tracker, AOneViewTrackTakesNoFreshBlobThatWouldMoveItFar) {
  const auto run = limb_with_stray(
      [](double t) -> std::optional<Eigen::Vector3d> {
        const Eigen::Vector3d marker = limb_position(0, t);
        const double along = std::lround(t * 100.0) % 2 == 0 ? 0.6 : 0.9;
        return marker + along * (marker - kLimbEye).normalized();
      },
      15);
  EXPECT_EQ(TrackerOptions{}.return_fresh_max_jump_m, 0.5);  // the default since stop 99
  const auto outcome = [&](double jump_m) {
    TrackerOptions options;
    options.return_max_carried_distance_m = 0;
    options.return_fresh_max_jump_m = jump_m;
    options.publish_max_sigma_m = 0;  // every record published: the track's own position is judged
    options.publish_max_innovation_px = 0;
    return one_view_outcome(run, options, [](const TrackerStats& s) { return s.returns_fresh_far; });
  };
  const OneViewOutcome with = outcome(0.5);
  const OneViewOutcome without = outcome(0);
  std::printf("marker 0's track 1.0-1.5 s: refused %llu fresh blobs, worst error %.3f m; option off %.3f m\n",
              static_cast<unsigned long long>(with.refused), with.worst_error, without.worst_error);
  ASSERT_EQ(with.before.size(), 1u);
  ASSERT_EQ(without.before.size(), 1u);
  EXPECT_GE(with.refused, 1u);
  EXPECT_EQ(without.refused, 0u);
  EXPECT_LT(with.worst_error, 0.2) << "one camera's drift along its ray only";
  EXPECT_EQ(with.after, with.before) << "marker 0 keeps its id";
  EXPECT_GT(without.worst_error, 0.4) << "the scene no longer exercises the option";
}

// delete_runaway_tracks (issue 35 item 3, stop 70): marker B rests 1 s in every view, then sweeps
// 1.5 m across camera 0's view (150 m/s² for 0.1 s, then 15 m/s for 0.05 s) seen by the first
// `cameras` cameras only, then rests again in every view. Seen by camera 0 alone, its track
// becomes fast by one camera's updates, which cannot tell where along camera 0's rays it is (as
// the runaway tracks of walking markers that one camera dragged at 12-65 m/s): it is deleted, and
// B at rest is a new track. Seen by cameras 0 and 1, the sweep is a fast marker like a club head:
// kept, under its id. With the option off, camera 0's track is kept too.
TEST(Tracker, ATrackMadeFastByOneCameraAloneIsDeleted) {
  const Eigen::Vector3d across(-std::sin(0.3), std::cos(0.3), 0.0);  // square to camera 0's axis
  const Eigen::Vector3d start = Eigen::Vector3d(0.1, 0.0, 1.0) - 0.9 * across;
  const auto b_position = [&](double t) -> Eigen::Vector3d {
    const double s = std::clamp(t - 1.0, 0.0, 0.1), u = std::clamp(t - 1.1, 0.0, 0.05);
    return start + (75.0 * s * s + 15.0 * u) * across;  // 150 m/s² for 0.1 s, 15 m/s for 0.05 s
  };
  struct Outcome {
    std::uint64_t runaways = 0;
    std::set<std::int64_t> before, after;  // ids on B at rest before and after the sweep
  };
  const auto sweep = [&](int cameras, const TrackerOptions& options) {
    const auto run = make_frames(
        1.6,
        [&](double t, int camera) {
          std::vector<Eigen::Vector3d> seen{marker_position(2, t)};  // another marker, far off, all along
          if (t < 1.0 || t >= 1.15 || camera < cameras) seen.push_back(b_position(t));
          return seen;
        },
        11);
    Outcome outcome;
    outcome.runaways = replay(run, options, [&](double t, const TrackRecord& track) {
                         if (t > 0.5 && t < 1.0 && (track.p - b_position(t)).norm() < 0.005)
                           outcome.before.insert(track.id);
                         if (t > 1.45 && (track.p - b_position(t)).norm() < 0.005)
                           outcome.after.insert(track.id);
                       }).runaway_tracks_deleted;
    return outcome;
  };
  const Outcome one = sweep(1, TrackerOptions{});
  const Outcome two = sweep(2, TrackerOptions{});
  TrackerOptions off;
  off.delete_runaway_tracks = false;
  const Outcome one_off = sweep(1, off);
  std::printf("runaways deleted: camera 0 alone %llu, cameras 0 and 1 %llu, option off %llu\n",
              static_cast<unsigned long long>(one.runaways), static_cast<unsigned long long>(two.runaways),
              static_cast<unsigned long long>(one_off.runaways));
  for (const Outcome* o : {&one, &two, &one_off}) {
    ASSERT_EQ(o->before.size(), 1u);
    ASSERT_EQ(o->after.size(), 1u);
  }
  EXPECT_EQ(one.runaways, 1u);
  EXPECT_NE(*one.after.begin(), *one.before.begin()) << "the runaway's id came back";
  EXPECT_EQ(two.runaways, 0u) << "a fast marker two cameras see is no runaway";
  EXPECT_EQ(*two.after.begin(), *two.before.begin());
  EXPECT_EQ(one_off.runaways, 0u);
  EXPECT_EQ(*one_off.after.begin(), *one_off.before.begin()) << "the scene no longer exercises the option";
}

// return_velocity_cap_mps (issue 35 item 3, stop 71): marker B moves at 3 m/s along camera 0's ray,
// in every view, and stops at 1.0 s; from then on camera 0 sees it and camera 1 catches one frame of
// it every 150 ms (at 1.14 s, 1.29 s, ...), the others none until 1.6 s. Camera 0 cannot see that B
// stopped (its image of B does not move): B's track slides on along the ray, held back, and camera
// 1's frame pulls it back. Without the cap the filter turns that pull into a velocity the other
// way, which camera 0's frames carry on until camera 1's next frame (the elbow of
// ring6/walk/c1/s1: 1.3 -> 9.3 m/s). With the cap (3 m/s) B's track is near rest and stays near B.
TEST(Tracker, AReturnToTwoViewsChangesVelocityByAtMostTheCap) {
  const Eigen::Vector3d eye(3.0 * std::cos(0.3), 3.0 * std::sin(0.3), 2.0);  // camera 0's centre
  const Eigen::Vector3d ray = (Eigen::Vector3d(0.0, 0.0, 1.0) - eye).normalized();
  const auto b_position = [&](double t) -> Eigen::Vector3d {
    return eye + 3.0 * std::min(t, 1.0) * ray;  // 3 m/s along the ray, at rest from 1.0 s
  };
  const auto run = make_frames(
      1.7,
      [&](double t, int camera) {
        std::vector<Eigen::Vector3d> seen{marker_position(2, t)};  // another marker, far off, all along
        const bool glimpse = camera == 1 && std::fmod(t - 1.0, 0.15) > 0.14;
        if (t < 1.0 || t >= 1.6 || camera == 0 || glimpse) seen.push_back(b_position(t));
        return seen;
      },
      12);
  struct Outcome {
    std::uint64_t capped = 0;
    double worst_speed = 0;  // of B's track from camera 1's first frame of it to its second
    double worst_error = 0;  // of its position then
    std::set<std::int64_t> ids;
  };
  const auto outcome = [&](const TrackerOptions& options) {
    Outcome o;
    o.capped = replay(run, options, [&](double t, const TrackRecord& track) {
                 if (t < 0.5 || (track.p - b_position(t)).norm() > 0.5) return;
                 o.ids.insert(track.id);
                 if (t < 1.1 || t > 1.285) return;
                 o.worst_speed = std::max(o.worst_speed, track.v.norm());
                 o.worst_error = std::max(o.worst_error, (track.p - b_position(t)).norm());
               }).return_velocities_capped;
    return o;
  };
  // The records are the measure of the state here: publish them whatever the views say (with
  // publish_max_innovation_px, the uncapped track's records from the pull-back on are withheld).
  // Without the one-view decay (on by default since stop 89), which leaves the return little
  // velocity to pull (docs/estimator.md, "One-view velocity"): the cap's own scene.
  TrackerOptions on;
  on.publish_max_innovation_px = 0;
  on.one_view_velocity_time_constant_ns = 0;
  EXPECT_EQ(on.return_velocity_cap_mps, 3.0);  // the default since stop 97
  TrackerOptions off = on;
  off.return_velocity_cap_mps = 0;
  const Outcome capped = outcome(on);
  const Outcome uncapped = outcome(off);
  std::printf(
      "B's track after camera 1's first frame: capped (%llu updates) speed <= %.2f m/s, error <= %.3f m; "
      "uncapped speed <= %.2f m/s, error <= %.3f m\n",
      static_cast<unsigned long long>(capped.capped), capped.worst_speed, capped.worst_error,
      uncapped.worst_speed, uncapped.worst_error);
  EXPECT_EQ(capped.ids.size(), 1u);
  EXPECT_EQ(uncapped.ids.size(), 1u);
  EXPECT_GE(capped.capped, 1u);
  EXPECT_EQ(uncapped.capped, 0u);
  EXPECT_GT(uncapped.worst_speed, 1.0) << "the scene no longer exercises the cap";
  EXPECT_LT(capped.worst_speed, 0.5 * uncapped.worst_speed);
  EXPECT_LT(capped.worst_error, 0.5 * uncapped.worst_error);
}

// publish_max_innovation_px (issue 35 item 3, stop 85): from 1.0 s cameras 2 and 3 see the marker
// `offset` higher than cameras 0 and 1 do (a neighbour in their views instead of the marker, as
// two clavicles 5 cm apart on the walk grid, each camera showing one). At 1 cm the track takes
// both pairs' blobs and sits between them, its innovations in every view about 3 px: some of its
// records are withheld (measured: 308 of 320 published, 320 without the limit). At 1.5 cm and
// more the pairs make two tracks, each consistent (not asserted); with no offset nothing is
// withheld.
TEST(Tracker, ATrackWhoseViewsDisagreeIsNotPublished) {
  const auto published = [](double offset_m, double limit_px) {
    const auto run = make_frames(
        2.0,
        [&](double t, int camera) {
          Eigen::Vector3d p = marker_position(0, t);
          if (camera >= 2 && t >= 1.0) p += Eigen::Vector3d(0.0, 0.0, offset_m);
          return std::vector<Eigen::Vector3d>{p};
        },
        3);
    TrackerOptions options;
    options.publish_max_innovation_px = limit_px;
    int records = 0;
    replay(run, options, [&](double t, const TrackRecord&) { records += t >= 1.2; });
    return records;
  };
  const int agree_on = published(0.0, 3.0), agree_off = published(0.0, 0.0);
  const int apart_on = published(0.01, 3.0), apart_off = published(0.01, 0.0);
  std::printf(
      "records from 1.2 s: views agree %d with the limit, %d without; 1 cm apart %d with, %d without\n",
      agree_on, agree_off, apart_on, apart_off);
  EXPECT_EQ(agree_on, agree_off);
  EXPECT_GT(apart_off, 0);
  EXPECT_LT(apart_on, apart_off);
}

// reanchor_one_view_tracks (issue 35 item 3, stop 76): marker B rests in every view until 1.0 s,
// then moves 0.18 m along camera 0's ray in 0.1 s, seen by camera 0 alone, and rests there in the
// views of cameras 0 and 1. Camera 0's image of B does not move, so B's track stays where it was,
// held by camera 0's blob; the process noise is small (0.1 m^2/s^3), so camera 1's blob of B stays
// outside the track's gate for a while (as a wrong velocity kept the elbow's track of
// ring4/walk/c0/s1 off its marker, docs/estimator.md, "One-view tracks"). Without re-anchoring B is
// untracked until the track's gate has grown to camera 1's blob (0.23 s): camera 0's blob is the
// track's, so the initiator cannot pair camera 1's. With it, the track moves to B under its id at
// camera 0's next frame.
TEST(Tracker, AOneViewTrackIsReanchoredWhereTwoViewsPutItsBlob) {
  const Eigen::Vector3d eye(3.0 * std::cos(0.3), 3.0 * std::sin(0.3), 2.0);  // camera 0's centre
  const Eigen::Vector3d ray = (Eigen::Vector3d(0.0, 0.0, 1.0) - eye).normalized();
  const auto b_position = [&](double t) -> Eigen::Vector3d {
    return eye + (2.9 + 1.8 * std::clamp(t - 1.0, 0.0, 0.1)) * ray;
  };
  const auto run = make_frames(
      1.6,
      [&](double t, int camera) {
        std::vector<Eigen::Vector3d> seen{marker_position(2, t)};  // another marker, far off, all along
        if (t < 1.0 || camera == 0 || (t >= 1.1 && camera == 1)) seen.push_back(b_position(t));
        return seen;
      },
      13);
  struct Outcome {
    std::uint64_t reanchored = 0;
    std::set<std::int64_t> before;  // ids on B before 1.0 s
    std::set<std::int64_t> after;   // ids on B from 1.12 s
    int instants = 0, tracked = 0;  // frames from 1.12 s, and those with a track within 5 mm of B
  };
  const auto outcome = [&](bool reanchor) {
    TrackerOptions options;
    options.process_noise = 0.1;
    options.reanchor_one_view_tracks = reanchor;
    Outcome o;
    double last = -1;
    o.reanchored = replay(run, options, [&](double t, const TrackRecord& track) {
                     const bool on_b = (track.p - b_position(t)).norm() < 0.005;
                     if (t > 0.5 && t < 1.0 && on_b) o.before.insert(track.id);
                     if (t < 1.12) return;
                     if (t != last) ++o.instants;
                     last = t;
                     if (!on_b) return;
                     o.after.insert(track.id);
                     ++o.tracked;
                   }).tracks_reanchored;
    return o;
  };
  const Outcome on = outcome(true);
  const Outcome off = outcome(false);
  std::printf("B tracked from 1.12 s: re-anchoring %d of %d instants (%llu re-anchored), off %d of %d\n",
              on.tracked, on.instants, static_cast<unsigned long long>(on.reanchored), off.tracked,
              off.instants);
  ASSERT_EQ(on.before.size(), 1u);
  ASSERT_EQ(off.before.size(), 1u);
  EXPECT_GE(on.reanchored, 1u);
  EXPECT_EQ(off.reanchored, 0u);
  EXPECT_EQ(on.after, on.before) << "B's track keeps its id";
  EXPECT_GE(on.tracked, on.instants * 95 / 100);
  EXPECT_LE(off.tracked, off.instants * 6 / 10) << "the scene no longer exercises the option";
}

// dispute_odd_views (issue 35 item 3, stop 95), after ring4/walk/c0/s1's sacrum: S moves on marker 0's
// circle, seen by cameras 0 and 3. P rides 5 cm behind S along camera 1's line of sight and drifts
// sideways from 2 mm to 5 cm, so that camera 1, which never sees S, sees P 1-15 px from where S
// would be. Camera 0 sees P all along (one view: no track), camera 1 from 0.5 s; markers 1 and 2 are
// seen by every camera. S's track takes
// P's blob in camera 1 and holds it, so P cannot be initiated: without the dispute P is untracked
// until S's track lets the blob go, and S's track sits between the two markers meanwhile (S and P
// tracked at 56 and 57 % of the instants from 0.7 s, against 100 % with it) and S comes back under
// a new id.
TEST(Tracker, AViewThatSeesANeighbourInsteadIsGivenUpToIt) {
  const Eigen::Vector3d eye1(3.0 * std::cos(0.3 + M_PI / 2), 3.0 * std::sin(0.3 + M_PI / 2), 2.0);
  const auto s_position = [](double t) { return marker_position(0, t); };
  const auto p_position = [&](double t) -> Eigen::Vector3d {
    const Eigen::Vector3d s = marker_position(0, t);
    const Eigen::Vector3d ray = (s - eye1).normalized();
    const Eigen::Vector3d side = ray.cross(Eigen::Vector3d::UnitZ()).normalized();
    return s + 0.05 * ray + (0.002 + 0.05 * std::max(0.0, t - 0.5)) * side;
  };
  const auto run = make_frames(
      1.5,
      [&](double t, int camera) {
        // Markers 1 and 2 in every view keep each camera's typical innovation that of a marker seen right.
        std::vector<Eigen::Vector3d> seen{marker_position(1, t), marker_position(2, t)};
        if (camera == 0 || camera == 3) seen.push_back(s_position(t));
        if (camera == 0 || (camera == 1 && t >= 0.5)) seen.push_back(p_position(t));
        return seen;
      },
      17);
  struct Outcome {
    std::uint64_t disputed = 0;
    std::set<std::int64_t> s_ids;                    // ids within 5 mm of S from 0.3 s
    int instants = 0, s_tracked = 0, p_tracked = 0;  // from 0.7 s
  };
  const auto outcome = [&](bool dispute) {
    TrackerOptions options;
    options.dispute_odd_views = dispute;
    Outcome o;
    double last = -1;
    o.disputed = replay(run, options, [&](double t, const TrackRecord& track) {
                   const bool on_s = (track.p - s_position(t)).norm() < 0.005;
                   if (t >= 0.3 && on_s) o.s_ids.insert(track.id);
                   if (t < 0.7) return;
                   if (t != last) ++o.instants;
                   last = t;
                   o.s_tracked += on_s;
                   o.p_tracked += (track.p - p_position(t)).norm() < 0.005;
                 }).views_disputed;
    return o;
  };
  const Outcome on = outcome(true);
  const Outcome off = outcome(false);
  std::printf(
      "from 0.7 s (%d instants): disputes on: S %d, P %d (%llu disputed, S's ids %zu); off: S %d, P %d "
      "(S's ids %zu)\n",
      on.instants, on.s_tracked, on.p_tracked, static_cast<unsigned long long>(on.disputed), on.s_ids.size(),
      off.s_tracked, off.p_tracked, off.s_ids.size());
  EXPECT_GE(on.disputed, 1u);
  EXPECT_EQ(off.disputed, 0u);
  EXPECT_EQ(on.s_ids.size(), 1u) << "S keeps its id";
  EXPECT_GE(on.s_tracked, on.instants * 95 / 100);
  EXPECT_GE(on.p_tracked, on.instants * 95 / 100);
  EXPECT_GE(off.s_ids.size(), 2u) << "without the dispute S comes back under a new id";
  EXPECT_LE(off.s_tracked, off.instants * 7 / 10) << "the scene no longer exercises the option";
  EXPECT_LE(off.p_tracked, off.instants * 7 / 10) << "the scene no longer exercises the option";
}

// A marker that stops while one camera alone sees it (a foot landing): camera 0's updates do not
// observe its motion along camera 0's ray, and constant velocity carries the track's depth on at the
// speed it had (one_view_velocity_time_constant_ns: docs/estimator.md, "One-view velocity"). B moves
// along that ray towards the camera at 1.2 m/s, seen by every camera, and stops at 1.0 s, from when
// only camera 0 sees it. With the velocity decaying the track stays nearer; while two cameras saw
// B, nothing changed (the records before 1.0 s are identical).
TEST(Tracker, AOneViewTrackThatStopsIsNotCarriedOnAlongTheRay) {
  const Eigen::Vector3d eye(3.0 * std::cos(0.3), 3.0 * std::sin(0.3), 2.0);  // camera 0's centre
  const Eigen::Vector3d ray = (Eigen::Vector3d(0.0, 0.0, 1.0) - eye).normalized();
  const auto b_position = [&](double t) -> Eigen::Vector3d {
    return eye + (2.6 + 1.2 * (1.0 - std::min(t, 1.0))) * ray;
  };
  const auto run = make_frames(
      1.2,
      [&](double t, int camera) {
        std::vector<Eigen::Vector3d> seen{marker_position(2, t)};  // another marker, far off, all along
        if (t < 1.0 || camera == 0) seen.push_back(b_position(t));
        return seen;
      },
      29);
  struct Outcome {
    std::vector<Eigen::Vector3d> before;  // every record before 1.0 s, in order
    std::set<std::int64_t> ids;           // ids on B in its last 0.2 s of two views
    double error_m = 0.0;                 // B's track from 1.08 to 1.12 s: its largest distance from B
  };
  const auto outcome = [&](TimeNs tau_ns) {
    TrackerOptions options;
    options.one_view_velocity_time_constant_ns = tau_ns;
    options.publish_max_sigma_m = 1.0;  // every record, however uncertain: the track is followed, not judged
    Outcome o;
    replay(run, options, [&](double t, const TrackRecord& track) {
      if (t < 1.0) {
        o.before.push_back(track.p);
        if (t > 0.8 && (track.p - b_position(t)).norm() < 0.005) o.ids.insert(track.id);
      } else if (t >= 1.08 && t <= 1.12 && o.ids.count(track.id) != 0) {
        o.error_m = std::max(o.error_m, (track.p - b_position(t)).norm());
      }
    });
    return o;
  };
  const Outcome damped = outcome(120'000'000);  // the grid's figure (off by default)
  const Outcome constant = outcome(0);
  std::printf(
      "B's track 80-120 ms after it stopped, seen by one camera: %.1f mm (velocity decaying), %.1f mm "
      "(constant velocity)\n",
      1e3 * damped.error_m, 1e3 * constant.error_m);
  ASSERT_EQ(damped.ids.size(), 1u);
  ASSERT_EQ(constant.ids.size(), 1u);
  EXPECT_EQ(damped.before, constant.before) << "two views: nothing changes";
  EXPECT_GT(constant.error_m, 0.05) << "the scene no longer exercises the option";
  EXPECT_LT(damped.error_m, 0.8 * constant.error_m);
}

// A pause of the input is no frame of any camera for 25 ms and 8 usual intervals: four cameras
// at 100 Hz missing 60 ms are one; one camera at 33 Hz is not paused at every frame. The three
// markers (0.3-0.6 m apart) come back from the pause under their ids.
TEST(Tracker, APauseOfEveryCameraIsOneAndTheMarkersKeepTheirIds) {
  auto always = [](int, double) { return true; };
  const auto run = make_run(2.0, always);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  std::map<int, std::set<std::int64_t>> ids;
  for (const auto& frame : run.frames) {
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    if (t >= 1.0 && t < 1.06) continue;
    tracker.process(frame);
    for (const auto& track : tracker.current_tracks()) {
      for (int m = 0; m < 3; ++m)
        if (t > 0.3 && (track.p - marker_position(m, t)).norm() < 0.005) ids[m].insert(track.id);
    }
  }
  EXPECT_EQ(tracker.stats().input_pauses, 1u);
  std::printf("after a pause of 60 ms: %llu track(s) reacquired\n",
              static_cast<unsigned long long>(tracker.stats().tracks_reacquired));
  for (int m = 0; m < 3; ++m) EXPECT_EQ(ids[m].size(), 1u) << "marker " << m << " changed identity";

  Tracker slow;
  slow.set_calibration(SystemCalibration{run.cameras});
  for (const auto& frame : run.frames)
    if (frame.camera_id == run.cameras[0].id && frame.frame % 3 == 0) slow.process(frame);
  EXPECT_EQ(slow.stats().input_pauses, 0u) << "one camera at 33 Hz";
}

// Issue 32: when every camera stops, no frame moves the tracker's time and the last tracks stayed
// confirmed for as long as the estimator ran. expire() deletes them at a later time; a time
// within delete_after of the last update keeps them, and a late frame still replays.
TEST(Tracker, ExpireDeletesTracksThatNoFrameKeptAlive) {
  auto always = [](int, double) { return true; };
  const auto run = make_run(1.0, always, 3);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  for (std::size_t i = 0; i + 1 < run.frames.size(); ++i) tracker.process(run.frames[i]);
  ASSERT_EQ(tracker.current_tracks().size(), 3u);
  const TimeNs last = tracker.last_stamp_ns();
  const TimeNs limit = TrackerOptions{}.delete_after_ns;
  EXPECT_EQ(tracker.expire(last + limit / 2), 0u);
  EXPECT_EQ(tracker.expire(last - limit), 0u);  // never before the newest frame
  EXPECT_EQ(tracker.track_counts(last)[1], 3u);
  EXPECT_EQ(tracker.expire(last + limit + 1'000'000), 3u);
  EXPECT_EQ(tracker.live_track_count(), 0u);
  EXPECT_TRUE(tracker.current_tracks().empty());
  EXPECT_EQ(tracker.track_counts(last), (std::array<std::size_t, 3>{0, 0, 0}));
  EXPECT_EQ(tracker.last_stamp_ns(), last);  // the tracker's time is still the newest frame's
  // The camera that was last to send replays its frame into the kept history.
  EXPECT_EQ(tracker.process(run.frames.back()),
            run.frames.back().stamp_ns > last ? FrameOutcome::kProcessed : FrameOutcome::kLateReplayed);
}

// Issue 16, edges of the volume: a marker that only one camera sees has no depth. Its track is
// kept (same id when a second camera sees it again) but not published once its position is
// uncertain, so no record drifts along the ray away from the marker.
TEST(Tracker, WithholdsAMarkerOnlyOneCameraSeesAndKeepsItsId) {
  auto visible = [](int m, double t, int camera) { return m != 1 || camera == 0 || t < 1.0 || t > 1.3; };
  const auto run = make_run(2.0, visible, 3);
  for (const double limit : {0.02, 0.0}) {
    TrackerOptions options;
    options.publish_max_sigma_m = limit;
    Tracker tracker(options);
    tracker.set_calibration(SystemCalibration{run.cameras});
    std::int64_t id_before = 0, id_after = 0;
    int published_alone = 0, far_records = 0;
    for (const auto& frame : run.frames) {
      tracker.process(frame);
      const double t = ns_to_seconds(scene_time(frame.stamp_ns));
      for (const auto& track : tracker.current_tracks()) {
        double nearest = 1e9;
        for (int m = 0; m < 3; ++m) nearest = std::min(nearest, (track.p - marker_position(m, t)).norm());
        const double error = (track.p - marker_position(1, t)).norm();
        if (t > 0.5 && nearest > 0.02) ++far_records;
        if (t > 0.9 && t < 1.0 && error < 0.005) id_before = track.id;
        if (t > 1.5 && error < 0.005) id_after = track.id;
        if (t > 1.1 && t < 1.3 && track.id == id_before) ++published_alone;
      }
    }
    SCOPED_TRACE("publish_max_sigma_m " + std::to_string(limit));
    EXPECT_NE(id_before, 0);
    EXPECT_EQ(id_before, id_after) << "marker 1 was given a new identity after 300 ms seen by one camera";
    if (limit > 0) {
      EXPECT_EQ(published_alone, 0) << "a track without depth was published";
      EXPECT_EQ(far_records, 0) << "records more than 2 cm from every marker";
    } else {
      EXPECT_GT(published_alone, 0) << "with the limit off the track is published throughout";
    }
  }
}

// Issue 32 item 9: on a loaded machine one camera's frames were processed alone for a few tens
// of milliseconds while the others' were late. Every track's depth uncertainty grew past
// publish_max_sigma_m (then 20 mm: about 27 ms alone here) for a frame, and TrackFrames blinked to
// zero tracks. A published track now stays published up to 2.5 times the limit (12 mm since stop
// 88: 30 mm; with twice it, 24 mm, this test fails).
TEST(Tracker, PublishedTracksDoNotBlinkWhileOneCameraAloneUpdatesThemFor30Ms) {
  auto visible = [](int, double t, int camera) { return camera == 0 || t < 1.0 || t >= 1.03; };
  const auto run = make_run(2.0, visible);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  std::size_t fewest = 3;
  int frames_checked = 0;
  for (const auto& frame : run.frames) {
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    if (t < 0.5) continue;
    fewest = std::min(fewest, tracker.current_tracks().size());
    ++frames_checked;
  }
  EXPECT_GT(frames_checked, 400);
  EXPECT_EQ(fewest, 3u) << "a TrackFrame would have blinked to " << fewest << " tracks";
  // Alone for a whole second, a track has no depth: it is withheld again (the limit still holds).
  auto alone = [](int, double t, int camera) { return camera == 0 || t < 1.0; };
  const auto long_run = make_run(2.0, alone);
  Tracker withheld;
  withheld.set_calibration(SystemCalibration{long_run.cameras});
  for (const auto& frame : long_run.frames) withheld.process(frame);
  EXPECT_TRUE(withheld.current_tracks().empty()) << "tracks without depth published after 1 s";
}

// Issue 19, validation: a marker that the body hides from two of four cameras for the whole run
// (inside their images, never in their frames) is seen by two. The misses of the cameras that
// cannot see it must not delete its tentative track faster than the two that see it confirm it;
// and no ghost may be published for it.
TEST(Tracker, ConfirmsAMarkerTwoCamerasSeeWhileTheOthersAreBlocked) {
  auto visible = [](int m, double, int camera) { return m != 1 || camera <= 1; };
  const auto run = make_run(2.0, visible, 4);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  std::set<std::int64_t> ids;
  int instants = 0, tracked = 0, far_records = 0;
  for (const auto& frame : run.frames) {
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    if (t < 0.3) continue;
    ++instants;
    for (const auto& track : tracker.current_tracks()) {
      double nearest = 1e9;
      for (int m = 0; m < 3; ++m) nearest = std::min(nearest, (track.p - marker_position(m, t)).norm());
      if (nearest > 0.01) ++far_records;
      if ((track.p - marker_position(1, t)).norm() < 0.005) {
        ++tracked;
        ids.insert(track.id);
      }
    }
  }
  EXPECT_GE(tracked, instants * 99 / 100) << "the two-camera marker was not tracked";
  EXPECT_EQ(ids.size(), 1u);
  EXPECT_EQ(far_records, 0) << "records more than 1 cm from every marker";
  EXPECT_EQ(tracker.stats().tracks_confirmed, 3u);
}

TEST(Tracker, CountsFramesFromUncalibratedCamerasAndLateFrames) {
  auto always = [](int, double) { return true; };
  const auto run = make_run(1.0, always);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  FeatureFrame stranger = run.frames[0];
  stranger.camera_id = "not-calibrated";
  EXPECT_EQ(tracker.process(stranger), FrameOutcome::kUnknownCamera);
  tracker.process(run.frames[10]);
  // Older than the newest frame but within the rewind horizon: replayed, not dropped.
  EXPECT_EQ(tracker.process(run.frames[5]), FrameOutcome::kLateReplayed);
  EXPECT_EQ(tracker.stats().frames_unknown_camera, 1u);
  EXPECT_EQ(tracker.stats().frames_late, 1u);
  EXPECT_EQ(tracker.stats().replays, 1u);
  // Once the run has gone on for longer than the rewind horizon, an early frame is dropped, counted.
  for (std::size_t i = 11; i < run.frames.size(); ++i) tracker.process(run.frames[i]);
  const FeatureFrame ancient = run.frames[5];
  EXPECT_EQ(tracker.process(ancient), FrameOutcome::kTooLate);
  EXPECT_EQ(tracker.stats().frames_too_late, 1u);
  const auto& counters = tracker.camera_counters();
  EXPECT_EQ(counters.at("not-calibrated").frames, 1u);
  EXPECT_EQ(counters.at("not-calibrated").used, 0u);
}

TEST(Tracker, NoGhostTrackIsPublished) {
  // Two cameras' rays can meet near a wrong blob and triangulate a ghost; confirmation by a third
  // camera must keep every published track on a real marker.
  auto always = [](int, double) { return true; };
  auto run = make_run(2.0, always, 3);
  Tracker tracker;
  tracker.set_calibration(SystemCalibration{run.cameras});
  std::size_t ghosts = 0;
  for (const auto& frame : run.frames) {
    tracker.process(frame);
    const double t = ns_to_seconds(scene_time(frame.stamp_ns));
    for (const auto& track : tracker.current_tracks()) {
      double nearest = 1e9;
      for (int m = 0; m < 3; ++m) nearest = std::min(nearest, (track.p - marker_position(m, t)).norm());
      if (nearest > 0.01) ++ghosts;
    }
  }
  EXPECT_EQ(ghosts, 0u);
}

TEST(FrameInbox, ReleasesFramesInStampOrderAfterTheWindow) {
  FrameInbox inbox(3, 10);
  for (TimeNs stamp : {105, 100, 120}) {
    FeatureFrame frame;
    frame.stamp_ns = stamp;
    EXPECT_TRUE(inbox.push(frame));
  }
  auto due = inbox.pop_due(116);  // window 10: stamps <= 106 leave
  ASSERT_EQ(due.size(), 2u);
  EXPECT_EQ(due[0].stamp_ns, 100);
  EXPECT_EQ(due[1].stamp_ns, 105);
  FeatureFrame a, b, c;
  a.stamp_ns = 130;
  b.stamp_ns = 140;
  c.stamp_ns = 150;
  EXPECT_TRUE(inbox.push(a));
  EXPECT_TRUE(inbox.push(b));
  EXPECT_FALSE(inbox.push(c));  // full: the oldest (120) is dropped
  EXPECT_EQ(inbox.drops(), 1u);
  const auto rest = inbox.drain();
  ASSERT_EQ(rest.size(), 3u);
  EXPECT_EQ(rest[0].stamp_ns, 130);
}

}  // namespace
}  // namespace panoptes::estimator
