// SPDX-License-Identifier: Apache-2.0
// A subject model trained from an already-labelled dynamic trial (issue 33 item 1, as AIM does):
// the first half of Gait2392's walk1 explains the second half better than the static trial does.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "labelling_test_support.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"

namespace panoptes::labelling {
namespace {

// The fraction of (frame, marker pair) samples of `trial` whose distance lies within the model's
// tolerance of its mean, over every pair the model has and the trial sees.
double fraction_within_tolerance(const SubjectModel& model, const MarkerSamples& trial) {
  const auto column = [&](const std::string& name) {
    for (std::size_t i = 0; i < trial.point_count(); ++i) {
      if (trial.names[i] == name) return std::optional<std::size_t>(i);
    }
    return std::optional<std::size_t>();
  };
  double inside = 0.0;
  double samples = 0.0;
  for (const auto& segment : model.segments) {
    for (const auto& d : segment.distances) {
      const auto a = column(d.markers[0]);
      const auto b = column(d.markers[1]);
      if (!a || !b) continue;
      for (std::size_t f = 0; f < trial.frame_count(); ++f) {
        if (!trial.is_valid(f, *a) || !trial.is_valid(f, *b)) continue;
        const double distance = (trial.position(f, *a) - trial.position(f, *b)).norm();
        inside += std::abs(distance - d.mean_m) <= d.tolerance_m ? 1.0 : 0.0;
        samples += 1.0;
      }
    }
  }
  return inside / samples;
}

// A model trained on the first half of `walk` and one from `static_trial`, judged on the second half.
struct HalfAndHalf {
  SubjectModel trained;
  double trained_inside = 0.0;  // fraction of the second half's distances within its tolerances
  double static_inside = 0.0;   // the same for the static model
};

HalfAndHalf train_on_first_half(const std::string& set_name, const std::filesystem::path& static_trial,
                                const std::filesystem::path& walk_path) {
  const MarkerSet set = load_marker_set(test::marker_set_path(set_name));
  const MarkerSamples walk = load_marker_samples(walk_path);
  const std::size_t half = walk.frame_count() / 2;
  ModelOptions dynamic;
  dynamic.dynamic = true;
  HalfAndHalf out;
  out.trained = build_subject_model(set, slice_frames(walk, 0, half), "s1", dynamic);
  const SubjectModel from_static = build_subject_model(set, load_marker_samples(static_trial), "s1");
  const MarkerSamples second_half = slice_frames(walk, half, walk.frame_count());
  EXPECT_EQ(second_half.frame_count(), walk.frame_count() - half);
  out.trained_inside = fraction_within_tolerance(out.trained, second_half);
  out.static_inside = fraction_within_tolerance(from_static, second_half);
  std::printf(
      "%s second half: %.1f %% of marker-pair distances within the tolerances of the model trained on "
      "the first half, %.1f %% within the static model's\n",
      walk_path.filename().c_str(), out.trained_inside * 100.0, out.static_inside * 100.0);
  return out;
}

TEST(DynamicModel, FirstHalfOfWalk1ExplainsTheSecondHalf) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  const HalfAndHalf result = train_on_first_half("gait2392", test::gait2392_static(), test::gait2392_walk());
  // The 8 knee and ankle markers are calibration-only: left out, flagged; so are the 4 joints.
  EXPECT_EQ(result.trained.marker_count(), 41U);
  std::size_t absent = 0;
  std::size_t moved = 0;
  for (const auto& flag : result.trained.flags) {
    absent += flag.kind == MarkerFlag::Kind::kAbsent ? 1 : 0;
    moved += flag.kind == MarkerFlag::Kind::kMoved ? 1 : 0;
  }
  EXPECT_EQ(absent, 8U + 4U);
  EXPECT_EQ(moved, 0U);
  EXPECT_TRUE(result.trained.joints.empty());
  EXPECT_GT(result.trained_inside, 0.95);
  EXPECT_GT(result.trained_inside, result.static_inside + 0.2);
}

TEST(DynamicModel, RajagopalFirstHalfExplainsTheSecondHalf) {
  PANOPTES_REQUIRE_SHARED(test::rajagopal_static());
  const HalfAndHalf result =
      train_on_first_half("rajagopal", test::rajagopal_static(), test::rajagopal_walk());
  EXPECT_EQ(result.trained.marker_count(), 41U);  // 47 less the 6 medial markers
  EXPECT_GT(result.trained_inside, 0.95);
  EXPECT_GT(result.trained_inside, result.static_inside + 0.2);
}

TEST(DynamicModel, SliceFramesKeepsTheFramesAsked) {
  MarkerSamples samples;
  samples.names = {"a", "b"};
  for (int f = 0; f < 5; ++f) {
    for (int p = 0; p < 2; ++p) samples.positions.emplace_back(f, p, 0.0);
  }
  samples.valid.assign(10, 1);
  const MarkerSamples middle = slice_frames(samples, 1, 3);
  ASSERT_EQ(middle.frame_count(), 2U);
  EXPECT_EQ(middle.position(0, 1), Eigen::Vector3d(1, 1, 0));
  EXPECT_EQ(middle.position(1, 0), Eigen::Vector3d(2, 0, 0));
  EXPECT_EQ(slice_frames(samples, 3, 100).frame_count(), 2U);
  EXPECT_EQ(slice_frames(samples, 7, 9).frame_count(), 0U);
}

}  // namespace
}  // namespace panoptes::labelling
