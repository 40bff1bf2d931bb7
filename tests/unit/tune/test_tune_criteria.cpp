// SPDX-License-Identifier: Apache-2.0
// The held-out criterion's scoring (estimator_node/tune/criteria.h): it is a proper score — the
// covariance the blobs were really drawn with scores better than one 4x too small or too large —
// and its NIS mean matches the truncated χ²₂ expectation for a consistent prediction.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "../estimator/test_cameras.h"
#include "panoptes/tune/criteria.h"

namespace panoptes::tune {
namespace {

// Blobs drawn around the projection of a point whose position error has `sigma_m` per axis, plus
// `pixel_sigma` of centroid noise; scored against a track claiming `claimed_sigma_m` and a filter
// claiming `claimed_pixel_sigma`.
HeldOutScore score_draws(double sigma_m, double pixel_sigma, double claimed_sigma_m,
                         double claimed_pixel_sigma) {
  const auto camera = estimator::make_ring_cameras(1, 4.0, 2.0)[0];
  HeldOutScorer scorer({}, claimed_pixel_sigma);
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 4000; ++i) {
    const Eigen::Vector3d truth(0.3 * std::sin(i * 0.01), 0.2 * std::cos(i * 0.013), 1.0);
    TrackRecord track;
    track.p = truth + sigma_m * Eigen::Vector3d(normal(random), normal(random), normal(random));
    const double v = claimed_sigma_m * claimed_sigma_m;
    track.position_covariance = {v, 0, 0, v, 0, v};
    const Eigen::Vector2d pixel = *camera.project(truth);
    FeatureFrame frame;
    frame.blobs.push_back(
        {pixel.x() + pixel_sigma * normal(random), pixel.y() + pixel_sigma * normal(random), 1.0, 1.0});
    scorer.add_frame(frame, {track}, camera);
  }
  return scorer.score();
}

TEST(TuneHeldOut, TheTrueCovarianceScoresBest) {
  const HeldOutScore right = score_draws(0.002, 1.0, 0.002, 1.0);
  const HeldOutScore overconfident = score_draws(0.002, 1.0, 0.0005, 0.25);
  const HeldOutScore underconfident = score_draws(0.002, 1.0, 0.008, 4.0);
  EXPECT_EQ(right.blobs, 4000u);
  EXPECT_LT(right.cost, overconfident.cost - 0.5);
  EXPECT_LT(right.cost, underconfident.cost - 0.5);
  // Consistent: mean d² within 10% of the truncated expectation (≈ 2).
  EXPECT_NEAR(right.mean_nis / right.expected_nis, 1.0, 0.1);
  EXPECT_NEAR(right.expected_nis, 2.0, 0.01);
  EXPECT_GT(overconfident.mean_nis, 4.0 * right.expected_nis);
  EXPECT_LT(underconfident.mean_nis, 0.25 * right.expected_nis);
}

TEST(TuneHeldOut, ABlobNoTrackExplainsCostsTheClutterFloor) {
  const auto camera = estimator::make_ring_cameras(1, 4.0, 2.0)[0];
  HeldOutCriterionOptions options;
  HeldOutScorer scorer(options, 0.5);
  FeatureFrame frame;
  frame.blobs.push_back({100.0, 100.0, 1.0, 1.0});
  scorer.add_frame(frame, {}, camera);
  const double area = 1280.0 * 1024.0;
  EXPECT_NEAR(scorer.score().nll_per_blob, -std::log(options.clutter_weight / area), 1e-9);
  EXPECT_EQ(scorer.score().nis_samples, 0u);
}

}  // namespace
}  // namespace panoptes::tune
