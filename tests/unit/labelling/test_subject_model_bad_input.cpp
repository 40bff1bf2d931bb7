// SPDX-License-Identifier: Apache-2.0
// Static trials that do not fit the marker set (issue 33, "Bad input"): a marker the trial lacks
// is an error naming it unless optional; a subject who moves or markers missing in frames still
// give a model, with those markers flagged.
#include <string>

#include <gtest/gtest.h>

#include "labelling_test_support.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"

namespace panoptes::labelling {
namespace {

using test::error_of;

constexpr double kMillimetre = 1e-3;

class StaticTrialBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    PANOPTES_REQUIRE_SHARED(test::gait2392_static());
    set_ = load_marker_set(test::marker_set_path("gait2392"));
    trial_ = load_marker_samples(test::gait2392_static());
  }
  std::size_t column(const std::string& name) const {
    for (std::size_t i = 0; i < trial_.point_count(); ++i) {
      if (trial_.names[i] == name) return i;
    }
    ADD_FAILURE() << name;
    return 0;
  }
  const ModelMarker& model_marker(const SubjectModel& model, const std::string& name) const {
    const SegmentLayout& segment = *model.segment(set_.segments[*set_.segment_of(name)].name);
    for (const auto& marker : segment.markers) {
      if (marker.name == name) return marker;
    }
    throw std::runtime_error(name + " not in the model");
  }
  MarkerSet set_;
  MarkerSamples trial_;
};

TEST_F(StaticTrialBadInput, AMarkerTheTrialLacksIsAnErrorNamingItAndTheFile) {
  trial_.names[column("R.Knee.Med")] = "RKneeMedial";
  const std::string message = error_of<InputError>([&] { build_subject_model(set_, trial_, "s1"); });
  EXPECT_NE(message.find(test::gait2392_static().string()), std::string::npos) << message;
  EXPECT_NE(message.find("marker 'R.Knee.Med'"), std::string::npos) << message;
  EXPECT_NE(message.find("is not in the static trial"), std::string::npos) << message;
  EXPECT_NE(message.find("optional: true"), std::string::npos) << message;
}

TEST_F(StaticTrialBadInput, AMarkerNeverSeenIsAnError) {
  const std::size_t c = column("Sternum");
  for (std::size_t f = 0; f < trial_.frame_count(); ++f) trial_.valid[f * trial_.point_count() + c] = 0;
  const std::string message = error_of<InputError>([&] { build_subject_model(set_, trial_, "s1"); });
  EXPECT_NE(message.find("marker 'Sternum'"), std::string::npos) << message;
  EXPECT_NE(message.find("never seen"), std::string::npos) << message;
}

TEST_F(StaticTrialBadInput, AnOptionalMarkerTheTrialLacksIsLeftOutAndFlagged) {
  set_.markers[*set_.marker_index("Top.Head")].optional = true;
  trial_.names[column("Top.Head")] = "Head.Top";
  const SubjectModel model = build_subject_model(set_, trial_, "s1");
  EXPECT_EQ(model.marker_count(), set_.markers.size() - 1);
  EXPECT_EQ(model.segment("Head")->markers.size(), 2U);
  EXPECT_FALSE(model.segment("Head")->has_pose);
  bool flagged = false;
  for (const auto& flag : model.flags)
    flagged = flagged || (flag.marker == "Top.Head" && flag.kind == MarkerFlag::Kind::kAbsent);
  EXPECT_TRUE(flagged);
  EXPECT_EQ(model.ignored_points, std::vector<std::string>{"Head.Top"});
}

TEST_F(StaticTrialBadInput, MarkersMissingInFramesAreFlaggedAndTheModelBuilt) {
  const std::size_t c = column("R.Thigh.Front");
  for (std::size_t f = 100; f < 130; ++f) trial_.valid[f * trial_.point_count() + c] = 0;
  const SubjectModel model = build_subject_model(set_, trial_, "s1");
  EXPECT_EQ(model_marker(model, "R.Thigh.Front").missing_frames, 30U);
  bool flagged = false;
  for (const auto& flag : model.flags) {
    if (flag.marker != "R.Thigh.Front") continue;
    flagged = flag.kind == MarkerFlag::Kind::kMissingFrames;
    EXPECT_NE(flag.reason.find("missing in 30 of 300 frames"), std::string::npos) << flag.reason;
  }
  EXPECT_TRUE(flagged);
  for (const auto& d : model.segment("R.Thigh")->distances) {
    const bool involved = d.markers[0] == "R.Thigh.Front" || d.markers[1] == "R.Thigh.Front";
    EXPECT_EQ(d.frames, involved ? 270U : 300U);
  }
}

