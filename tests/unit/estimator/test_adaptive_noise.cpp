// SPDX-License-Identifier: Apache-2.0
// Adaptive process noise (issue 35 item 2; docs/estimator.md, "Adaptive process noise"): a marker
// on a swung club (25 m/s through the bottom) keeps one identity with the default settings, also
// when it leaves every view at the top of the swing (rejoin_fast_tracks), and a slow marker is
// tracked as well as with one fixed σ². Also a one-view marker's depth from its neighbours.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "panoptes/estimator/tracker.h"
#include "test_cameras.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000LL;

// A pendulum swing about a pivot 1.7 m up, θ(t) = 2.5 sin(10 t): the head, 1.0 m out, at
// 25 m/s through the bottom (centripetal 625 m/s²), or a slow circle at 0.5 m/s.
Eigen::Vector3d club_head(double t) {
  const double amplitude = 2.5, omega = 10.0;  // peak angular speed 25 rad/s at r = 1 m
  const double theta = amplitude * std::sin(omega * t);
  return {std::sin(theta), 0.1, 1.7 - std::cos(theta)};
}

// A ball thrown to and fro along x at 25 m/s between two hands 1.6 m apart, each catch and throw
// back a half-sine reversal over 0.1 s (peak 785 m/s², as the accuracy grid's ball).
Eigen::Vector3d thrown_ball(double t) {
  constexpr double kSpeed = 25.0, kFlight = 1.6 / kSpeed, kCatch = 0.1, kPi = 3.14159265358979323846;
  const double period = 2.0 * (kFlight + kCatch);
  double u = std::fmod(t, period);
  double sign = 1.0, x0 = -0.8;
  if (u >= kFlight + kCatch) {  // the way back: the same, mirrored
    u -= kFlight + kCatch;
    sign = -1.0;
    x0 = 0.8;
  }
  // Flight at constant speed, then a reversal whose velocity goes as cos(π s / kCatch): it leaves
  // at the speed it arrived with, the other way, having gone 2 kSpeed kCatch / π beyond the hand.
  const double x =
      u < kFlight
          ? x0 + sign * kSpeed * u
          : x0 + sign * (kSpeed * kFlight + kSpeed * kCatch / kPi * std::sin(kPi * (u - kFlight) / kCatch));
  return {x, 0.2, 1.3};
}

Eigen::Vector3d slow_marker(double t) {
  return {0.5 * std::cos(t), 0.5 * std::sin(t), 1.0};
}

struct Result {
  std::set<std::int64_t> ids;
  int instants = 0;  // while the marker is visible
  int tracked = 0;
  double sum2 = 0;
  double max_error = 0;  // of the tracked instants
  // RMSE of the tracked instants, m (NaN with none: every comparison with it fails).
  double rmse_m() const { return tracked == 0 ? std::nan("") : std::sqrt(sum2 / tracked); }
};

using Path = std::function<Eigen::Vector3d(double)>;
using Region = std::function<bool(const Eigen::Vector3d&)>;
// Whether camera c shows marker m at t s (besides `hidden` and `seeing` below).
using Shown = std::function<bool(std::size_t c, std::size_t m, double t)>;

