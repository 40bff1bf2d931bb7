// SPDX-License-Identifier: Apache-2.0
// The labeller (issue 33 item 2) on the real Gait2392 walk: the model from the static trial, the
// walk's markers as anonymous tracks (shuffled ids, 0.5 mm noise, 0.3 ghosts per frame, occlusion
// gaps after which a marker comes back under a new track id), scored against the held-back names.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "labelling_replay.h"
#include "labelling_test_support.h"
#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"

namespace panoptes::labelling {
namespace {

struct Score {
  double visible = 0, right = 0, wrong = 0, swaps = 0, ghosts = 0, ghosts_named = 0;
  double visible_after = 0, right_after = 0;  // from the first frame a track may be acquired on
  double wrong_after = 0, swaps_after = 0;    // (or from Blinks::scored_from)
  std::vector<int> returns;                   // frames until a reappearing marker has its name back
  std::map<std::string, int> unlabelled;      // marker-frames without a name, by marker
  int never_returned = 0;
  double microseconds_per_frame = 0;
  double worst_return_ms = 0;  // over every seed
};

std::string mirrored(const std::string& name) {
  if (name.rfind("R.", 0) == 0) return "L." + name.substr(2);
  if (name.rfind("L.", 0) == 0) return "R." + name.substr(2);
  return name;
}

// Scores one frame's labels; `waiting[track]` is the frame a reappearing marker's new track began.
void score_frame(const Labeller& labeller, const std::vector<TrackPoint>& points,
                 const std::map<std::uint64_t, std::string>& truth, std::map<std::uint64_t, int>& waiting,
                 int f, int after, Score& score) {
  std::map<std::string, int> names;  // a name is never on two tracks
  for (const auto& point : points) {
    const auto label = labeller.label_of(point.track);
    if (label) {
      EXPECT_EQ(++names[label->marker], 1) << label->marker << " on two tracks in frame " << f;
    }
    const auto name = truth.find(point.track);
    if (name == truth.end()) {
      score.ghosts += 1;
      score.ghosts_named += label ? 1 : 0;
      if (label) ++score.unlabelled["a ghost named " + label->marker];
      continue;
    }
    score.visible += 1;
    const bool right = label && label->marker == name->second;
    score.right += right ? 1 : 0;
    if (f >= after) {
      score.visible_after += 1;
      score.right_after += right ? 1 : 0;
      score.wrong_after += label && !right ? 1 : 0;
      score.swaps_after += label && !right && label->marker == mirrored(name->second) ? 1 : 0;
    }
    score.wrong += label && !right ? 1 : 0;
    if (!label) ++score.unlabelled[name->second];
    if (label && !right) ++score.unlabelled[name->second + " named " + label->marker];
    score.swaps += label && !right && label->marker == mirrored(name->second) ? 1 : 0;
    const auto wait = waiting.find(point.track);
    if (wait != waiting.end() && right) {
      score.returns.push_back(f - wait->second);
      if (f - wait->second > 4)
        std::printf("  %s came back after %d frames\n", name->second.c_str(), f - wait->second);
      waiting.erase(wait);
    }
  }
}

// Live, the estimator leaves tracks out of an instant now and then (coasting; not determined while
// one camera's frames were processed alone): at `all_share` of the instants every track is missing,
// at `some_share` each track is missing with probability 0.4; the same ids come back the next
// instant. `live`: the labeller is given the instant's time (keep_absent_s), as the estimator does.
// `hidden_at_start`: that marker has no track for the first `hidden_frames` frames; the `_after`
// figures count from frame `scored_from` (at least the first a track may be acquired on).
struct Blinks {
  double all_share = 0.0;
  double some_share = 0.0;
  bool live = false;
  std::string hidden_at_start;
  int hidden_frames = 0;
  int scored_from = 0;
};

Score replay_walk(const SubjectModel& model, const MarkerSamples& walk, std::uint64_t seed,
                  const LabellerOptions& options, const Blinks& blinks = {}) {
  Labeller labeller({model}, options);
  Replay replay{std::mt19937_64(seed)};
  Stream stream{
      std::vector<std::uint64_t>(walk.point_count(), 0), std::vector<int>(walk.point_count(), 0), {}};
  std::map<std::uint64_t, std::string> truth;
  std::map<std::uint64_t, int> waiting;
  std::vector<char> seen_before(walk.point_count(), 0);
  Score score;
  double seconds = 0.0;
  std::mt19937_64 blink_random(seed + 1000);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t m = 0; m < walk.point_count(); ++m) {
    if (walk.names[m] == blinks.hidden_at_start) stream.hidden_for[m] = blinks.hidden_frames + 1;
  }
  for (std::size_t f = 0; f < walk.frame_count(); ++f) {
    const auto before = stream.id;
    auto points = next_frame(walk, f, replay, stream, truth);
    const double roll = uniform(blink_random);
    if (roll < blinks.all_share) {
      points.clear();
    } else if (roll < blinks.all_share + blinks.some_share) {
      std::erase_if(points, [&](const TrackPoint&) { return uniform(blink_random) < 0.4; });
    }
    for (std::size_t m = 0; m < walk.point_count(); ++m) {
      if (stream.id[m] != 0 && stream.id[m] != before[m] && seen_before[m] != 0) {
        waiting[stream.id[m]] = static_cast<int>(f);
      }
      if (stream.id[m] != 0) seen_before[m] = 1;
    }
    const auto start = std::chrono::steady_clock::now();
    if (blinks.live) {
      labeller.update(points, static_cast<double>(f) / walk.rate_hz);
    } else {
      labeller.update(points);
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    score_frame(labeller, points, truth, waiting, static_cast<int>(f),
                std::max(LabellerOptions{}.min_track_age - 1, blinks.scored_from), score);
  }
  score.never_returned = static_cast<int>(waiting.size());
  score.microseconds_per_frame = seconds * 1e6 / static_cast<double>(walk.frame_count());
  return score;
}

// Subject s1 from Gait2392 subject01's static trial (the caller checks the shared data is there).
SubjectModel gait2392_model() {
  return build_subject_model(load_marker_set(test::marker_set_path("gait2392")),
                             load_marker_samples(test::gait2392_static()), "s1");
}

LabellerOptions gait2392_options() {
  LabellerOptions options;
  options.soft_segments = {"Torso"};
  return options;
}

constexpr int kSeeds = 10;

// Every seed's figures printed, the total returned (printed too).
Score replay_seeds(const std::string& title, const SubjectModel& model, const MarkerSamples& walk,
                   const LabellerOptions& options, const Blinks& blinks = {}, int seeds = kSeeds) {
  Score total;
  for (std::uint64_t seed = 1; seed <= static_cast<std::uint64_t>(seeds); ++seed) {
    const Score s = replay_walk(model, walk, seed, options, blinks);
    int worst = 0;
    for (int r : s.returns) worst = std::max(worst, r);
    std::printf(
        "%s seed %llu: %.0f visible marker-frames, %.2f %% right, %.3f %% wrong, %.0f left/right swaps, %.0f "
        "ghost-frames named, %zu reappearances: worst %d frames to the name, %d never; %.1f us per "
        "subject-frame\n",
        title.c_str(), static_cast<unsigned long long>(seed), s.visible, 100.0 * s.right / s.visible,
        100.0 * s.wrong / s.visible, s.swaps, s.ghosts_named, s.returns.size(), worst, s.never_returned,
        s.microseconds_per_frame);
    for (const auto& [name, frames] : s.unlabelled) {
      if (frames > LabellerOptions{}.min_track_age)
        std::printf("  %s: %d marker-frames\n", name.c_str(), frames);
    }
    total.visible += s.visible;
    total.visible_after += s.visible_after;
    total.right_after += s.right_after;
    total.wrong_after += s.wrong_after;
    total.swaps_after += s.swaps_after;
    total.ghosts_named += s.ghosts_named;
    total.ghosts += s.ghosts;
    total.microseconds_per_frame += s.microseconds_per_frame / seeds;
    total.right += s.right;
    total.wrong += s.wrong;
    total.swaps += s.swaps;
    total.never_returned += s.never_returned;
    total.returns.insert(total.returns.end(), s.returns.begin(), s.returns.end());
  }
  int worst = 0;
  for (int r : total.returns) worst = std::max(worst, r);
  std::printf(
      "%s, %d seeds: %.2f %% right (%.2f %% from frame %d, when tracks are old enough to acquire), %.3f %% "
      "wrong, %.0f left/right swaps, %.0f of %.0f false point-frames named, %zu reappearances: worst %d "
      "frames "
      "(%.0f ms at %.0f Hz) to the name, %d never; %.1f us per subject-frame\n",
      title.c_str(), seeds, 100.0 * total.right / total.visible,
      100.0 * total.right_after / total.visible_after,
      std::max(LabellerOptions{}.min_track_age - 1, blinks.scored_from), 100.0 * total.wrong / total.visible,
      total.swaps, total.ghosts_named, total.ghosts, total.returns.size(), worst,
      worst * 1000.0 / walk.rate_hz, walk.rate_hz, total.never_returned, total.microseconds_per_frame);
  total.returns = {worst};
  total.worst_return_ms = worst * 1000.0 / walk.rate_hz;
  return total;
}

TEST(Labeller, Gait2392WalkFromTheStaticModel) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const SubjectModel model = gait2392_model();
  const Score total =
      replay_seeds("gait2392 walk1", model, load_marker_samples(test::gait2392_walk()), gait2392_options());
  // Measured (10 seeds): 98.44 % right, 99.83 % from frame 2, 0.068 % wrong, 0 swaps, worst return 2
  // frames (33 ms), 4 never (docs/marker_sets.md). The issue asks 99.5 % right, 0.1 % wrong and every
  // name back within 100 ms live.
  EXPECT_EQ(total.swaps, 0.0);
  EXPECT_GT(100.0 * total.right / total.visible, 98.0);
  EXPECT_GT(100.0 * total.right_after / total.visible_after, 99.5);
  EXPECT_LT(100.0 * total.wrong / total.visible, 0.1);
  EXPECT_LE(total.worst_return_ms, 100.0);
  EXPECT_LE(total.never_returned, 6);
  EXPECT_LT(total.ghosts_named, 40.0);
}

TEST(Labeller, RajagopalWalkFromItsStaticModel) {
  PANOPTES_REQUIRE_SHARED(test::rajagopal_static());
  const MarkerSet set = load_marker_set(test::marker_set_path("rajagopal"));
  const SubjectModel model = build_subject_model(set, load_marker_samples(test::rajagopal_static()), "s1");
  LabellerOptions options;
  options.soft_segments = {"Torso"};
  const Score total =
      replay_seeds("rajagopal walk", model, load_marker_samples(test::rajagopal_walk()), options);
  // Measured (10 seeds): 99.02 % right, 99.90 % from frame 2, no wrong name, 0 swaps, worst return 2
  // frames (20 ms), 1 never (docs/marker_sets.md).
  EXPECT_EQ(total.swaps, 0.0);
  EXPECT_GT(100.0 * total.right / total.visible, 98.5);
  EXPECT_GT(100.0 * total.right_after / total.visible_after, 99.5);
  EXPECT_LT(100.0 * total.wrong / total.visible, 0.05);
  EXPECT_LE(total.worst_return_ms, 100.0);
  EXPECT_LE(total.never_returned, 3);
}

// Tracks the estimator leaves out for an instant keep their names when the labeller knows the time
// (live); without it every blink ended the names, and an instant with no track at all made the
// subject start again from nothing: the estimator's labels at 240 Hz and on every frame were 66-67 %
// right with 2000+ left/right swaps (docs/marker_sets.md, "Labelling rate").
TEST(Labeller, TracksMissingForAnInstantKeepTheirNamesLive) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const SubjectModel model = gait2392_model();
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  const Blinks ended{0.02, 0.10, false, {}, 0, 0};
  const Blinks live{0.02, 0.10, true, {}, 0, 0};
  const Score before =
      replay_seeds("gait2392 walk1, blinks, tracks ended", model, walk, gait2392_options(), ended, 3);
  const Score after = replay_seeds("gait2392 walk1, blinks, live", model, walk, gait2392_options(), live, 3);
  const auto right = [](const Score& s) { return 100.0 * s.right_after / s.visible_after; };
  EXPECT_EQ(after.swaps, 0.0);
  EXPECT_GT(right(after), 99.0);
  EXPECT_LT(100.0 * after.wrong / after.visible, 0.1);
  EXPECT_GT(right(after) - right(before), 1.0) << "the blinks should cost the names when tracks end at once";
}