// The subject walks 0.5 m forward and turns 30 degrees during the "static" trial: every marker is
// flagged as moved, and the layouts stay those of the still trial (generalised Procrustes).
TEST_F(StaticTrialBadInput, ASubjectWhoMovesIsFlaggedAndTheLayoutsStaySharp) {
  const SubjectModel still = build_subject_model(set_, trial_, "s1");
  const double frames = static_cast<double>(trial_.frame_count());
  for (std::size_t f = 0; f < trial_.frame_count(); ++f) {
    const double s = static_cast<double>(f) / frames;
    const Eigen::AngleAxisd turn(s * 30.0 * M_PI / 180.0, Eigen::Vector3d::UnitY());  // y is up in the file
    for (std::size_t i = 0; i < trial_.point_count(); ++i) {
      Eigen::Vector3d& p = trial_.positions[f * trial_.point_count() + i];
      p = turn * p + Eigen::Vector3d(0.5 * s, 0.0, 0.0);
    }
  }
  const SubjectModel moving = build_subject_model(set_, trial_, "s1");
  std::size_t moved = 0;
  for (const auto& flag : moving.flags) moved += flag.kind == MarkerFlag::Kind::kMoved ? 1 : 0;
  EXPECT_EQ(moved, set_.markers.size());
  for (std::size_t s = 0; s < still.segments.size(); ++s) {
    const SegmentLayout& a = still.segments[s];
    const SegmentLayout& b = moving.segments[s];
    if (!a.has_pose) continue;  // translation-only segments cannot follow a turn
    EXPECT_LT(b.static_fit_rms_m, 1 * kMillimetre) << a.name;
    for (std::size_t i = 0; i < a.markers.size(); ++i) {
      for (std::size_t j = i + 1; j < a.markers.size(); ++j) {
        const double da = (a.markers[i].position_m - a.markers[j].position_m).norm();
        const double db = (b.markers[i].position_m - b.markers[j].position_m).norm();
        EXPECT_NEAR(da, db, 0.05 * kMillimetre)
            << a.name << " " << a.markers[i].name << "-" << a.markers[j].name;
      }
    }
  }
}

TEST_F(StaticTrialBadInput, ANameTheTrialRepeatsIsFlaggedAndTheFirstUsed) {
  const SubjectModel original = build_subject_model(set_, trial_, "s1");
  trial_.names[column("R.Toe.Lat")] = "R.Heel";  // R.Heel comes first in the file
  set_.markers[*set_.marker_index("R.Toe.Lat")].optional = true;
  const SubjectModel model = build_subject_model(set_, trial_, "s1");
  bool flagged = false;
  for (const auto& flag : model.flags) {
    if (flag.marker == "R.Heel" && flag.kind == MarkerFlag::Kind::kRepeated) {
      flagged = true;
      EXPECT_NE(flag.reason.find("2 points of this name"), std::string::npos) << flag.reason;
    }
  }
  EXPECT_TRUE(flagged);
  // The heel, not the toe marker that now has its name: the heel-midfoot distance is unchanged
  // (to the hundredth of a millimetre: the foot's layout has one marker fewer).
  const auto heel_to_midfoot = [&](const SubjectModel& m) {
    return (model_marker(m, "R.Heel").position_m - model_marker(m, "R.Midfoot.Sup").position_m).norm();
  };
  EXPECT_NEAR(heel_to_midfoot(model), heel_to_midfoot(original), 0.01 * kMillimetre);
}

TEST_F(StaticTrialBadInput, AJointPointTheTrialLacksNamesTheJoint) {
  set_.joints.push_back({"R.Hip", "R.Thigh", {"R_HJC"}});
  const std::string message = error_of<InputError>([&] { build_subject_model(set_, trial_, "s1"); });
  EXPECT_NE(message.find("joint 'R.Hip'"), std::string::npos) << message;
  EXPECT_NE(message.find("point 'R_HJC'"), std::string::npos) << message;
}

}  // namespace
}  // namespace panoptes::labelling
