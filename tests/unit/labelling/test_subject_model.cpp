// SPDX-License-Identifier: Apache-2.0
// Subject models from the real static trials of ../shared/data/static (docs/marker_sets.md): every
// marker of the set, distances equal to the file's own, small tolerances for a standing subject,
// joint centres where the set defines them, and layouts that explain the walking trials.
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "labelling_test_support.h"
#include "panoptes/formats/trc.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace panoptes::labelling {
namespace {

using test::marker_set_path;

constexpr double kMillimetre = 1e-3;

SubjectModel model_of(const std::string& set_name, const std::filesystem::path& trial) {
  return build_subject_model(load_marker_set(marker_set_path(set_name)), load_marker_samples(trial), "s1");
}

// The mean over frames of |a - b| in the file, computed here from the TRC reader's samples.
double file_distance(const MarkerTrajectories& file, const std::string& a, const std::string& b) {
  const auto column = [&](const std::string& name) {
    for (std::size_t i = 0; i < file.marker_count(); ++i) {
      if (file.marker_names[i] == name) return i;
    }
    ADD_FAILURE() << name << " not in the file";
    return std::size_t{0};
  };
  const std::size_t ia = column(a);
  const std::size_t ib = column(b);
  double sum = 0.0;
  double frames = 0.0;
  for (std::size_t f = 0; f < file.frame_count(); ++f) {
    if (!file.is_valid(f, ia) || !file.is_valid(f, ib)) continue;
    sum += (file.position(f, ia) - file.position(f, ib)).norm();
    frames += 1.0;
  }
  return sum / frames;
}

// Every marker of the set, distances as in the file, layouts reproducing them, tolerances positive
// and below `max_tolerance_m`.
void expect_model_matches_file(const SubjectModel& model, const MarkerSet& set,
                               const std::filesystem::path& trial, double max_tolerance_m) {
  ASSERT_EQ(model.marker_count(), set.markers.size());
  for (const auto& marker : set.markers) {
    const SegmentLayout* segment = model.segment(set.segments[*set.segment_of(marker.name)].name);
    ASSERT_NE(segment, nullptr) << marker.name;
    bool found = false;
    for (const auto& m : segment->markers)
      found = found || (m.name == marker.name && m.calibration_only == marker.calibration_only);
    EXPECT_TRUE(found) << marker.name;
  }
  const MarkerTrajectories file = load_trc(trial);
  double worst_statistic = 0.0;
  double worst_layout = 0.0;
  std::string worst_layout_pair;
  for (const auto& segment : model.segments) {
    const std::size_t n = segment.markers.size();
    ASSERT_EQ(segment.distances.size(), n * (n - 1) / 2) << segment.name;
    std::map<std::string, Eigen::Vector3d> layout;
    for (const auto& m : segment.markers) layout[m.name] = m.position_m;
    for (const auto& d : segment.distances) {
      const double truth = file_distance(file, d.markers[0], d.markers[1]);
      worst_statistic = std::max(worst_statistic, std::abs(d.mean_m - truth));
      const double layout_error = std::abs((layout[d.markers[0]] - layout[d.markers[1]]).norm() - truth);
      if (layout_error > worst_layout)
        worst_layout_pair = segment.name + " " + d.markers[0] + "-" + d.markers[1];
      worst_layout = std::max(worst_layout, layout_error);
      EXPECT_GT(d.tolerance_m, 0.0) << d.markers[0] << "-" << d.markers[1];
      EXPECT_LE(d.tolerance_m, max_tolerance_m) << d.markers[0] << "-" << d.markers[1];
      EXPECT_LE(d.min_m, d.mean_m);
      EXPECT_GE(d.max_m, d.mean_m);
      EXPECT_EQ(d.frames, file.frame_count());
    }
  }
  std::printf(
      "%s: worst |model mean - file mean| %.6f mm, worst |layout distance - file mean| %.4f mm (%s)\n",
      trial.filename().c_str(), worst_statistic * 1000.0, worst_layout * 1000.0, worst_layout_pair.c_str());
  EXPECT_LT(worst_statistic, 0.1 * kMillimetre);
  // For a standing subject the layout's distances equal the file's within a tenth of a millimetre;
  // the arms of the Rajagopal subject rotate, and segments without a pose are fitted by
  // translation only, so their layout is the mean positions.
  EXPECT_LT(worst_layout, 0.1 * kMillimetre);
}

TEST(SubjectModel, Gait2392StaticTrialGivesEveryMarkerAndTheFilesDistances) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  const MarkerSet set = load_marker_set(marker_set_path("gait2392"));
  const SubjectModel model = model_of("gait2392", test::gait2392_static());
  expect_model_matches_file(model, set, test::gait2392_static(), 3 * kMillimetre);
  EXPECT_EQ(model.frames, 300U);
  EXPECT_TRUE(model.ignored_points.empty());
  for (const auto& segment : model.segments) {
    EXPECT_EQ(segment.has_pose, segment.tracked_marker_names().size() >= 3) << segment.name;
    if (segment.has_pose) {
      EXPECT_LT(segment.static_fit_rms_m, 1 * kMillimetre) << segment.name;
    }
  }
  // The head turns during the trial: the left temple spreads 21 mm RMS and is flagged.
  ASSERT_EQ(model.flags.size(), 1U);
  EXPECT_EQ(model.flags[0].marker, "L.Temple");
  EXPECT_EQ(model.flags[0].kind, MarkerFlag::Kind::kMoved);
}