// The estimator's first instants lack some tracks (a camera's frames not in yet, a track not
// confirmed): acquired while L.Acromium was hidden, the three-marker soft torso had no rigid fit
// with the right two, and the hypothesis that took L.Temple as L.Acromium explained more (the torso
// unlocks the head and the arms); its names stayed on living tracks for the whole trial (the
// estimator's walk: 80.5 % right, 2.4 % wrong, the head and left arm never named). revise() searches
// the tree and each subtree afresh while mature tracks are left unnamed and takes a hypothesis that
// explains more.
TEST(Labeller, ASubjectAcquiredWhileAMarkerWasHiddenIsRevised) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const SubjectModel model = gait2392_model();
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  // Scored from two revision periods (12 instants each) after L.Acromium's track has begun: before
  // it nothing tells the wrong torso from the right one.
  const Blinks hidden{0.0, 0.0, false, "L.Acromium", 20, 20 + 2 * LabellerOptions{}.revise_period_instants};
  LabellerOptions never = gait2392_options();
  never.revise_margin = 1000;  // no revision: the behaviour before it
  const Score before = replay_seeds("gait2392 walk1, L.Acromium hidden at start, never revised", model, walk,
                                    never, hidden, 10);
  const Score after =
      replay_seeds("gait2392 walk1, L.Acromium hidden at start", model, walk, gait2392_options(), hidden, 10);
  const auto right = [](const Score& s) { return 100.0 * s.right_after / s.visible_after; };
  const auto wrong = [](const Score& s) { return 100.0 * s.wrong_after / s.visible_after; };
  EXPECT_EQ(after.swaps_after, 0.0);
  EXPECT_GT(right(after), 99.5);
  EXPECT_LT(wrong(after), 0.1);
  EXPECT_GT(wrong(before), 2.0) << "the early acquisition should stay wrong unrevised";
}