// Each marker's result; `hidden`: where no camera sees a marker (none: everywhere visible);
// `seeing`: how many of the six cameras see the markers at all (the others see nothing).
std::vector<Result> track(const std::vector<Path>& paths, const TrackerOptions& options, double duration_s,
                          const Region& hidden = nullptr, std::size_t seeing = 6,
                          const Shown& shown = nullptr, TrackerStats* stats = nullptr) {
  const auto cameras = make_ring_calibration(6, 4.0, 2.5, true);
  std::vector<CameraModel> models;
  for (const auto& c : cameras) models.push_back(c.model());
  Tracker tracker(options);
  tracker.set_calibration(SystemCalibration{cameras});
  std::mt19937_64 rng(35);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<Result> results(paths.size());
  // Six cameras at 110 Hz, phases spread over the frame interval.
  const TimeNs period = 9'090'909;
  for (int k = 0; k < static_cast<int>(duration_s * 110); ++k) {
    for (std::size_t c = 0; c < models.size(); ++c) {
      const TimeNs t = k * period + static_cast<TimeNs>(c) * period / 6;
      FeatureFrame frame;
      frame.camera_id = cameras[c].id;
      frame.frame = k;
      frame.stamp_ns = kEpoch + t;
      std::vector<Eigen::Vector3d> truth;
      std::vector<char> seen;
      for (const Path& path : paths) {
        truth.push_back(path(ns_to_seconds(t)));
        seen.push_back(!hidden || !hidden(truth.back()));
        const auto pixel = models[c].project(truth.back());
        if (c < seeing && seen.back() && pixel && models[c].in_image(*pixel) &&
            (!shown || shown(c, truth.size() - 1, ns_to_seconds(t)))) {
          Blob blob;
          blob.x = pixel->x() + noise(rng);
          blob.y = pixel->y() + noise(rng);
          blob.area = 12;
          frame.blobs.push_back(blob);
        }
      }
      EXPECT_EQ(tracker.process(frame), FrameOutcome::kProcessed);
      if (ns_to_seconds(t) < 0.3) continue;
      const auto records = tracker.current_tracks();
      for (std::size_t m = 0; m < paths.size(); ++m) {
        if (!seen[m]) continue;
        Result& result = results[m];
        ++result.instants;
        for (const auto& record : records) {
          const double error = (record.p - truth[m]).norm();
          if (error < 0.02) {
            result.ids.insert(record.id);
            ++result.tracked;
            result.sum2 += error * error;
            result.max_error = std::max(result.max_error, error);
            break;
          }
        }
      }
    }
  }
  if (stats != nullptr) *stats = tracker.stats();
  return results;
}

Result track(const Path& path, const TrackerOptions& options, double duration_s,
             const Region& hidden = nullptr, std::size_t seeing = 6) {
  return track(std::vector<Path>{path}, options, duration_s, hidden, seeing).front();
}

TEST(AdaptiveNoise, SwungClubHeadKeepsOneIdentityWithTheDefaults) {
  const Result r = track(club_head, TrackerOptions{}, 3.0);
  std::printf("adaptive: %zu ids, tracked %d of %d instants\n", r.ids.size(), r.tracked, r.instants);
  EXPECT_EQ(r.ids.size(), 1u) << "the club head changed identity";
  EXPECT_GE(r.tracked, 0.99 * r.instants) << r.tracked << " of " << r.instants;
}

TEST(AdaptiveNoise, FixedDefaultNoiseLosesTheClubHead) {
  // The same scene with adaptation off: the test above is not passing by accident of the scene.
  // The constant-velocity model with fixed noise, as before issue 35: with the acceleration input
  // (fast_acceleration_time_constant_ns) even fixed noise keeps the head (1 id, every instant).
  TrackerOptions fixed;
  fixed.process_noise_max_scale = 1.0;
  fixed.fast_acceleration_time_constant_ns = 0;
  const Result r = track(club_head, fixed, 3.0);
  std::printf("fixed: %zu ids, tracked %d of %d instants\n", r.ids.size(), r.tracked, r.instants);
  EXPECT_TRUE(r.ids.size() > 1u || r.tracked < 0.99 * r.instants)
      << r.ids.size() << " ids, " << r.tracked << " of " << r.instants;
}

// Above 2.35 m no camera sees the head: ~84 ms at the top of every swing (it leaves at ~10 m/s and
// comes back where it left). The track coasts on a straight line meanwhile, far from the return.
bool above_the_views(const Eigen::Vector3d& p) {
  return p.z() > 2.35;
}