TEST(SubjectModel, RajagopalStaticTrialIgnoresVirtualPointsItDoesNotName) {
  PANOPTES_REQUIRE_SHARED(test::rajagopal_static());
  const MarkerSet set = load_marker_set(marker_set_path("rajagopal"));
  const SubjectModel model = model_of("rajagopal", test::rajagopal_static());
  expect_model_matches_file(model, set, test::rajagopal_static(), 7 * kMillimetre);
  // 64 points: 47 markers, 6 joint centres the set names, 11 ignored.
  EXPECT_EQ(model.ignored_points.size(), 11U);
  EXPECT_EQ(model.joints.size(), 8U);
  EXPECT_TRUE(model.flags.empty());
}

// A joint centre in the parent's and the child's frame maps back onto the file's own point.
TEST(SubjectModel, JointCentresReproduceTheStaticFilesPoints) {
  PANOPTES_REQUIRE_SHARED(test::rajagopal_static());
  const SubjectModel model = model_of("rajagopal", test::rajagopal_static());
  const MarkerSamples trial = load_marker_samples(test::rajagopal_static());
  const std::map<std::string, std::string> point_of = {
      {"R.Hip", "R_HJC"}, {"L.Knee", "L.KneeJoint"}, {"R.Ankle", "R.AnkleJoint"}};
  const std::size_t frame = 100;
  const auto world = [&](const std::string& name) {
    for (std::size_t i = 0; i < trial.point_count(); ++i) {
      if (trial.names[i] == name) return trial.position(frame, i);
    }
    return Eigen::Vector3d(Eigen::Vector3d::Constant(NAN));
  };
  const auto pose = [&](const std::string& segment_name) {
    const SegmentLayout& segment = *model.segment(segment_name);
    std::vector<std::optional<Eigen::Vector3d>> points;
    for (const auto& m : segment.markers) points.emplace_back(world(m.name));
    return fit_layout(segment, points).value().T_world_segment;
  };
  for (const auto& joint : model.joints) {
    if (!point_of.contains(joint.name)) continue;
    const Eigen::Vector3d truth = world(point_of.at(joint.name));
    EXPECT_LT((pose(joint.parent).apply(joint.in_parent_m) - truth).norm(), 2 * kMillimetre) << joint.name;
    EXPECT_LT((pose(joint.child).apply(joint.in_child_m) - truth).norm(), 2 * kMillimetre) << joint.name;
  }
}

// A midpoint joint: the knee centre of Gait2392 from the thigh's and from the shank's layout lands
// on the midpoint of the two knee markers in a frame of the trial.
TEST(SubjectModel, MidpointJointCentresLandOnTheMidpoint) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  const SubjectModel model = model_of("gait2392", test::gait2392_static());
  const MarkerSamples trial = load_marker_samples(test::gait2392_static());
  const std::size_t frame = 200;
  const auto world = [&](const std::string& name) {
    for (std::size_t i = 0; i < trial.point_count(); ++i) {
      if (trial.names[i] == name) return trial.position(frame, i);
    }
    ADD_FAILURE() << name;
    return Eigen::Vector3d(Eigen::Vector3d::Zero());
  };
  const auto pose = [&](const std::string& segment_name) {
    const SegmentLayout& segment = *model.segment(segment_name);
    std::vector<std::optional<Eigen::Vector3d>> points;
    for (const auto& m : segment.markers) points.emplace_back(world(m.name));
    return fit_layout(segment, points).value().T_world_segment;
  };
  for (const char* side : {"R", "L"}) {
    const std::string s = side;
    const JointCentre* knee = nullptr;
    for (const auto& joint : model.joints) knee = joint.name == s + ".Knee" ? &joint : knee;
    ASSERT_NE(knee, nullptr);
    EXPECT_EQ(knee->parent, s + ".Thigh");
    const Eigen::Vector3d truth = (world(s + ".Knee.Lat") + world(s + ".Knee.Med")) / 2.0;
    const double from_thigh = (pose(knee->parent).apply(knee->in_parent_m) - truth).norm();
    const double from_shank = (pose(knee->child).apply(knee->in_child_m) - truth).norm();
    std::printf("%s knee centre: %.2f mm from the thigh, %.2f mm from the shank\n", side, from_thigh * 1000.0,
                from_shank * 1000.0);
    EXPECT_LT(from_thigh, 1 * kMillimetre);
    EXPECT_LT(from_shank, 1 * kMillimetre);
  }
}