// From frame `from` on, marker m is seen under the track id of marker moved[m] (the tracker moved
// tracks between markers); the labeller runs every `every` frames with the walk's times (live). The
// names of the moved markers afterwards, counted at every frame: (right, wrong).
std::pair<int, int> names_after_moved_tracks(const SubjectModel& model, const MarkerSamples& walk,
                                             const LabellerOptions& options,
                                             const std::map<std::size_t, std::size_t>& moved,
                                             std::size_t from, std::size_t every = 1) {
  std::map<std::size_t, std::size_t> marker_of;  // track index -> marker, once moved
  for (const auto& [m, track] : moved) marker_of[track] = m;
  Labeller labeller({model}, options);
  int wrong = 0;
  int right = 0;
  for (std::size_t f = 0; f < walk.frame_count(); ++f) {
    std::vector<TrackPoint> points;
    for (std::size_t m = 0; m < walk.point_count(); ++m) {
      if (!walk.is_valid(f, m) || !walk.position(f, m).allFinite()) continue;
      const auto to = moved.find(m);
      const std::size_t id = f >= from && to != moved.end() ? to->second : m;
      points.push_back({static_cast<std::uint64_t>(id) + 1, walk.position(f, m)});
    }
    if (f % every == 0) labeller.update(points, static_cast<double>(f) / walk.rate_hz);
    if (f <= from) continue;
    for (const auto& point : points) {
      const auto found = marker_of.find(point.track - 1);
      if (found == marker_of.end()) continue;
      if (const auto label = labeller.label_of(point.track))
        (label->marker == walk.names[found->second] ? right : wrong) += 1;
    }
  }
  std::printf("after the tracks moved: %d marker-frames of the %zu markers named right, %d wrong\n", right,
              moved.size(), wrong);
  return {right, wrong};
}