TEST(AdaptiveNoise, ClubHeadThatLeavesEveryViewRejoinsItsIdentity) {
  const Result r = track(club_head, TrackerOptions{}, 3.0, above_the_views);
  std::printf("rejoin: %zu ids, tracked %d of %d visible instants\n", r.ids.size(), r.tracked, r.instants);
  EXPECT_EQ(r.ids.size(), 1u) << "the club head came back under another identity";
  EXPECT_GE(r.tracked, 0.95 * r.instants) << r.tracked << " of " << r.instants;
  // Without the rejoin and the held σ² every top of the swing starts a new identity (the test is
  // not vacuous). The held σ² alone carries the head across the top here (its coasting track's gate
  // takes the return, 84 ms later); the rejoin is for longer absences (the grid's corridors).
  TrackerOptions off;
  off.rejoin_fast_tracks = false;
  off.fast_process_noise_scale = 0;
  const Result without = track(club_head, off, 3.0, above_the_views);
  TrackerOptions held_only;
  held_only.rejoin_fast_tracks = false;
  const Result held = track(club_head, held_only, 3.0, above_the_views);
  std::printf("neither: %zu ids; held sigma^2 without the rejoin: %zu ids\n", without.ids.size(),
              held.ids.size());
  EXPECT_GT(without.ids.size(), 3u);
  EXPECT_EQ(held.ids.size(), 1u);
}

// Head (1.0 m out) and a shaft marker (0.6 m) of one club, both hidden above 2.0 m: the head leaves
// the views while the shaft is still followed 0.4 m away and comes back at ~17 m/s with no earlier
// blob to give its new track a velocity. Each must come back under its own identity. A followed
// track near the return blocks a rejoin only when it is nearer than the lost one (a shaft track
// astray); blocking at any distance gave the head 9 identities here. The stop-57 tracker passes
// too (head 897 of 961 instants); the grid's club cells are where the rejoin rules were measured.
TEST(AdaptiveNoise, HeadAndShaftThatLeaveTheViewsTogetherKeepTheirIdentities) {
  const auto marker_at = [](double radius) {
    return [radius](double t) {
      const Eigen::Vector3d head = club_head(t);
      const Eigen::Vector3d pivot(0.0, 0.1, 1.7);
      return Eigen::Vector3d(pivot + radius * (head - pivot));
    };
  };
  const Region above = [](const Eigen::Vector3d& p) { return p.z() > 2.0; };
  const auto results = track({marker_at(1.0), marker_at(0.6)}, TrackerOptions{}, 3.0, above);
  const char* names[] = {"head", "shaft"};
  for (std::size_t m = 0; m < results.size(); ++m) {
    const Result& r = results[m];
    std::printf("%s: %zu ids, tracked %d of %d visible instants\n", names[m], r.ids.size(), r.tracked,
                r.instants);
    EXPECT_EQ(r.ids.size(), 1u) << names[m] << " came back under another identity";
    EXPECT_GE(r.tracked, 0.9 * r.instants) << names[m] << ": " << r.tracked << " of " << r.instants;
  }
  EXPECT_TRUE(results[0].ids.empty() || results[1].ids.empty() ||
              *results[0].ids.begin() != *results[1].ids.begin())
      << "head and shaft share an identity";
}

