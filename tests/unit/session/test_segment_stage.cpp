// SPDX-License-Identifier: Apache-2.0
// Live segment poses (issue 33 item 4; docs/marker_sets.md, "Segment poses live"): the Gait2392
// subject01 model, its static trial's markers moved rigidly and named in a frame's output; each
// segment's pose is the static pose moved alike, its described markers land on the named ones, and
// segments without enough markers, other subjects' names and segments without an id are handled.
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "../shared_data.h"
#include "panoptes/errors.h"
#include "panoptes/estimator_app/frame_messages.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"
#include "panoptes/session/segment_stage.h"

namespace panoptes::session {
namespace {

namespace fs = std::filesystem;

struct Trial {
  labelling::SubjectModel model;
  labelling::MarkerSamples samples;
};

Trial gait2392_static(const fs::path& static_trial) {
  Trial trial;
  trial.samples = labelling::load_marker_samples(static_trial);
  trial.model = labelling::build_subject_model(
      labelling::load_marker_set(fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "markersets" / "gait2392.yaml"),
      trial.samples, "s1");
  return trial;
}

// Frame `frame` of the trial's tracked markers moved by T, named as `subject`'s, plus one unnamed.
FrameOutput named_frame(const Trial& trial, std::size_t frame, const RigidTransform& T,
                        const std::string& subject) {
  FrameOutput out;
  out.stamp_ns = 123'456'789;
  std::map<std::string, bool> tracked;
  for (const auto& segment : trial.model.segments) {
    for (const auto& name : segment.tracked_marker_names()) tracked[name] = true;
  }
  for (std::size_t p = 0; p < trial.samples.point_count(); ++p) {
    if (!tracked.count(trial.samples.names[p]) || !trial.samples.is_valid(frame, p)) continue;
    MarkerOutput marker;
    marker.track.id = static_cast<std::int64_t>(p) + 1;
    marker.track.p = T.apply(trial.samples.position(frame, p));
    marker.subject = subject;
    marker.name = trial.samples.names[p];
    out.markers.push_back(marker);
  }
  MarkerOutput ghost;
  ghost.track.id = 999;
  ghost.track.p = {5.0, 5.0, 5.0};
  out.markers.push_back(ghost);
  return out;
}

std::map<std::string, int> ids_of(const SegmentStage& stage, int first) {
  std::map<std::string, int> ids;
  for (const auto& description : stage.descriptions()) ids.emplace(description.name, first++);
  return ids;
}

TEST(SegmentStage, PosesMoveWithTheMarkersAndTheirDescriptionsLandOnThem) {
  const fs::path static_trial = test::shared_data("static/gait2392_subject01_static.trc");
  PANOPTES_REQUIRE_SHARED(static_trial);
  const Trial trial = gait2392_static(static_trial);
  const SegmentStage stage({trial.model}, labelling::KinematicsOptions{});
  // Gait2392: 13 segments, 9 of them with a pose (the arms have two markers and no joint centre).
  ASSERT_EQ(stage.descriptions().size(), 9U);
  EXPECT_EQ(stage.descriptions().front().name, "s1/" + trial.model.segments.front().name);
  const std::map<std::string, int> ids = ids_of(stage, 5);

  RigidTransform T;  // the OpenSim trial's y-up world turned into a z-up one and moved
  T.q = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()) *
        Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX());
  T.t = {1.5, -0.75, 0.02};
  FrameOutput still = named_frame(trial, 0, RigidTransform{}, "s1");
  FrameOutput moved = named_frame(trial, 0, T, "s1");
  stage.append(still, ids);
  stage.append(moved, ids);
  ASSERT_EQ(moved.bodies.size(), 9U);
  std::size_t posed = 0;
  for (std::size_t b = 0; b < moved.bodies.size(); ++b) {
    const BodyOutput& body = moved.bodies[b];
    const BodyOutput& before = still.bodies[b];
    EXPECT_TRUE(body.segment);
    EXPECT_EQ(body.id, ids.at(body.name));
    EXPECT_EQ(body.pose.stamp_ns, moved.stamp_ns);
    EXPECT_EQ(body.tracking_valid, before.tracking_valid) << body.name;
    if (!body.tracking_valid) continue;
    ++posed;
    const Eigen::Quaterniond q(body.pose.q[3], body.pose.q[0], body.pose.q[1], body.pose.q[2]);
    const Eigen::Quaterniond q_before(before.pose.q[3], before.pose.q[0], before.pose.q[1], before.pose.q[2]);
    EXPECT_LT((body.pose.p - T.apply(before.pose.p)).norm(), 1e-9) << body.name;
    EXPECT_LT(q.angularDistance(T.q * q_before), 1e-9) << body.name;
    EXPECT_GT(body.pose.quality, 0.0);
    EXPECT_LE(body.pose.quality, 1.0);
    EXPECT_LT(body.mean_marker_error_m, 0.005) << body.name;  // one static frame against the mean layout
    // The described markers, posed, land on the named markers of the frame (in layout order).
    const BodyDefinition& description = stage.descriptions()[b];
    ASSERT_EQ(description.name, body.name);
    const labelling::SegmentLayout* layout = trial.model.segment(body.name.substr(3));
    ASSERT_NE(layout, nullptr);
    const std::vector<std::string> names = layout->tracked_marker_names();
    ASSERT_EQ(description.markers.size(), names.size());
    for (std::size_t m = 0; m < names.size(); ++m) {
      for (const auto& marker : moved.markers) {
        if (marker.name == names[m]) {
          EXPECT_LT((q * description.markers[m] + body.pose.p - marker.track.p).norm(), 0.01) << names[m];
        }
      }
    }
  }
  EXPECT_EQ(posed, 9U);  // every one posed in the static pose