// Rigid fit of each posed segment's layout to every frame of a walking trial: RMS over frames.
std::map<std::string, double> walk_fit_rms(const SubjectModel& model, const MarkerSamples& walk,
                                           const std::map<std::string, std::string>& rename = {}) {
  std::map<std::string, double> rms;
  for (const auto& segment : model.segments) {
    if (!segment.has_pose) continue;
    double squares = 0.0;
    double used = 0.0;
    for (std::size_t f = 0; f < walk.frame_count(); ++f) {
      std::vector<std::optional<Eigen::Vector3d>> points;
      for (const auto& m : segment.markers) {
        const std::string name = rename.contains(m.name) ? rename.at(m.name) : m.name;
        std::optional<Eigen::Vector3d> seen;
        for (std::size_t i = 0; i < walk.point_count(); ++i) {
          if (walk.names[i] == name && walk.is_valid(f, i)) seen = walk.position(f, i);
        }
        points.push_back(seen);
      }
      const auto fit = fit_layout(segment, points);
      if (!fit) continue;
      squares += fit->rms_m * fit->rms_m * static_cast<double>(fit->markers_used);
      used += static_cast<double>(fit->markers_used);
    }
    rms[segment.name] = used > 0.0 ? std::sqrt(squares / used) : NAN;
  }
  return rms;
}

void expect_layouts_explain_walk(const SubjectModel& model, const std::filesystem::path& walk_path) {
  const MarkerSamples walk = load_marker_samples(walk_path);
  const auto rms = walk_fit_rms(model, walk);
  for (const auto& [segment, value] : rms) {
    std::printf("%s: %-8s rigid fit RMS over the walk %.2f mm\n", walk_path.filename().c_str(),
                segment.c_str(), value * 1000.0);
    // Soft tissue moves the markers a few millimetres on the skin, and the knee marker on the
    // thigh and the toe markers on the foot move with the joints they sit near: up to 9 mm. The
    // torso is not rigid at all: the acromion markers move with the shoulder girdle, which the
    // subjects held differently when standing (Gait2392: R.Acromium-L.Acromium 342 mm standing,
    // 419 mm walking; Rajagopal: R.Shoulder-L.Shoulder 283 mm, 344 mm): 28-38 mm.
    EXPECT_GT(value, 0.1 * kMillimetre) << segment;
    EXPECT_LT(value, (segment == "Torso" ? 45 : 10) * kMillimetre) << segment;
  }
  // Left and right swapped: the thigh layouts no longer explain the frames (the test can fail).
  std::map<std::string, std::string> swap;
  for (const auto& segment : model.segments) {
    if (segment.name != "R.Thigh" && segment.name != "L.Thigh") continue;
    for (const auto& m : segment.markers) {
      std::string other = m.name;
      other[0] = other[0] == 'R' ? 'L' : 'R';
      swap[m.name] = other;
    }
  }
  const auto swapped = walk_fit_rms(model, walk, swap);
  std::printf("%s: thighs with left and right swapped: %.1f mm, %.1f mm\n", walk_path.filename().c_str(),
              swapped.at("R.Thigh") * 1000.0, swapped.at("L.Thigh") * 1000.0);
  EXPECT_GT(swapped.at("R.Thigh"), 3 * rms.at("R.Thigh"));
}

TEST(SubjectModel, Gait2392LayoutsExplainWalk1) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  PANOPTES_REQUIRE_SHARED(test::gait2392_walk());
  expect_layouts_explain_walk(model_of("gait2392", test::gait2392_static()), test::gait2392_walk());
}

TEST(SubjectModel, RajagopalLayoutsExplainTheWalk) {
  PANOPTES_REQUIRE_SHARED(test::rajagopal_static());
  expect_layouts_explain_walk(model_of("rajagopal", test::rajagopal_static()), test::rajagopal_walk());
}

TEST(SubjectModel, FileRoundTripKeepsTheModelToTheMicrometre) {
  PANOPTES_REQUIRE_SHARED(test::gait2392_static());
  const SubjectModel model = model_of("gait2392", test::gait2392_static());
  const auto path = test::scratch_file("subject.yaml");
  save_subject_model(model, path);
  const SubjectModel back = load_subject_model(path);
  ASSERT_EQ(back.segments.size(), model.segments.size());
  EXPECT_EQ(back.subject, "s1");
  EXPECT_EQ(back.flags.size(), model.flags.size());
  EXPECT_EQ(back.flags[0].kind, model.flags[0].kind);
  EXPECT_EQ(back.joints.size(), model.joints.size());
  EXPECT_EQ(back.sticks, model.sticks);
  for (std::size_t s = 0; s < model.segments.size(); ++s) {
    const auto& a = model.segments[s];
    const auto& b = back.segments[s];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.parent, b.parent);
    EXPECT_EQ(a.has_pose, b.has_pose);
    ASSERT_EQ(a.markers.size(), b.markers.size());
    for (std::size_t m = 0; m < a.markers.size(); ++m)
      EXPECT_LT((a.markers[m].position_m - b.markers[m].position_m).norm(), 1e-6) << a.markers[m].name;
    ASSERT_EQ(a.distances.size(), b.distances.size());
    for (std::size_t d = 0; d < a.distances.size(); ++d)
      EXPECT_NEAR(a.distances[d].tolerance_m, b.distances[d].tolerance_m, 1e-6);
  }
}

}  // namespace
}  // namespace panoptes::labelling