// The head alone hidden (above 2.2 m: 116 ms at each top of the swing), its shaft marker 0.4 m
// nearer the pivot followed throughout; at the tops on the positive side a clutter point appears
// for 60 ms, seen by every camera, 0.5 m from where the head left the views (within its reach) and
// 0.9 m from the shaft. The head's identity must not go to the clutter: the head keeps its rigid
// partner's distance (0.4 m), the clutter does not (rejoin_rigid_margin_m). Without the test the
// clutter is published under the head's identity for its 60 ms (the head takes it back after).
TEST(AdaptiveNoise, AClutterPointWithinTheHeadsReachDoesNotTakeItsIdentity) {
  const Eigen::Vector3d pivot(0.0, 0.1, 1.7);
  const auto marker_at = [pivot](double radius) {
    return [radius, pivot](double t) { return Eigen::Vector3d(pivot + radius * (club_head(t) - pivot)); };
  };
  constexpr double kPeriod = 2.0 * 3.14159265358979323846 / 10.0;
  const Path clutter = [kPeriod](double t) {
    const double since_top = std::fmod(t, kPeriod) - kPeriod / 4;  // the positive side's top
    return std::abs(since_top) < 0.03 ? Eigen::Vector3d(1.166, 0.5, 2.1) : Eigen::Vector3d(0, 0, 3.0);
  };
  const Region above = [](const Eigen::Vector3d& p) { return p.z() > 2.2; };
  const auto run = [&](const TrackerOptions& options, const char* label) {
    auto results = track({marker_at(1.0), marker_at(0.6), clutter}, options, 3.0, above);
    std::printf("%s: head %zu ids, tracked %d of %d visible instants; shaft %zu ids\n", label,
                results[0].ids.size(), results[0].tracked, results[0].instants, results[1].ids.size());
    return results;
  };
  const auto shared = [](const Result& a, const Result& b) {
    return std::count_if(a.ids.begin(), a.ids.end(), [&](std::int64_t id) { return b.ids.count(id) > 0; });
  };
  const auto results = run(TrackerOptions{}, "rigid partner");
  EXPECT_EQ(results[0].ids.size(), 1u) << "the head came back under another identity";
  EXPECT_EQ(results[1].ids.size(), 1u) << "the shaft changed identity";
  EXPECT_GE(results[0].tracked, 0.9 * results[0].instants);
  EXPECT_EQ(shared(results[2], results[0]), 0) << "the clutter took the head's identity";
  // Without the test the clutter takes the head's identity (the test is not vacuous).
  TrackerOptions off;
  off.rejoin_rigid_margin_m = 0;
  const auto without = run(off, "no rigid test");
  std::printf("the clutter held %zu ids, %ld of them the head's; without the rigid test %zu, %ld\n",
              results[2].ids.size(), static_cast<long>(shared(results[2], results[0])), without[2].ids.size(),
              static_cast<long>(shared(without[2], without[0])));
  EXPECT_GT(shared(without[2], without[0]), 0);
}

// Head and shaft marker of one club, 0.4 m apart. At the tops of the swing (above 2.2 m, ~116 ms
// each) camera 0 alone shows the head, and camera 2 a false blob 0.7 m further along camera 0's ray:
// the head's one-view track, its depth along that ray uncertain, gates it (as the grid's clutter
// did in ceiling6/club/c1/s1, where the head's track jumped a metre and the head came back under a
// new id). Taking it would put the head more than 0.1 m off its distance from the shaft's track,
// which two cameras follow (partner_update_margin_m). Camera 0 alone does not keep the head at every top
// here (it loses it either way); the test is that the false blobs cost it fewer identities and fewer
// instants with the refusal than without, and that the shaft, whose partner is the head, keeps its
// own blobs.
TEST(AdaptiveNoise, AHeadSeenByOneCameraTakesNoBlobOffItsShaft) {
  const Eigen::Vector3d pivot(0.0, 0.1, 1.7);
  const auto marker_at = [pivot](double radius) {
    return [radius, pivot](double t) { return Eigen::Vector3d(pivot + radius * (club_head(t) - pivot)); };
  };
  const Eigen::Vector3d eye = make_ring_calibration(6, 4.0, 2.5, true)[0].model().center_world();
  const auto at_top = [](double t) { return club_head(t).z() > 2.2; };
  const Path stray = [&](double t) {
    const Eigen::Vector3d head = club_head(t);
    return Eigen::Vector3d(head + 0.7 * (head - eye).normalized());
  };
  const Shown shown = [&](std::size_t c, std::size_t m, double t) {
    if (m == 2) return c == 2 && at_top(t);  // the false blob
    return m == 1 || !at_top(t) || c == 0;
  };
  const auto run = [&](const TrackerOptions& options, const char* label) {
    TrackerStats stats;
    auto results = track({marker_at(1.0), marker_at(0.6), stray}, options, 3.0, nullptr, 6, shown, &stats);
    std::printf(
        "%s: head %zu ids, tracked %d of %d instants, max error %.3f m; shaft %zu ids; "
        "blobs refused %llu\n",
        label, results[0].ids.size(), results[0].tracked, results[0].instants, results[0].max_error,
        results[1].ids.size(), static_cast<unsigned long long>(stats.fast_off_partner));
    return std::make_pair(results, stats);
  };
  const auto [with, stats] = run(TrackerOptions{}, "rigid partner at every update");
  TrackerOptions off;
  off.partner_update_margin_m = 0;
  const auto [without, stats_off] = run(off, "no such test");
  EXPECT_GT(stats.fast_off_partner, 0u);
  EXPECT_EQ(stats_off.fast_off_partner, 0u);
  EXPECT_LT(with[0].ids.size(), without[0].ids.size()) << "the false blobs cost the head as many identities";
  EXPECT_GT(with[0].tracked, without[0].tracked);
  EXPECT_EQ(with[1].ids.size(), 1u) << "the shaft changed identity";
  EXPECT_LE(with[0].max_error, 0.02);
}

