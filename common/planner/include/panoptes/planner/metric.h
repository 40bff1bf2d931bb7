// SPDX-License-Identifier: Apache-2.0
// The quality of a camera configuration with respect to a working volume (seed 003 §4.3, eq.
// 4.2–4.8): the 3D position uncertainty of points drawn over the volume, with the cameras that
// see each point under static obstacles and under dynamic self-occlusion, modelled as a plane
// through the point whose normal is drawn from a distribution. Lower is better. docs/planner.md.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "panoptes/planner/room.h"

namespace panoptes::planner {

// How a set of values is aggregated (the seed's norm_k): the worst, the mean, the root mean square.
enum class Norm { kMax, kMean, kRms };

// How one camera's resolution bounds a point's position.
//  kPyramid: the seed's ray pyramid (eq. 4.2): in each direction the shortest extent over the
//            cameras that see the point; cameras do not combine.
//  kCovariance: the triangulation covariance of all cameras that see the point (information
//            summed, as the tracker's filter does), evaluated in each direction.
enum class ResolutionModel { kPyramid, kCovariance };

// Occluder planes through each point; normals uniform within `max_angle_deg` of `axis` (180:
// any orientation; e.g. 60 about +z for a head marker that never faces down). planes = 0: none.
struct OccluderModel {
  int planes = 64;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double max_angle_deg = 180.0;
};

struct MetricOptions {
  ResolutionModel resolution = ResolutionModel::kCovariance;
  Norm over_directions = Norm::kRms;  // eq. 4.2
  Norm over_planes = Norm::kRms;      // eq. 4.5, the seed's Σ*
  Norm over_points = Norm::kRms;      // eq. 4.6
  double pixel_sigma = 0.1;           // centroid noise, pixels
  double unseen_m = 1.0;              // the "huge" extent of a direction no camera constrains
  int k_cameras = 2;                  // second figure: P(at least k cameras see a point)
  int threads = 1;                    // points are split over this many threads
};

// The random parts of the metric, drawn once so that every configuration of an optimisation is
// judged on the same samples.
struct SampleSet {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> weights;              // by point, sum 1
  std::vector<Eigen::Vector3d> normals;     // occluder plane normals (may be empty)
  std::vector<Eigen::Vector3d> directions;  // unit directions over a hemisphere (eq. 4.2)
};

SampleSet draw_samples(const Room& room, const OccluderModel& occluders, int points, int directions,
                       std::uint64_t seed);

struct Evaluation {
  double quality = 0;                     // eq. 4.8, metres (lower is better)
  double resolution_only = 0;             // eq. 4.2 + 4.6 with static occlusion only, metres
  double p_at_least_k = 0;                // over points and occluder planes, weighted
  std::vector<double> visible_histogram;  // P(n cameras see a point), n = 0..cameras
  std::vector<double> point_uncertainty;  // U(P) by sample point (eq. 4.5)
  std::vector<double> point_p_k;          // P(at least k see P) by sample point
};

Evaluation evaluate(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                    std::span<const Box> obstacles, const MetricOptions& options);

// norm_k of `values` weighted by `weights` (empty: equal weights).
double aggregate(std::span<const double> values, std::span<const double> weights, Norm norm);

}  // namespace panoptes::planner