std::size_t column(const MarkerSamples& walk, const std::string& name) {
  return static_cast<std::size_t>(std::find(walk.names.begin(), walk.names.end(), name) - walk.names.begin());
}

// The tracker swapped two close markers' tracks (seen live under CPU contention: a foot's midfoot
// and toe markers, test_live_labels): the names stayed on the tracks, wrong for the rest of the
// walk, since no revision sees it (as many markers explained). untangle() refits a segment that
// fits poorly with each pair of its named points exchanged and moves the names.
TEST(Labeller, TracksThatExchangeTheirMarkersAreUntangled) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const SubjectModel model = gait2392_model();
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  const std::size_t a = column(walk, "L.Midfoot.Sup");
  const std::size_t b = column(walk, "L.Toe.Med");
  ASSERT_LT(b, walk.point_count());
  const std::map<std::size_t, std::size_t> exchanged{{a, b}, {b, a}};
  LabellerOptions never = gait2392_options();
  never.untangle_rms_m = 1e9;  // the behaviour before untangle()
  never.release_rms_m = 1e9;
  const auto [right_before, wrong_before] = names_after_moved_tracks(model, walk, never, exchanged, 60);
  const auto [right_after, wrong_after] =
      names_after_moved_tracks(model, walk, gait2392_options(), exchanged, 60);
  EXPECT_GT(wrong_before, 100) << "the exchanged tracks should keep the wrong names without untangle()";
  EXPECT_LE(wrong_after, 2) << "the names should follow their markers within an instant";
  EXPECT_GT(right_after, 100);
}