// A fast track keeps the large σ² through the catch (fast_process_noise_scale, fast_hold_ns): the
// ball stays on its identity and within a few millimetres at the catches. With the adaptive
// factor alone (fast_process_noise_scale 0) the catch comes before the evidence for a larger σ².
// Depth from the neighbours (tracker.one_view_carried_sigma_m; docs/estimator.md, "Depth from the
// neighbours"): five markers of a rigid group 8-12 cm apart go round a circle at 0.5 m/s; for 0.8 s
// one of them is seen by camera 0 alone (the others miss it: a body in the way) while the group
// turns. Its one-view track's depth along camera 0's ray is what its prediction says, unless the
// neighbours, still seen by every camera, carry it. Every track is published here (publish limit
// 0), so that the depth shows in the records.
TEST(AdaptiveNoise, AOneViewMarkerKeepsItsDepthFromItsNeighbours) {
  const std::vector<Eigen::Vector3d> offsets{
      {0.0, 0.0, 0.0}, {0.10, 0.0, 0.02}, {0.0, 0.12, 0.0}, {-0.08, 0.05, 0.1}, {0.05, -0.1, 0.05}};
  std::vector<Path> paths;
  for (const Eigen::Vector3d& offset : offsets)
    paths.push_back([offset](double t) -> Eigen::Vector3d { return slow_marker(t) + offset; });
  const Shown shown = [](std::size_t c, std::size_t m, double t) {
    return m != 0 || c == 0 || t < 1.0 || t > 1.8;
  };
  const auto one_view_tracked = [&](double sigma_m, TrackerStats& stats, std::size_t& ids) {
    TrackerOptions options;
    options.publish_max_sigma_m = 0;
    options.one_view_carried_sigma_m = sigma_m;
    const auto results = track(paths, options, 2.4, nullptr, 6, shown, &stats);
    ids = results[0].ids.size();
    return results[0];
  };
  TrackerStats with_stats, without_stats;
  std::size_t with_ids = 0, without_ids = 0;
  const Result with = one_view_tracked(0.05, with_stats, with_ids);
  const Result without = one_view_tracked(0.0, without_stats, without_ids);
  std::printf(
      "one view for 0.8 s: within 2 cm at %d of %d instants with the neighbours' depth (%llu updates "
      "given it, %zu ids), %d without (%zu ids)\n",
      with.tracked, with.instants, static_cast<unsigned long long>(with_stats.one_view_depths_pinned),
      with_ids, without.tracked, without_ids);
  // Measured (stop 101): 1385 of 1385 instants within 2 cm and one id with it (87 of camera 0's 88
  // frames in the stretch give the depth); 974 and two ids without.
  EXPECT_GT(with_stats.one_view_depths_pinned, 80u);
  EXPECT_EQ(without_stats.one_view_depths_pinned, 0u);
  EXPECT_GE(with.tracked, with.instants * 98 / 100);
  EXPECT_EQ(with_ids, 1u);
  EXPECT_LT(without.tracked, without.instants * 85 / 100);  // the control: the scene needs the rule
}

