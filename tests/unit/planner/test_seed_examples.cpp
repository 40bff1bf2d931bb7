// SPDX-License-Identifier: Apache-2.0
// The placement examples of seed 003 §4.5 reproduced with the planner's metric and optimiser:
// each test states the seed's conclusion and checks it on numbers (docs/planner.md shows them).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "panoptes/planner/metric.h"
#include "panoptes/planner/optimizer.h"

namespace panoptes::planner {
namespace {

constexpr double kOuter = 4.0;  // cameras on a sphere of this radius, metres
constexpr double kInner = 1.0;  // the target sphere

Lens lens_with_half_fov(double half_fov_deg, const std::string& name = "lens") {
  Lens lens;
  lens.name = name;
  lens.intrinsics.width = 640;
  lens.intrinsics.height = 640;
  lens.intrinsics.fx = lens.intrinsics.fy = 320.0 / std::tan(half_fov_deg * std::numbers::pi / 180.0);
  lens.intrinsics.cx = lens.intrinsics.cy = 319.5;
  lens.min_depth_m = 0.1;
  lens.max_depth_m = 20.0;
  return lens;
}

// Just covers the target sphere from the outer sphere.
Lens wide_lens() {
  return lens_with_half_fov(std::asin(kInner / kOuter) * 180.0 / std::numbers::pi + 1.0);
}

Eigen::Vector3d on_sphere(double azimuth_deg, double elevation_deg, double radius = kOuter) {
  const double a = azimuth_deg * std::numbers::pi / 180.0, e = elevation_deg * std::numbers::pi / 180.0;
  return radius * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
}

// Points uniform in the target ball, occluder normals uniform over the sphere (the seed's choice).
SampleSet ball_samples(int points, int planes, std::uint64_t seed) {
  Room room;
  room.volume = {Eigen::Vector3d::Constant(-kInner), Eigen::Vector3d::Constant(kInner)};
  SampleSet samples = draw_samples(room, {planes}, 4 * points, 64, seed);
  std::vector<Eigen::Vector3d> inside;
  for (const auto& p : samples.points)
    if (p.norm() <= kInner && static_cast<int>(inside.size()) < points) inside.push_back(p);
  samples.points = inside;
  samples.weights.assign(inside.size(), 1.0 / static_cast<double>(inside.size()));
  return samples;
}

MetricOptions seed_metric(ResolutionModel model) {
  MetricOptions options;
  options.resolution = model;  // 2-norm everywhere, as in the seed's examples
  options.pixel_sigma = 0.5;
  options.min_triangulation_deg = 0;  // the seed's metric has no short-baseline rule
  return options;
}

// Cameras on the outer sphere at the given unit directions, all looking at the centre.
std::vector<PlannedCamera> sphere_rig(const std::vector<Eigen::Vector3d>& directions, const Lens& lens) {
  std::vector<PlannedCamera> cameras;
  for (std::size_t i = 0; i < directions.size(); ++i)
    cameras.push_back(make_camera("c" + std::to_string(i), lens, kOuter * directions[i].normalized(),
                                  Eigen::Vector3d::Zero()));
  return cameras;
}

// N directions spread evenly over the sphere (a Fibonacci lattice).
std::vector<Eigen::Vector3d> spread(int n) {
  std::vector<Eigen::Vector3d> directions;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / n;
    const double r = std::sqrt(1.0 - z * z);
    directions.emplace_back(r * std::cos(golden * k), r * std::sin(golden * k), z);
  }
  return directions;
}

class SeedExamples : public ::testing::TestWithParam<ResolutionModel> {};

// §4.5, Fig. 4.13: two cameras on a sphere. Resolution only: best near 90° (the bad directions
// cancel); with dynamic occlusion: best near 180° (some camera sees the point whatever the plane).
TEST_P(SeedExamples, TwoCamerasResolutionPrefersRightAngleOcclusionPrefersOpposite) {
  const SampleSet samples = ball_samples(300, 64, 3);
  const MetricOptions metric = seed_metric(GetParam());
  double best_res = 1e9, best_res_angle = -1, best_occ = 1e9, best_occ_angle = -1;
  for (int angle = 10; angle <= 180; angle += 10) {
    const auto cameras = sphere_rig({on_sphere(0, 0, 1), on_sphere(angle, 0, 1)}, wide_lens());
    const Evaluation e = evaluate(cameras, samples, {}, metric);
    std::printf("theta %3d deg: resolution-only %.5f m, with occlusion %.4f m, P(>=2) %.3f\n", angle,
                e.resolution_only, e.quality, e.p_at_least_k);
    if (e.resolution_only < best_res) best_res = e.resolution_only, best_res_angle = angle;
    if (e.quality < best_occ) best_occ = e.quality, best_occ_angle = angle;
  }
  EXPECT_GE(best_res_angle, 70);
  EXPECT_LE(best_res_angle, 110);
  EXPECT_GE(best_occ_angle, 160);
}

// §4.5, Fig. 4.14: quality vs number of cameras. Resolution only: nearly flat after two cameras
// (ray pyramids: each direction takes the best camera, cameras do not add up); with occlusion: it
// keeps improving with every camera until every point is seen by two under nearly every plane.
// The covariance model adds cameras' information, so its resolution-only figure falls as
// 1/sqrt(N); the occlusion-aware figure still falls far faster.
TEST_P(SeedExamples, ResolutionFlatAfterTwoOcclusionKeepsImproving) {
  const SampleSet samples = ball_samples(300, 64, 4);
  const MetricOptions metric = seed_metric(GetParam());
  // Two cameras at their resolution optimum, more cameras spread evenly.
  const Evaluation pair =
      evaluate(sphere_rig({on_sphere(0, 0, 1), on_sphere(90, 0, 1)}, wide_lens()), samples, {}, metric);
  double previous_occ = 1e9, previous_p2 = 0, first_occ = 0, res = pair.resolution_only, occ = 0;
  for (int n = 2; n <= 8; ++n) {
    const Evaluation e = evaluate(sphere_rig(spread(n), wide_lens()), samples, {}, metric);
    res = std::min(pair.resolution_only, e.resolution_only);
    occ = e.quality;
    std::printf("%d cameras: resolution-only %.5f m (%.2f of two), with occlusion %.4f m, P(>=2) %.3f\n", n,
                res, res / pair.resolution_only, occ, e.p_at_least_k);
    if (n == 2) first_occ = occ;
    if (n >= 3 && previous_p2 < 0.99) {
      EXPECT_LT(occ, 0.93 * previous_occ) << n << " cameras";
    }
    previous_occ = occ;
    previous_p2 = e.p_at_least_k;
  }
  const double res_gain = res / pair.resolution_only, occ_gain = occ / first_occ;
  EXPECT_LT(occ_gain, 0.1 * res_gain);
  if (GetParam() == ResolutionModel::kPyramid) {
    EXPECT_GT(res_gain, 0.8) << "resolution-only should be nearly flat after two cameras";
  }
}

// §4.5, Fig. 4.15: eight cameras as two clusters of four narrow-angle cameras (each a quarter of
// the target) 90° apart, or spread evenly with wide lenses. Ray pyramids prefer the clusters on
// resolution alone; with occlusion the spread wins by far, whatever the resolution model.
TEST_P(SeedExamples, NarrowClustersWinOnResolutionSpreadWideWinsWithOcclusion) {
  const SampleSet samples = ball_samples(300, 64, 5);
  const MetricOptions metric = seed_metric(GetParam());
  const Lens wide = wide_lens();
  const Lens narrow = lens_with_half_fov(
      std::atan(std::tan(std::asin(kInner / kOuter)) / 2.0) * 180.0 / std::numbers::pi + 1.0);
  std::vector<PlannedCamera> clusters;
  for (const double azimuth : {0.0, 90.0}) {
    const Eigen::Vector3d position = on_sphere(azimuth, 0);
    const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(position).normalized();
    for (const double a : {-0.5, 0.5})
      for (const double b : {-0.5, 0.5})
        clusters.push_back(
            make_camera("n", narrow, position, kInner * (a * side + b * Eigen::Vector3d::UnitZ())));
  }
  const Evaluation cluster = evaluate(clusters, samples, {}, metric);
  const Evaluation wide_spread = evaluate(sphere_rig(spread(8), wide), samples, {}, metric);
  std::printf("clusters: resolution-only %.5f m, with occlusion %.4f m, P(>=2) %.3f\n",
              cluster.resolution_only, cluster.quality, cluster.p_at_least_k);
  std::printf("spread:   resolution-only %.5f m, with occlusion %.4f m, P(>=2) %.3f\n",
              wide_spread.resolution_only, wide_spread.quality, wide_spread.p_at_least_k);
  EXPECT_LT(wide_spread.quality, 0.1 * cluster.quality);
  if (GetParam() == ResolutionModel::kPyramid) {
    EXPECT_LT(cluster.resolution_only, 0.8 * wide_spread.resolution_only);
  } else {
    // Summed information: two cameras of twice the focal length carry what eight wide ones do, so
    // without occlusion the two layouts are about even (docs/planner.md).
    EXPECT_NEAR(cluster.resolution_only / wide_spread.resolution_only, 1.0, 0.15);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, SeedExamples,
                         ::testing::Values(ResolutionModel::kPyramid, ResolutionModel::kCovariance),
                         [](const auto& info) {
                           return info.param == ResolutionModel::kPyramid ? "Pyramid" : "Covariance";
                         });

}  // namespace
}  // namespace panoptes::planner
