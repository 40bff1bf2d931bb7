// SPDX-License-Identifier: Apache-2.0
// Marker labels: tracks at a body's predicted markers carry its label; loose markers stay
// unlabelled; one track labels one body marker; the mean marker error is the mean distance.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "panoptes/estimator/marker_labels.h"

namespace panoptes::estimator {
namespace {

BodyDefinition triangle(const char* name) {
  return {name, {{0, 0, 0}, {0.2, 0, 0}, {0.05, 0.15, 0}}, BodyKind::kPassive};
}

PoseRecord pose_of(const char* body, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  PoseRecord pose;
  pose.body = body;
  pose.p = p;
  pose.q = Eigen::Vector4d(q.x(), q.y(), q.z(), q.w());
  return pose;
}

TrackRecord track_at(std::int64_t id, const Eigen::Vector3d& p) {
  TrackRecord track;
  track.id = id;
  track.p = p;
  return track;
}

TEST(MarkerLabels, LabelsTheTracksAtABodysMarkersAndLeavesLooseMarkersUnlabelled) {
  const std::vector<BodyDefinition> bodies = {triangle("a"), triangle("b")};
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.3, 1).normalized()));
  const Eigen::Vector3d origin(1.0, -0.5, 1.2);
  std::vector<TrackRecord> tracks;
  // Body a's markers 2, 0 and 1 with 1, 2 and 3 mm errors; a loose marker; body b is not tracked.
  const double errors_m[3] = {0.002, 0.003, 0.001};
  for (int m : {2, 0, 1}) {
    const Eigen::Vector3d at = origin + q * bodies[0].markers[static_cast<std::size_t>(m)];
    tracks.push_back(track_at(10 + m, at + Eigen::Vector3d(errors_m[m], 0, 0)));
  }
  tracks.push_back(track_at(99, Eigen::Vector3d(0, 0, 1)));

  const auto result = label_markers(tracks, {pose_of("a", origin, q)}, bodies);
  ASSERT_EQ(result.labels.size(), 4u);
  EXPECT_EQ(result.labels[0].body, 0);
  EXPECT_EQ(result.labels[0].marker, 2);
  EXPECT_EQ(result.labels[1].marker, 0);
  EXPECT_EQ(result.labels[2].marker, 1);
  EXPECT_EQ(result.labels[3].body, -1) << "a loose marker is unlabelled";
  EXPECT_EQ(result.labelled_markers[0], 3);
  EXPECT_EQ(result.labelled_markers[1], 0) << "an untracked body labels nothing";
  EXPECT_NEAR(result.mean_error_m[0], 0.002, 1e-12);
  EXPECT_EQ(result.mean_error_m[1], 0.0);
}

TEST(MarkerLabels, ATrackBeyondTheDistanceOrClaimedTwiceIsLabelledOnce) {
  const std::vector<BodyDefinition> bodies = {triangle("a")};
  const PoseRecord pose = pose_of("a", Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  // Two tracks near marker 0 (the nearer wins), one 2 cm from marker 1 (too far).
  const std::vector<TrackRecord> tracks = {track_at(1, {0.004, 0, 0}), track_at(2, {0.001, 0, 0}),
                                           track_at(3, {0.2, 0.02, 0})};
  const auto result = label_markers(tracks, {pose}, bodies, 0.01);
  EXPECT_EQ(result.labels[0].body, -1);
  EXPECT_EQ(result.labels[1].body, 0);
  EXPECT_EQ(result.labels[1].marker, 0);
  EXPECT_EQ(result.labels[2].body, -1) << "2 cm from the marker is beyond 1 cm";
  EXPECT_EQ(result.labelled_markers[0], 1);
}

TEST(MarkerLabels, NothingToLabelGivesEmptyLabels) {
  const std::vector<BodyDefinition> bodies = {triangle("a")};
  EXPECT_TRUE(label_markers({}, {}, bodies).labels.empty());
  const auto result = label_markers({track_at(1, {0, 0, 0})}, {}, bodies);
  EXPECT_EQ(result.labels[0].body, -1);
  const auto unknown =
      label_markers({track_at(1, {0, 0, 0})},
                    {pose_of("zz", Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity())}, bodies);
  EXPECT_EQ(unknown.labels[0].body, -1) << "a pose of an undefined body is ignored";
}

}  // namespace
}  // namespace panoptes::estimator
