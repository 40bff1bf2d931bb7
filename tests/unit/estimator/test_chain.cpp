// SPDX-License-Identifier: Apache-2.0
// Articulated chains (issue 21): the kinematic model, the EKF's Jacobian, identification among
// reflections, grab gestures and the acceptance scene (chain_fixtures.h).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <optional>
#include <random>
#include <vector>

#include "chain_fixtures.h"
#include "panoptes/estimator/chain.h"

namespace panoptes::estimator {
namespace {

TEST(Chain, ShapeFollowsTheLinksAndTheBends) {
  const ChainDefinition finger = test_finger();
  JointVector angles = JointVector::Zero();
  angles(0) = M_PI / 2;
  const ChainShape shape = chain_shape(finger, angles);
  ASSERT_EQ(shape.marker_count, 4);
  EXPECT_NEAR((shape.markers[1] - Eigen::Vector3d(0.045, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((shape.markers[2] - Eigen::Vector3d(0.045, 0.030, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((shape.markers[3] - Eigen::Vector3d(0.045, 0.055, 0)).norm(), 0.0, 1e-12);
  // The tip offset turns with the last link: x along it, y towards the bend (here -x).
  EXPECT_NEAR((shape.tip - Eigen::Vector3d(0.041, 0.067, 0)).norm(), 0.0, 1e-12);
}

TEST(Chain, DefinitionErrorsNameTheField) {
  ChainDefinition finger = test_finger();
  EXPECT_FALSE(chain_definition_error(finger).has_value());
  finger.link_lengths_m[1] = 0.0;
  EXPECT_NE(chain_definition_error(finger).value_or("").find("links[1]"), std::string::npos);
  finger = test_finger();
  finger.joint_limits[0] = {1.0, 0.5};
  EXPECT_NE(chain_definition_error(finger).value_or("").find("joint_limits[0]"), std::string::npos);
  finger = test_finger();
  finger.joint_limits.pop_back();
  EXPECT_NE(chain_definition_error(finger).value_or("").find("joint_limits"), std::string::npos);
  finger = test_finger();
  finger.link_lengths_m = {0.04};
  EXPECT_TRUE(chain_definition_error(finger).has_value());
}

TEST(Chain, ProjectionJacobianMatchesNumericalDerivative) {
  const ChainDefinition finger = test_finger();
  const CameraModel camera = make_ring_cameras(4, 1.9, 1.6, true)[1];
  const FingerScene scene(5.0, 1);
  ChainState state;
  const FingerTruth truth = scene.truth(1.1);
  state.p = truth.base.t;
  state.q = truth.base.q;
  state.angles << 0.4, 0.9, 0.0;
  state.P = chain_prior(test_chain_prior(), finger.joint_count());
  for (int marker = 0; marker < finger.marker_count(); ++marker) {
    const auto projection = project_chain_marker(state, finger, marker, camera, 0.1);
    ASSERT_TRUE(projection.has_value());
    for (int column = 0; column < kChainStateSize; ++column) {
      ChainVector dx = ChainVector::Zero();
      const double step = 1e-6;
      dx(column) = step;
      ChainState plus = state, minus = state;
      inject(plus, dx);
      inject(minus, -dx);
      const Eigen::Vector2d numeric = (project_chain_marker(plus, finger, marker, camera, 0.1)->pixel -
                                       project_chain_marker(minus, finger, marker, camera, 0.1)->pixel) /
                                      (2 * step);
      EXPECT_NEAR((numeric - projection->H.col(column)).norm(), 0.0, 1e-3 * (1.0 + numeric.norm()))
          << "marker " << marker << " column " << column;
    }
  }
}

std::vector<Eigen::Vector3d> noisy(std::vector<Eigen::Vector3d> points, double sigma_m, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, sigma_m);
  for (Eigen::Vector3d& point : points) point += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  return points;
}

TEST(ChainIdentification, FindsTheFingerAmongReflections) {
  const ChainDefinition finger = test_finger();
  const FingerScene scene(10.0, 2);
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> spread(-0.1, 0.1);
  int identified = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const FingerTruth truth = scene.truth(0.2 * trial);
    // Reflections first, so the finger's indices are not simply 0..3.
    std::vector<Eigen::Vector3d> points;
    for (int r = 0; r < 8; ++r)
      points.push_back(truth.base.t + Eigen::Vector3d(spread(rng), spread(rng), spread(rng)));
    for (const Eigen::Vector3d& marker : noisy(FingerScene::markers(finger, truth), 0.0003, rng))
      points.push_back(marker);
    const ChainIdentification result = identify_chain(finger, points, ChainIdentificationOptions{});
    // Random reflections may by chance complete a second path: then "ambiguous", never a guess.
    if (result.status != ChainIdentificationStatus::kIdentified) {
      EXPECT_EQ(result.status, ChainIdentificationStatus::kAmbiguous);
      continue;
    }
    ++identified;
    ASSERT_EQ(result.point_indices.size(), 4U);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(result.point_indices[k], 8 + k) << "trial " << trial;
    // 0.3 mm noise on 25-45 mm links: σ ≈ 0.02 rad per angle.
    EXPECT_NEAR(result.angles(0), truth.angles(0), 0.08);
    EXPECT_NEAR(result.angles(1), truth.angles(1), 0.08);
  }
  EXPECT_GE(identified, 45);
}

TEST(ChainIdentification, ReportsAmbiguityAndUsesThePrediction) {
  const ChainDefinition finger = test_finger();
  const FingerScene scene(10.0, 3);
  const FingerTruth truth = scene.truth(2.0);
  std::vector<Eigen::Vector3d> points = FingerScene::markers(finger, truth);
  // A reflection where the tip marker would be with the last joint 1 rad further bent: a second
  // chain that passes every check.
  FingerTruth other = truth;
  other.angles(1) = truth.angles(1) + 1.0 <= 1.8 ? truth.angles(1) + 1.0 : truth.angles(1) - 1.0;
  points.push_back(FingerScene::markers(finger, other)[3]);
  const ChainIdentification blind = identify_chain(finger, points, ChainIdentificationOptions{});
  EXPECT_EQ(blind.status, ChainIdentificationStatus::kAmbiguous);
  EXPECT_TRUE(blind.point_indices.empty());
  // With the filter's prediction the reflection falls outside the gate.
  const std::vector<Eigen::Vector3d> predicted = FingerScene::markers(finger, truth);
  const ChainIdentification guided = identify_chain(finger, points, ChainIdentificationOptions{}, &predicted);
  ASSERT_EQ(guided.status, ChainIdentificationStatus::kIdentified);
  EXPECT_EQ(guided.point_indices, (std::vector<int>{0, 1, 2, 3}));
  // A missing marker: not found.
  points.erase(points.begin() + 2);
  EXPECT_EQ(identify_chain(finger, points, ChainIdentificationOptions{}).status,
            ChainIdentificationStatus::kNotFound);
}

TEST(GrabDetector, HysteresisAndDwell) {
  GrabDetector detector(GrabOptions{});
  const Eigen::Vector3d tip(1, 2, 3);
  std::vector<GrabEvent> events;
  // Noise around the grab threshold once the finger is bent past it.
  const double bends[] = {0.3, 1.0, 1.55, 1.65, 1.59, 1.7, 1.7, 1.7, 1.2, 1.05, 0.95, 0.9, 0.9, 1.1, 0.9};
  TimeNs t = 0;
  for (const double bend : bends) {
    if (auto event = detector.observe(t, bend, tip)) events.push_back(*event);
    t += 10'000'000;
  }
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].kind, GrabEventKind::kGrab);
  EXPECT_EQ(events[0].stamp_ns, 50'000'000);  // the sustained crossing, not the flicker at 30 ms
  EXPECT_EQ(events[1].kind, GrabEventKind::kRelease);
  EXPECT_EQ(events[1].stamp_ns, 100'000'000);
  EXPECT_EQ(events[1].tip, tip);
}

struct FingerRunOptions {
  double duration_s = 120.0;
  unsigned seed = 2100;
  int occluded_marker = -1;  // hidden from every camera during [occlusion_start_s, +0.5 s)
  double occlusion_start_s = 0.0;
  double occlusion_s = 0.5;
};

struct FingerRunResult {
  double tip_rmse_m = 0.0;
  double angle_rmse_deg = 0.0;
  double predicted_tip_rmse_m = 0.0;  // 80 ms ahead
  double max_tip_error_m = 0.0;
  std::vector<GrabEvent> events;
  int ambiguous_markers = 0;
  int occluded_marker_updates_after = 0;  // updates of the occluded marker after it reappears
  double tip_rmse_after_occlusion_m = 0.0;
  bool identified = false;
};

FingerRunResult run_finger(const FingerScene& scene, const FingerRunOptions& options) {
  const ChainDefinition finger = test_finger();
  const std::vector<CameraModel> cameras = make_ring_cameras(4, 1.9, 1.6);
  std::mt19937 rng(options.seed);
  FingerRunResult result;
  // Identification from triangulated points (the finger with 0.2 mm noise, and the reflections).
  std::vector<Eigen::Vector3d> points = FingerScene::reflections();
  for (const Eigen::Vector3d& marker : noisy(FingerScene::markers(finger, scene.truth(0.0)), 0.0002, rng))
    points.push_back(marker);
  const ChainIdentification identification = identify_chain(finger, points, ChainIdentificationOptions{});
  result.identified = identification.status == ChainIdentificationStatus::kIdentified;
  if (!result.identified) return result;
  ChainFilter filter(finger, chain_state_from_identification(identification, 0, test_chain_prior(), 2),
                     ChainMotionNoise{}, ChainUpdateOptions{});
  GrabDetector detector(GrabOptions{});
  double tip2 = 0, angle2 = 0, predicted2 = 0, after2 = 0;
  int count = 0, predicted_count = 0, after_count = 0;
  const double occlusion_end = options.occlusion_start_s + options.occlusion_s;
  for (const SimFrame& frame : asynchronous_frames(4, 100.0, scene.duration_s())) {
    const double t = ns_to_seconds(frame.stamp_ns);
    std::vector<Eigen::Vector3d> visible = FingerScene::markers(finger, scene.truth(t));
    const bool occluded = options.occluded_marker >= 0 && t >= options.occlusion_start_s && t < occlusion_end;
    if (occluded) visible.erase(visible.begin() + options.occluded_marker);
    for (const Eigen::Vector3d& reflection : FingerScene::reflections()) visible.push_back(reflection);
    const auto blobs = observe(cameras[frame.camera], visible, 0.1, rng);
    const ChainFrameResult updated = filter.process(cameras[frame.camera], frame.stamp_ns, blobs);
    result.ambiguous_markers += updated.markers_ambiguous;
    if (options.occluded_marker >= 0 && t >= occlusion_end &&
        filter.last_update_ns(options.occluded_marker) == frame.stamp_ns)
      ++result.occluded_marker_updates_after;
    const ChainPose pose = chain_pose(filter.state(), finger);
    if (auto event = detector.observe(frame.stamp_ns, pose.angles(0) + pose.angles(1), pose.tip))
      result.events.push_back(*event);
    if (t < 0.5) continue;  // convergence from the identification's prior
    const FingerTruth truth = scene.truth(t);
    const double tip_error = (pose.tip - FingerScene::tip(finger, truth)).norm();
    result.max_tip_error_m = std::max(result.max_tip_error_m, tip_error);
    tip2 += tip_error * tip_error;
    angle2 += (pose.angles.head<2>() - truth.angles.head<2>()).squaredNorm() / 2.0;
    ++count;
    // From 0.1 s after the marker returns (two cameras must agree first), for 1 s.
    if (options.occluded_marker >= 0 && t >= occlusion_end + 0.1 && t < occlusion_end + 1.1) {
      after2 += tip_error * tip_error;
      ++after_count;
    }
    if (t + 0.08 < scene.duration_s()) {
      const ChainPose ahead = chain_pose(filter.state(), finger, 0.08);
      predicted2 += (ahead.tip - FingerScene::tip(finger, scene.truth(t + 0.08))).squaredNorm();
      ++predicted_count;
    }
  }
  result.tip_rmse_m = std::sqrt(tip2 / count);
  result.angle_rmse_deg = std::sqrt(angle2 / count) * 180.0 / M_PI;
  result.predicted_tip_rmse_m = std::sqrt(predicted2 / predicted_count);
  if (after_count > 0) result.tip_rmse_after_occlusion_m = std::sqrt(after2 / after_count);
  return result;
}

// Events must match the scene's transitions one to one, in order, each within its transition
// (plus the dwell and the filter's lag).
void expect_events_match(const FingerScene& scene, const std::vector<GrabEvent>& events) {
  const auto& transitions = scene.transitions();
  ASSERT_EQ(events.size(), transitions.size());
  for (std::size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(events[i].kind, transitions[i].bending ? GrabEventKind::kGrab : GrabEventKind::kRelease) << i;
    const double t = ns_to_seconds(events[i].stamp_ns);
    EXPECT_GT(t, transitions[i].start_s) << i;
    EXPECT_LT(t, transitions[i].start_s + FingerScene::transition_s() + 0.05) << i;
  }
}

TEST(ChainAcceptance, TwoMinutesOfGrabsWithReflections) {
  const FingerScene scene(120.0, 2101);
  const FingerRunResult result = run_finger(scene, FingerRunOptions{});
  ASSERT_TRUE(result.identified);
  std::cout << "tip RMSE " << result.tip_rmse_m * 1e3 << " mm, max " << result.max_tip_error_m * 1e3
            << " mm; joint-angle RMSE " << result.angle_rmse_deg << " deg; 80 ms prediction RMSE "
            << result.predicted_tip_rmse_m * 1e3 << " mm; events " << result.events.size() << " for "
            << scene.transitions().size() << " transitions; ambiguous marker gates "
            << result.ambiguous_markers << "\n";
  EXPECT_LE(result.tip_rmse_m, 0.0005);
  EXPECT_LE(result.angle_rmse_deg, 0.5);
  EXPECT_LE(result.predicted_tip_rmse_m, 0.004);
  EXPECT_GE(scene.transitions().size(), 60U);
  expect_events_match(scene, result.events);
}

TEST(ChainAcceptance, OneMarkerOccludedHalfASecondWhileBending) {
  const FingerScene scene(12.0, 2102);
  // Hide the tip marker from the start of the second transition (the release) for 0.5 s.
  FingerRunOptions options;
  options.duration_s = scene.duration_s();
  options.occluded_marker = 3;
  options.occlusion_start_s = scene.transitions().at(1).start_s;
  const FingerRunResult result = run_finger(scene, options);
  ASSERT_TRUE(result.identified);
  std::cout << "tip RMSE over the run " << result.tip_rmse_m * 1e3 << " mm, max "
            << result.max_tip_error_m * 1e3
            << " mm (the hidden joint is held while the finger moves); in the 1 s after the marker returns "
            << result.tip_rmse_after_occlusion_m * 1e3 << " mm\n";
  EXPECT_GT(result.occluded_marker_updates_after, 100);
  EXPECT_LE(result.tip_rmse_after_occlusion_m, 0.0005);
  expect_events_match(scene, result.events);
}

TEST(ChainTracker, AmbiguousThenTrackedThenLostAndFoundAgain) {
  const ChainDefinition finger = test_finger();
  const FingerScene scene(8.0, 2103);
  const std::vector<CameraModel> cameras = make_ring_cameras(4, 1.9, 1.6);
  std::mt19937 rng(2103);
  ChainTracker tracker({finger}, ChainTrackerOptions{});
  // At 0 s a reflection completes a second valid chain: reported, not forced.
  std::vector<Eigen::Vector3d> points = FingerScene::markers(finger, scene.truth(0.0));
  FingerTruth other = scene.truth(0.0);
  other.angles(1) += 1.0;
  points.push_back(FingerScene::markers(finger, other)[3]);
  tracker.identify(0, points);
  ASSERT_EQ(tracker.outputs().at(0).status, ChainStatus::kAmbiguous);
  EXPECT_FALSE(tracker.outputs().at(0).marker_valid.at(0));
  // Every marker hidden during [3, 3.5) s: lost after 0.3 s, then found again among reflections.
  std::vector<ChainStatus> statuses;
  double tip2 = 0;
  int count = 0;
  for (const SimFrame& frame : asynchronous_frames(4, 100.0, scene.duration_s())) {
    const double t = ns_to_seconds(frame.stamp_ns);
    const FingerTruth truth = scene.truth(t);
    std::vector<Eigen::Vector3d> visible = FingerScene::reflections();
    if (t < 3.0 || t >= 3.5) {
      for (const Eigen::Vector3d& marker : FingerScene::markers(finger, truth)) visible.push_back(marker);
    }
    // Triangulated points (0.2 mm noise) ten times a second, as confirmed point tracks would be.
    if (frame.camera == 0 && frame.stamp_ns % 100'000'000 == 0 && t >= 0.3)
      tracker.identify(frame.stamp_ns, noisy(visible, 0.0002, rng));
    tracker.process(cameras[frame.camera], frame.stamp_ns, observe(cameras[frame.camera], visible, 0.1, rng));
    const ChainOutput output = tracker.outputs().at(0);
    if (statuses.empty() || statuses.back() != output.status) statuses.push_back(output.status);
    if (t > 4.0 && output.status == ChainStatus::kTracking) {
      tip2 += (output.pose.tip - FingerScene::tip(finger, truth)).squaredNorm();
      ++count;
    }
  }
  EXPECT_EQ(statuses, (std::vector<ChainStatus>{ChainStatus::kAmbiguous, ChainStatus::kTracking,
                                                ChainStatus::kNotIdentified, ChainStatus::kTracking}));
  ASSERT_GT(count, 1000);
  const double tip_rmse = std::sqrt(tip2 / count);
  std::cout << "tip RMSE after re-identification " << tip_rmse * 1e3 << " mm\n";
  EXPECT_LE(tip_rmse, 0.0005);
  // Events keep flowing after the re-identification (found again at 3.5-3.6 s).
  int events_after = 0;
  for (const NamedGrabEvent& event : tracker.take_events()) {
    EXPECT_EQ(event.chain, "index");
    if (ns_to_seconds(event.event.stamp_ns) > 3.6) ++events_after;
  }
  int transitions_after = 0;
  for (const BendTransition& transition : scene.transitions())
    transitions_after += transition.start_s > 3.6 ? 1 : 0;
  EXPECT_EQ(events_after, transitions_after);
}

}  // namespace
}  // namespace panoptes::estimator