// A live run under CPU contention (test_live_labels, replayed with panoptes_label_replay): the
// tracker moved three of a foot's tracks round and one between the feet at once, and with the
// labeller running every 50 ms instead of every frame the names stayed wrong for the rest of the
// walk (16 % of all marker-frames). No exchange of two names fits: the misfitting names are released
// and come back on the right tracks.
TEST(Labeller, TracksMovedRoundOrToAnotherSegmentAreReleased) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const SubjectModel model = gait2392_model();
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  const std::size_t sup = column(walk, "L.Midfoot.Sup");
  const std::size_t med = column(walk, "L.Toe.Med");
  const std::size_t tip = column(walk, "L.Toe.Tip");
  const std::size_t heel = column(walk, "L.Heel");
  const std::size_t right_med = column(walk, "R.Toe.Med");
  for (std::size_t m : {sup, med, tip, heel, right_med}) ASSERT_LT(m, walk.point_count());
  const std::map<std::size_t, std::size_t> moved{
      {med, sup}, {tip, med}, {sup, tip}, {right_med, heel}, {heel, right_med}};
  const std::size_t every =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(0.05 * walk.rate_hz)));
  LabellerOptions never = gait2392_options();
  never.release_rms_m = 1e9;  // the behaviour before release_misfits()
  const auto [right_before, wrong_before] = names_after_moved_tracks(model, walk, never, moved, 60, every);
  const auto [right_after, wrong_after] =
      names_after_moved_tracks(model, walk, gait2392_options(), moved, 60, every);
  EXPECT_GT(wrong_before, 100) << "the moved tracks should keep the wrong names without releasing them";
  EXPECT_LE(wrong_after, 5 * static_cast<int>(every))
      << "the names should follow their markers within a few runs";
  EXPECT_GE(right_after, wrong_before * 9 / 10) << "the moved markers should be named again";
}