TEST(AdaptiveNoise, ThrownBallKeepsItsTrackThroughEveryCatch) {
  const Result held = track(thrown_ball, TrackerOptions{}, 3.0);
  TrackerOptions adaptive_only;
  adaptive_only.fast_process_noise_scale = 0;
  const Result adaptive = track(thrown_ball, adaptive_only, 3.0);
  const double rmse = held.rmse_m(), rmse_adaptive = adaptive.rmse_m();
  std::printf(
      "thrown ball: held %zu ids, tracked %d of %d, RMSE %.3f mm; adaptive only %zu ids, tracked %d, RMSE "
      "%.3f mm\n",
      held.ids.size(), held.tracked, held.instants, rmse * 1e3, adaptive.ids.size(), adaptive.tracked,
      rmse_adaptive * 1e3);
  EXPECT_EQ(held.ids.size(), 1u);
  EXPECT_GE(held.tracked, 0.99 * held.instants) << held.tracked << " of " << held.instants;
  EXPECT_LT(rmse, rmse_adaptive);
}

// A fast track predicts with its acceleration (fast_acceleration_time_constant_ns: its velocity's
// change per update, low-passed, as a known input of the prediction): the ball's catches (785 m/s²
// for 0.1 s) are predicted, not only allowed for by the wide σ² of a fast track. Seen by all six
// cameras and by three of them (6 ms between their frames, where the constant-velocity track is
// unpublished between frames and lost at some catches). A slow marker never takes it.
TEST(AdaptiveNoise, AFastTrackPredictsWithItsAcceleration) {
  TrackerOptions constant_velocity;
  constant_velocity.fast_acceleration_time_constant_ns = 0;
  for (const std::size_t seeing : {6u, 3u}) {
    const Result input = track(thrown_ball, TrackerOptions{}, 3.0, nullptr, seeing);
    const Result cv = track(thrown_ball, constant_velocity, 3.0, nullptr, seeing);
    std::printf(
        "thrown ball, %zu cameras: acceleration input %zu ids, tracked %d of %d, RMSE %.3f mm, max %.3f mm; "
        "constant velocity %zu ids, tracked %d, RMSE %.3f mm, max %.3f mm\n",
        seeing, input.ids.size(), input.tracked, input.instants, input.rmse_m() * 1e3, input.max_error * 1e3,
        cv.ids.size(), cv.tracked, cv.rmse_m() * 1e3, cv.max_error * 1e3);
    EXPECT_LE(input.ids.size(), cv.ids.size());
    EXPECT_GE(input.tracked, cv.tracked);
    EXPECT_LT(input.rmse_m(), 0.8 * cv.rmse_m());
  }
  const Result slow = track(slow_marker, TrackerOptions{}, 3.0);
  const Result slow_cv = track(slow_marker, constant_velocity, 3.0);
  EXPECT_EQ(slow.tracked, slow_cv.tracked);
  EXPECT_EQ(slow.sum2, slow_cv.sum2);
}

