// SPDX-License-Identifier: Apache-2.0
// The planner's prediction of the tracker's error (predict_tracking, docs/planner.md,
// "Validation against the tracker"): the one-view coasting term, the triangulation term and the
// two-view correspondence ambiguity, each on a rig where the answer is known.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "panoptes/planner/metric.h"

namespace panoptes::planner {
namespace {

// The validation room's lens (deploy/planner/walk_room.yaml): 1280 × 1024 px, f = 1000 px.
Lens test_lens() {
  return {"f1000", CameraIntrinsics{1280, 1024, 1000.0, 1000.0, 639.5, 511.5, {}}, 0.3, 20.0};
}

// `n` cameras on a horizontal circle of radius 4 m at 2 m height, aimed at the middle of a
// 0.4 m cube around (0, 0, 1).
std::vector<PlannedCamera> circle(int n) {
  std::vector<PlannedCamera> cameras;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * std::numbers::pi * k / n;
    cameras.push_back(make_camera("c" + std::to_string(k), test_lens(),
                                  Eigen::Vector3d(4.0 * std::cos(a), 4.0 * std::sin(a), 2.0),
                                  Eigen::Vector3d(0.0, 0.0, 1.0)));
  }
  return cameras;
}

SampleSet cube_samples() {
  Room room;
  room.volume = {Eigen::Vector3d(-0.2, -0.2, 0.8), Eigen::Vector3d(0.2, 0.2, 1.2)};
  OccluderModel none;
  none.planes = 0;  // every camera sees every point: the classes are exact
  return draw_samples(room, none, 200, 16, 3);
}

TrackerModel walker(int markers) {
  TrackerModel model;
  model.subject_markers = markers;
  model.subject_size = Eigen::Vector3d(0.7, 0.6, 1.5);
  return model;
}

TEST(TrackingPrediction, OneCameraCoastsAtHalfThePublicationLimit) {
  const auto cameras = circle(1);
  const TrackingPrediction t = predict_tracking(cameras, cube_samples(), {}, MetricOptions{}, walker(41));
  EXPECT_NEAR(t.one_view_share, 1.0, 1e-12);
  EXPECT_NEAR(t.rmse_m, 0.5 * TrackerModel{}.publish_max_sigma_m, 1e-12);  // sqrt(σ_max² / 4)
  EXPECT_EQ(t.confirmable_share, 0.0);
}

TEST(TrackingPrediction, TwoViewsAreAmbiguousOnADenseSubjectAndThreeViewsAreNot) {
  const SampleSet samples = cube_samples();
  const auto two = std::vector<PlannedCamera>{circle(4)[0], circle(4)[1]};  // 90 degrees apart
  const TrackingPrediction sparse = predict_tracking(two, samples, {}, MetricOptions{}, walker(0));
  EXPECT_NEAR(sparse.two_view_share, 1.0, 1e-12);
  EXPECT_EQ(sparse.ambiguous_share, 0.0);  // no other marker: nothing to confuse
  EXPECT_NEAR(sparse.confirmable_share, 1.0, 1e-12);
  EXPECT_LT(sparse.rmse_m, 1e-3);  // triangulation at 0.1 px over ~4 m: sub-millimetre
  EXPECT_DOUBLE_EQ(sparse.rmse_with_ambiguity_m, sparse.rmse_m);

  const TrackingPrediction dense = predict_tracking(two, samples, {}, MetricOptions{}, walker(41));
  EXPECT_GT(dense.ambiguous_share, 0.3);
  EXPECT_LT(dense.confirmable_share, 0.7);
  EXPECT_DOUBLE_EQ(dense.rmse_m, sparse.rmse_m);  // ambiguity is charged only to the second figure
  EXPECT_GT(dense.rmse_with_ambiguity_m, 3.0 * dense.rmse_m);
  const TrackingPrediction denser = predict_tracking(two, samples, {}, MetricOptions{}, walker(100));
  EXPECT_GT(denser.ambiguous_share, dense.ambiguous_share);
  TrackerModel tight = walker(41);
  tight.epipolar_px = 0.5;
  EXPECT_LT(predict_tracking(two, samples, {}, MetricOptions{}, tight).ambiguous_share,
            dense.ambiguous_share);

  const TrackingPrediction three = predict_tracking(circle(3), samples, {}, MetricOptions{}, walker(41));
  EXPECT_EQ(three.two_view_share, 0.0);
  EXPECT_NEAR(three.confirmable_share, 1.0, 1e-12);
  EXPECT_LT(three.rmse_m, sparse.rmse_m);

  // Two cameras 3 degrees apart see from one direction: one view (min_triangulation_deg).
  const auto close = std::vector<PlannedCamera>{circle(120)[0], circle(120)[1]};
  EXPECT_NEAR(predict_tracking(close, samples, {}, MetricOptions{}, walker(41)).one_view_share, 1.0, 1e-12);
}

TEST(TrackingPrediction, SelfOcclusionMovesTimeToOneViewAndRaisesTheError) {
  Room room;
  room.volume = {Eigen::Vector3d(-0.2, -0.2, 0.8), Eigen::Vector3d(0.2, 0.2, 1.2)};
  OccluderModel body;  // sideways-facing markers seen up to 100 degrees off their normal
  body.min_angle_deg = 45;
  body.max_angle_deg = 135;
  body.facing_angle_deg = 100;
  const SampleSet samples = draw_samples(room, body, 200, 16, 3);
  const TrackingPrediction three = predict_tracking(circle(3), samples, {}, MetricOptions{}, walker(41));
  const TrackingPrediction eight = predict_tracking(circle(8), samples, {}, MetricOptions{}, walker(41));
  EXPECT_GT(three.one_view_share, 0.05);
  EXPECT_LT(eight.one_view_share, 0.01);
  EXPECT_GT(three.rmse_m, 3.0 * eight.rmse_m);
}

}  // namespace
}  // namespace panoptes::planner