// Seen in a live run's tracks labelled again at every instant (panoptes_label_replay): the tracker
// exchanged the upper arm's two markers (Bicep, Elbow: a two-marker segment, no rigid fit) and the
// left foot's lateral and medial markers in pairs (Toe.Lat/Toe.Med, Midfoot.Lat/Midfoot.Sup),
// which the foot's layout fits turned upside down with a small residual. The names stayed wrong for
// the rest of the walk (14.6 % of all marker-frames). The pair's handedness with its parent's
// markers and the foot's turn from its parent give them back.
TEST(Labeller, ExchangedPairsAndAMirroredSegmentAreUntangled) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const SubjectModel model = gait2392_model();
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  std::map<std::size_t, std::size_t> moved;
  for (const auto& [a, b] : {std::pair<std::string, std::string>{"L.Bicep", "L.Elbow"},
                             {"L.Toe.Lat", "L.Toe.Med"},
                             {"L.Midfoot.Lat", "L.Midfoot.Sup"}}) {
    const std::size_t i = column(walk, a);
    const std::size_t j = column(walk, b);
    ASSERT_LT(i, walk.point_count()) << a;
    ASSERT_LT(j, walk.point_count()) << b;
    moved[i] = j;
    moved[j] = i;
  }
  const auto [right, wrong] = names_after_moved_tracks(model, walk, gait2392_options(), moved, 60);
  EXPECT_LE(wrong, 6 * 2) << "the names should follow their markers within two instants";
  EXPECT_GT(right, 6 * 80);
}

// A fresh clone's suite under a parallel build (test_live_labels, replayed offline): after a 108 ms
// stall of every camera the tracker exchanged the left shank's Upper and Rear tracks. The shank's
// three markers make a near-isosceles triangle (Upper-Front 86.6 mm, Rear-Front 90.5 mm), so the
// exchanged names fit it within 3 mm, turned over against the thigh. Releasing the names let them
// straight back onto the same tracks at every run (95.8 % named right over the walk); exchanging
// them back follows the markers.
TEST(Labeller, AThreeMarkerSegmentThatFitsOnlyTurnedOverHasItsNamesExchangedBack) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  const std::size_t upper = column(walk, "L.Shank.Upper");
  const std::size_t rear = column(walk, "L.Shank.Rear");
  ASSERT_LT(upper, walk.point_count());
  ASSERT_LT(rear, walk.point_count());
  const std::map<std::size_t, std::size_t> exchanged{{upper, rear}, {rear, upper}};
  const auto [right, wrong] =
      names_after_moved_tracks(gait2392_model(), walk, gait2392_options(), exchanged, 60);
  EXPECT_LE(wrong, 2 * 2) << "the names should follow their markers within an instant";
  EXPECT_GT(right, 2 * 80);
}

// A hidden L.Wrist.Lat whose coasting track leaves the estimator's output for `out_frames` from
// frame 60, then comes back for `astray_frames` where `astray` puts it (the walk, the frame, Lat's
// and Med's true places), then ends; the marker reappears under a new track. What the labeller made
// of it: frames with the Med marker's track misnamed, frames until the new track is named Lat.
struct AstrayReturn {
  int med_wrong = 0;
  std::optional<double> lat_named_after_s;
};
AstrayReturn astray_return(
    std::size_t out_frames, std::size_t astray_frames,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d& lat, const Eigen::Vector3d& med)>& astray) {
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  const std::size_t lat = column(walk, "L.Wrist.Lat");
  const std::size_t med = column(walk, "L.Wrist.Med");
  EXPECT_LT(lat, walk.point_count());
  EXPECT_LT(med, walk.point_count());
  AstrayReturn result;
  if (lat >= walk.point_count() || med >= walk.point_count()) return result;
  const std::size_t gone = 60, back = gone + out_frames, reappears = back + astray_frames;
  constexpr std::uint64_t kNewTrack = 1000;
  Labeller labeller({gait2392_model()}, gait2392_options());
  std::optional<std::size_t> lat_named;
  for (std::size_t f = 0; f < walk.frame_count(); ++f) {
    std::vector<TrackPoint> points;
    for (std::size_t m = 0; m < walk.point_count(); ++m) {
      if (!walk.is_valid(f, m) || !walk.position(f, m).allFinite()) continue;
      Eigen::Vector3d p = walk.position(f, m);
      std::uint64_t id = m + 1;
      if (m == lat && f >= gone && f < back) continue;
      if (m == lat && f >= back && f < reappears) p = astray(p, walk.position(f, med));
      if (m == lat && f >= reappears) id = kNewTrack;
      points.push_back({id, p});
    }
    labeller.update(points, static_cast<double>(f) / walk.rate_hz);
    if (f < gone) continue;
    const auto label = labeller.label_of(med + 1);
    result.med_wrong += label && label->marker != "L.Wrist.Med" ? 1 : 0;
    const auto new_label = labeller.label_of(kNewTrack);
    if (f >= reappears && !lat_named && new_label && new_label->marker == "L.Wrist.Lat") lat_named = f;
  }
  if (lat_named) result.lat_named_after_s = static_cast<double>(*lat_named - reappears) / walk.rate_hz;
  std::printf("L.Wrist.Med misnamed in %d frames; L.Wrist.Lat's new track named after %s s\n",
              result.med_wrong, lat_named ? std::to_string(*result.lat_named_after_s).c_str() : "never");
  return result;
}