// A fast track with no other confirmed track within fast_isolation_m (1 m) takes its own factor,
// fast_isolated_process_noise_scale, instead of the club's fast_process_noise_scale (100). Stop 63
// made it larger (300: the lone ball followed its catches closer with a constant-velocity
// prediction); since stop 77, with the acceleration input, the ball is best with a smaller one (20:
// 0.98 against 1.05 mm here; on the accuracy grid the ball's worst coverage 72.4 -> 87.7 %, see
// docs/estimator.md "Acceleration input"), while a club's markers, 0.4 m apart, keep 100 (with 20
// the corridors' 12 s club cells had 22 switches instead of 0). They never take the factor: their
// tracks are the same to the last bit with the rule off.
TEST(AdaptiveNoise, OnlyAnIsolatedFastTrackTakesItsOwnFactor) {
  TrackerOptions club_factor;
  club_factor.fast_isolated_process_noise_scale = 0;  // off: fast_process_noise_scale for every fast track
  const Result isolated = track(thrown_ball, TrackerOptions{}, 3.0);
  const Result neighbour_factor = track(thrown_ball, club_factor, 3.0);
  const double rmse = isolated.rmse_m(), rmse_club_factor = neighbour_factor.rmse_m();
  std::printf(
      "thrown ball: isolated factor tracked %d of %d, RMSE %.3f mm, max %.3f mm; x100 tracked %d, RMSE %.3f "
      "mm, max "
      "%.3f mm\n",
      isolated.tracked, isolated.instants, rmse * 1e3, isolated.max_error * 1e3, neighbour_factor.tracked,
      rmse_club_factor * 1e3, neighbour_factor.max_error * 1e3);
  EXPECT_EQ(isolated.ids.size(), 1u);
  EXPECT_GE(isolated.tracked, neighbour_factor.tracked);
  EXPECT_LT(rmse, rmse_club_factor);  // equal if the rule never applied

  const auto marker_at = [](double radius) {
    return [radius](double t) {
      const Eigen::Vector3d pivot(0.0, 0.1, 1.7);
      return Eigen::Vector3d(pivot + radius * (club_head(t) - pivot));
    };
  };
  const std::vector<Path> club = {marker_at(1.0), marker_at(0.6)};
  const auto with_rule = track(club, TrackerOptions{}, 3.0);
  const auto without_rule = track(club, club_factor, 3.0);
  for (std::size_t m = 0; m < club.size(); ++m) {
    EXPECT_EQ(with_rule[m].tracked, without_rule[m].tracked) << "marker " << m;
    EXPECT_EQ(with_rule[m].sum2, without_rule[m].sum2) << "marker " << m;
    EXPECT_EQ(with_rule[m].ids.size(), 1u) << "marker " << m;
  }
}

// A fast track is also published while its cameras confirm its predictions
// (fast_publish_innovation_px): seen by three of the six cameras (6 ms between their frames), the
// lone ball's σ (×300) passes the publication limit between their frames though they find it where
// the track predicted. Judged at every frame, as here, it is tracked at more of them (1226
// against 1118 of 1781 when written), on no more identities (3 either way: with three views some
// catches lose it) and as accurately (5.03 against 5.19 mm).
TEST(AdaptiveNoise, AFastTrackTheCamerasConfirmIsPublishedBetweenTheirFrames) {
  // The ball's own factor is 20 since stop 77 (its σ then stays under the limit between frames and
  // the rule does not apply); a club's markers keep 100. The wider factor here makes the case.
  TrackerOptions wide;
  wide.fast_isolated_process_noise_scale = 300;
  TrackerOptions sigma_only = wide;
  sigma_only.fast_publish_innovation_px = 0;
  const Result confirmed = track(thrown_ball, wide, 3.0, nullptr, 3);
  const Result by_sigma = track(thrown_ball, sigma_only, 3.0, nullptr, 3);
  std::printf(
      "thrown ball: %zu ids, tracked %d of %d, RMSE %.3f mm, max %.3f mm; sigma only: %zu ids, tracked %d, "
      "RMSE "
      "%.3f mm\n",
      confirmed.ids.size(), confirmed.tracked, confirmed.instants, confirmed.rmse_m() * 1e3,
      confirmed.max_error * 1e3, by_sigma.ids.size(), by_sigma.tracked, by_sigma.rmse_m() * 1e3);
  EXPECT_LE(confirmed.ids.size(), by_sigma.ids.size());
  EXPECT_GT(confirmed.tracked, by_sigma.tracked);
  EXPECT_LT(confirmed.rmse_m(), 1.1 * by_sigma.rmse_m());
}

TEST(AdaptiveNoise, SlowMarkerAsAccurateAsWithFixedNoise) {
  TrackerOptions fixed;
  fixed.process_noise_max_scale = 1.0;
  const Result adaptive = track(slow_marker, TrackerOptions{}, 3.0);
  const Result reference = track(slow_marker, fixed, 3.0);
  const double rmse = adaptive.rmse_m(), rmse_fixed = reference.rmse_m();
  std::printf("slow marker RMSE: adaptive %.4f mm, fixed %.4f mm\n", rmse * 1e3, rmse_fixed * 1e3);
  EXPECT_LE(rmse, 1.03 * rmse_fixed);
  EXPECT_EQ(adaptive.ids.size(), 1u);
}

}  // namespace
}  // namespace panoptes::estimator
