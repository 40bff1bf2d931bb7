// SPDX-License-Identifier: Apache-2.0
// FrameOutputBuilder over a real offline run: frame numbers count, every defined body is listed
// (tracked ones with the published pose, bit for bit), loose markers are unlabelled and the
// body markers are labelled with small mean errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/session/estimator_session.h"
#include "panoptes/session/frame_output.h"
#include "panoptes/simulator.h"
#include "scene_frames.h"

namespace panoptes::session {
namespace {

using testing::simulate;

TEST(FrameOutput, ListsEveryBodyAndLabelsBodyMarkersInARealRun) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/clients.yaml");
  const std::vector<FeatureFrame> frames = simulate(scene, 3.0);

  EstimatorConfig config;
  EstimatorSession session(config);
  session.tracker().set_calibration(scene.calibration());
  std::vector<BodyDefinition> bodies = scene.body_definitions();
  bodies.push_back({"absent", {{0, 0, 0}, {0.3, 0, 0}, {0, 0.31, 0}, {0.1, 0.1, 0.2}}, BodyKind::kPassive});
  session.tracker().set_bodies(bodies);

  FrameOutputBuilder builder;
  std::uint64_t processed = 0;
  std::size_t labelled = 0, unlabelled = 0;
  double worst_error = 0.0;
  for (const FeatureFrame& frame : frames) {
    if (session.process(frame) != estimator::FrameOutcome::kProcessed) continue;
    const auto poses = session.current_poses();
    const auto out = builder.build(session.tracker(), frame, {}, poses, session.tracker().current_tracks());
    ASSERT_EQ(out.frame_number, ++processed);
    EXPECT_EQ(out.stamp_ns, frame.stamp_ns);
    ASSERT_EQ(out.bodies.size(), 3u);
    EXPECT_EQ(out.bodies[2].name, "absent");
    EXPECT_FALSE(out.bodies[2].tracking_valid);
    EXPECT_EQ(out.bodies[2].id, 3);
    for (const auto& body : out.bodies) {
      if (!body.tracking_valid) continue;
      const auto it =
          std::find_if(poses.begin(), poses.end(), [&](const PoseRecord& p) { return p.body == body.name; });
      ASSERT_NE(it, poses.end());
      EXPECT_EQ(body.pose.p, it->p) << "the published pose, bit for bit";
      EXPECT_EQ(body.pose.q, it->q);
      worst_error = std::max(worst_error, body.mean_marker_error_m);
    }
    if (frame.stamp_ns - frames.front().stamp_ns < 1'000'000'000) continue;  // warm-up
    for (const auto& marker : out.markers) (marker.body.empty() ? unlabelled : labelled) += 1;
  }
  ASSERT_GT(processed, 1000u);
  // Nine body markers and two loose ones: most tracks are labelled, about 2 in 11 are not.
  const double unlabelled_share =
      static_cast<double>(unlabelled) / static_cast<double>(labelled + unlabelled);
  EXPECT_GT(unlabelled_share, 0.12);
  EXPECT_LT(unlabelled_share, 0.25);
  EXPECT_LT(worst_error, 0.005) << "mean marker error of a tracked body, m";
}

// With smoothing the published poses lag the frame; markers are still labelled with the filter's
// poses at the frame (issue 16).
TEST(FrameOutput, SmoothedPosesLagTheFrameAndMarkersAreStillLabelled) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/clients.yaml");
  const std::vector<FeatureFrame> frames = simulate(scene, 2.0);
  double share[2] = {0, 0};
  for (int smoothed = 0; smoothed < 2; ++smoothed) {
    EstimatorConfig config;
    const TimeNs lag_ns = smoothed ? 20'000'000 : 0;
    config.tracker.bodies.smoothing_ns = lag_ns;
    EstimatorSession session(config);
    session.tracker().set_calibration(scene.calibration());
    session.tracker().set_bodies(scene.body_definitions());
    FrameOutputBuilder builder;
    std::size_t labelled = 0, markers = 0, poses_seen = 0;
    for (const FeatureFrame& frame : frames) {
      if (session.process(frame) != estimator::FrameOutcome::kProcessed) continue;
      const auto poses = session.current_poses();
      const auto out = builder.build(session.tracker(), frame, {}, poses, session.tracker().current_tracks());
      for (const auto& pose : poses) EXPECT_EQ(pose.stamp_ns, frame.stamp_ns - lag_ns);
      poses_seen += poses.size();
      if (frame.stamp_ns - frames.front().stamp_ns < 1'000'000'000) continue;  // warm-up
      for (const auto& marker : out.markers) {
        ++markers;
        labelled += marker.body.empty() ? 0 : 1;
      }
    }
    ASSERT_GT(poses_seen, 100u);
    share[smoothed] = static_cast<double>(labelled) / static_cast<double>(markers);
  }
  std::printf("labelled share: %.4f without smoothing, %.4f with 20 ms\n", share[0], share[1]);
  EXPECT_GT(share[0], 0.7);
  EXPECT_GE(share[1], share[0] - 0.005);
}

}  // namespace
}  // namespace panoptes::session