// Live, a hidden marker's coasting track kept its name through 0.2 s out of the estimator's output
// (under keep_absent_s) and came back on the far side of its segment's other marker, at the right
// distance but mirrored (L.Wrist.Lat through L.Wrist.Med, test_label_occlusion seed 8). The pair's
// handedness exchange then named the Med marker's track L.Wrist.Lat. The track that came back is
// released instead; the marker's own new track gets the name when it reappears.
TEST(Labeller, ATrackBackFromALongAbsenceOnTheWrongSideIsReleasedNotExchanged) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  // 0.2 s out, 0.3 s astray (60 Hz), mirrored through Med.
  const AstrayReturn got = astray_return(12, 18, [](const Eigen::Vector3d& lat, const Eigen::Vector3d& med) {
    return Eigen::Vector3d(2.0 * med - lat);
  });
  EXPECT_EQ(got.med_wrong, 0) << "the Med marker's track took the hidden marker's name";
  ASSERT_TRUE(got.lat_named_after_s) << "L.Wrist.Lat's new track was never named";
  EXPECT_LE(*got.lat_named_after_s, 0.1);
}

// test_live_labels under load: the hidden L.Wrist.Lat's coasting track was out of the output for
// 93 ms (not a long absence) and came back 3 mm from L.Wrist.Med for 5 ms. Its pair's handedness
// (measured from two points on one marker) asked for an exchange, which named the Med marker's track
// L.Wrist.Lat for the remaining 3.9 s. Two tracks not the pair's distance apart are no exchanged pair.
TEST(Labeller, ATrackBackOnItsNeighbourAfterAShortAbsenceTakesNoName) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  // 5 frames out (83 ms at 60 Hz), 1 frame 3 mm from Med, on the side away from Lat (the handedness
  // mirrored).
  const AstrayReturn got = astray_return(5, 1, [](const Eigen::Vector3d& lat, const Eigen::Vector3d& med) {
    return Eigen::Vector3d(med - 0.003 * (lat - med).normalized());
  });
  EXPECT_EQ(got.med_wrong, 0) << "the Med marker's track took the hidden marker's name";
  ASSERT_TRUE(got.lat_named_after_s) << "L.Wrist.Lat's new track was never named";
  EXPECT_LE(*got.lat_named_after_s, 0.1);
}

TEST(Labeller, PointsThatFitNothingStayUnlabelled) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  Labeller labeller({gait2392_model()}, gait2392_options());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> room(-1.5, 1.5);
  std::size_t named = 0;
  for (std::uint64_t frame = 0; frame < 60; ++frame) {  // 45 points in a 3 m room, each a second long
    std::vector<TrackPoint> points;
    for (std::uint64_t t = 0; t < 45; ++t)
      points.push_back({t, Eigen::Vector3d(room(rng), room(rng), room(rng))});
    labeller.update(points);
    for (const auto& point : points) named += labeller.label_of(point.track) ? 1 : 0;
  }
  EXPECT_EQ(named, 0U);
}

}  // namespace
}  // namespace panoptes::labelling