  // The tree: the root has no parent, every other segment's parent is a segment of the subject.
  std::size_t roots = 0;
  for (const auto& body : moved.bodies) {
    if (body.parent.empty()) {
      ++roots;
    } else {
      EXPECT_TRUE(ids.count(body.parent)) << body.name << "'s parent " << body.parent;
    }
  }
  EXPECT_EQ(roots, 1U);
}

TEST(SegmentStage, FewNamesOtherSubjectsAndUnknownIdsGiveNoPose) {
  const fs::path static_trial = test::shared_data("static/gait2392_subject01_static.trc");
  PANOPTES_REQUIRE_SHARED(static_trial);
  const Trial trial = gait2392_static(static_trial);
  const SegmentStage stage({trial.model}, labelling::KinematicsOptions{});
  const std::map<std::string, int> ids = ids_of(stage, 1);

  FrameOutput other = named_frame(trial, 0, RigidTransform{}, "s2");  // names of another subject
  stage.append(other, ids);
  ASSERT_EQ(other.bodies.size(), 9U);  // every segment listed, none tracked
  for (const auto& body : other.bodies) EXPECT_FALSE(body.tracking_valid) << body.name;

  // The pelvis with two of its three markers: no pose (no parent to place a joint centre).
  FrameOutput sparse = named_frame(trial, 0, RigidTransform{}, "s1");
  const std::vector<std::string> pelvis = trial.model.segment("Pelvis")->tracked_marker_names();
  ASSERT_EQ(pelvis.size(), 3U);
  std::vector<MarkerOutput> kept;
  for (const auto& marker : sparse.markers) {
    if (marker.name != pelvis[0]) kept.push_back(marker);
  }
  sparse.markers = kept;
  std::map<std::string, int> without_head = ids;
  without_head.erase("s1/Head");
  stage.append(sparse, without_head);
  EXPECT_EQ(sparse.bodies.size(), 8U);  // the head has no id: left out
  for (const auto& body : sparse.bodies) {
    EXPECT_NE(body.name, "s1/Head");
    if (body.name == "s1/Pelvis") {
      EXPECT_FALSE(body.tracking_valid);
    }
    if (body.name == "s1/R.Thigh") {
      EXPECT_TRUE(body.tracking_valid);
    }
  }
}

TEST(SegmentStage, AxesThatAreNotOrthogonalAreRefused) {
  const fs::path static_trial = test::shared_data("static/gait2392_subject01_static.trc");
  PANOPTES_REQUIRE_SHARED(static_trial);
  const Trial trial = gait2392_static(static_trial);
  labelling::KinematicsOptions options;
  options.forward = *labelling::axis_from_name("-y");
  EXPECT_THROW(SegmentStage({trial.model}, options), InputError);
  EXPECT_FALSE(labelling::axis_from_name("w").has_value());
  EXPECT_EQ(*labelling::axis_from_name("Z"), Eigen::Vector3d::UnitZ());
}

// BodyDescriptions lists the segments after the bodies and rigs, kind "segment", ids going on; a
// segment named like a body is left out (a name twice would make the set malformed for clients).
TEST(SegmentStage, DescriptionsListSegmentsAfterBodiesAndRigs) {
  const std::vector<BodyDefinition> bodies{
      {"head", {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}}, BodyKind::kPassive}};
  const std::vector<BodyDefinition> rigs{{"rig_a", {}, BodyKind::kPassive}};
  const std::vector<BodyDefinition> segments{
      {"s1/Pelvis", {{0.1, 0, 0}, {-0.1, 0, 0}, {0, 0, -0.1}}, BodyKind::kPassive},
      {"head", {{0, 0, 0}}, BodyKind::kPassive},
      {"s1/R.Thigh", {{0, -0.2, 0}, {0.05, -0.3, 0}, {0, -0.4, 0.05}}, BodyKind::kPassive}};
  const msg::BodyDescriptions message =
      estimator_app::to_descriptions_message(bodies, 1, "bodies.yaml", 5, rigs, segments);
  ASSERT_EQ(message.bodies().size(), 4U);
  const std::vector<std::string> kinds{"passive", "rig", "segment", "segment"};
  const std::vector<std::string> names{"head", "rig_a", "s1/Pelvis", "s1/R.Thigh"};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(message.bodies()[i].name(), names[i]);
    EXPECT_EQ(message.bodies()[i].kind(), kinds[i]);
    EXPECT_EQ(message.bodies()[i].id(), static_cast<int>(i) + 1);
  }
  EXPECT_EQ(message.bodies()[3].markers().size(), 3U);
  EXPECT_EQ(message.bodies()[3].markers()[1].position()[1], -0.3);
}

}  // namespace
}  // namespace panoptes::session
