// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "panoptes/estimator/evaluation.h"
#include "panoptes/simulator.h"

namespace panoptes::estimator {
namespace {

const char* kScene = R"(
seed: 1
duration: 3.0
cameras:
  - id: cam0
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    look_at: {eye: [3, 0, 1], target: [0, 0, 1]}
    rate: 100
markers:
  - name: a
    path: {type: static, position: [0, 0, 1]}
  - name: b
    path: {type: static, position: [0.5, 0, 1]}
)";

TEST(Evaluation, MeasuresErrorCoverageAndIdSwitches) {
  const Scene scene = Scene::from_yaml_string(kScene);
  EvaluationOptions options;
  options.epoch_ns = 1000;
  options.warmup_ns = 0;
  std::vector<TrackRecord> tracks;
  for (int k = 0; k < 100; ++k) {
    const TimeNs stamp = options.epoch_ns + k * 10'000'000LL;
    TrackRecord a;
    a.stamp_ns = stamp;
    a.id = k < 50 ? 1 : 7;               // one identity switch at k = 50
    a.p = Eigen::Vector3d(0.001, 0, 1);  // 1 mm off
    tracks.push_back(a);
    if (k % 2 == 0) {  // b tracked half of the time, exactly
      TrackRecord b;
      b.stamp_ns = stamp;
      b.id = 2;
      b.p = Eigen::Vector3d(0.5, 0, 1);
      tracks.push_back(b);
    }
    TrackRecord ghost;  // far from every marker
    ghost.stamp_ns = stamp;
    ghost.id = 3;
    ghost.p = Eigen::Vector3d(2, 2, 2);
    tracks.push_back(ghost);
  }
  const auto result = evaluate(scene, tracks, options);
  ASSERT_EQ(result.markers.size(), 2u);
  EXPECT_NEAR(result.markers[0].rmse_m, 0.001, 1e-9);
  EXPECT_DOUBLE_EQ(result.markers[0].tracked_fraction(), 1.0);
  ASSERT_EQ(result.markers[0].id_switches.size(), 1u);
  EXPECT_EQ(result.markers[0].id_switches[0].from_id, 1);
  EXPECT_EQ(result.markers[0].id_switches[0].to_id, 7);
  EXPECT_NEAR(result.markers[1].tracked_fraction(), 0.5, 1e-12);
  EXPECT_NEAR(result.markers[1].rmse_m, 0.0, 1e-12);
  ASSERT_EQ(result.false_tracks.size(), 1u);
  EXPECT_EQ(result.false_tracks[0], 3);
  EXPECT_EQ(result.id_switch_count, 1u);
  EXPECT_NE(result.to_json().find("\"id_switches\""), std::string::npos);
}

}  // namespace
}  // namespace panoptes::estimator
