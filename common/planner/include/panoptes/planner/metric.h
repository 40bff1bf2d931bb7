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

// Occluder planes through each point; normals uniform over the directions between `min_angle_deg`
// and `max_angle_deg` from `axis` (0-180: any orientation; 0-60 about +z: a head marker that never
// faces down; 45-135: markers on a standing body, facing mostly sideways). planes = 0: none.
struct OccluderModel {
  int planes = 64;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double max_angle_deg = 180.0;
  double min_angle_deg = 0.0;
  // A camera sees the point when its direction is within this angle of the normal: 90 is the
  // seed's plane; a marker on a convex body is seen a little beyond it (the simulator's
  // trc.occlusion.facing_angle is the same quantity).
  double facing_angle_deg = 90.0;
};

struct MetricOptions {
  ResolutionModel resolution = ResolutionModel::kCovariance;
  Norm over_directions = Norm::kRms;  // eq. 4.2
  Norm over_planes = Norm::kRms;      // eq. 4.5, the seed's Σ*
  Norm over_points = Norm::kRms;      // eq. 4.6
  double pixel_sigma = 0.1;           // centroid noise, pixels
  double unseen_m = 1.0;              // the "huge" extent of a direction no camera constrains
  int k_cameras = 2;                  // second figure: P(at least k cameras see a point)
  // Cameras whose rays to a point are all within this angle of each other see it from one
  // direction: they count as one camera (a tracker cannot triangulate, nor tell ghosts apart, on
  // such a short baseline). 0 disables the rule (the seed's metric).
  double min_triangulation_deg = 10.0;
  int threads = 1;  // points are split over this many threads
};

// The random parts of the metric, drawn once so that every configuration of an optimisation is
// judged on the same samples.
struct SampleSet {
  double facing_cos = 0.0;  // cos(facing angle): a camera sees P when n·(C − P)/|C − P| > it
  std::vector<Eigen::Vector3d> points;
  std::vector<double> weights;              // by point, sum 1
  std::vector<Eigen::Vector3d> normals;     // occluder plane normals (may be empty)
  std::vector<Eigen::Vector3d> directions;  // unit directions over a hemisphere (eq. 4.2)
};

SampleSet draw_samples(const Room& room, const OccluderModel& occluders, int points, int directions,
                       std::uint64_t seed);

struct Evaluation {
  double quality = 0;          // eq. 4.8, metres (lower is better)
  double resolution_only = 0;  // eq. 4.2 + 4.6 with static occlusion only, metres
  double p_at_least_k = 0;     // over points and occluder planes, weighted
  // RMS of U_res over the (point, plane) samples that at least k cameras see: the error of what a
  // tracker reports (it reports only what it sees); compare with a tracker's RMSE.
  double seen_uncertainty = 0;
  std::vector<double> visible_histogram;  // P(n cameras see a point), n = 0..cameras
  std::vector<double> point_uncertainty;  // U(P) by sample point (eq. 4.5)
  std::vector<double> point_p_k;          // P(at least k see P) by sample point
};

Evaluation evaluate(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                    std::span<const Box> obstacles, const MetricOptions& options);

// What the tracker (docs/estimator.md) does with what the cameras see, for a predicted RMSE of
// its reported positions (docs/planner.md, "Validation against the tracker"). Every parameter is the
// tracker's or the subject's; none is fitted to measurements.
struct TrackerModel {
  // A track that one camera sees has no depth: under white acceleration of spectral density
  // `process_noise` its depth variance grows as q·t³/3, and it is reported while its 1σ stays
  // under `publish_max_sigma_m`, i.e. for t_pub = (3·σ_max²/q)^(1/3) (29 ms with the 20 mm below
  // and the tracker's process noise). A consistent filter's squared error equals its variance: over the
  // reported time it averages σ_max²/4. Of an episode seen by one camera only the first t_pub is reported.
  // TrackerOptions::publish_max_sigma_m as it was when docs/planner.md's validation was measured;
  // the tracker's default is 12 mm since stop 88, so this one-view term is pessimistic by up to
  // (20² − 12²)/4 mm² per sample seen by fewer than two cameras (docs/planner.md, "Validation against the
  // tracker").
  double publish_max_sigma_m = 0.02;
  double process_noise = 50.0;  // TrackerOptions::process_noise, m²/s³
  // How long a marker typically stays seen by one camera: on a walking body the visibility of a
  // marker changes with the gait (limbs swing, the torso turns), about twice a cycle of ~1 s.
  double one_view_episode_s = 0.5;
  // Two-view pairing: another marker within this many pixels of the epipolar line pairs as well
  // (InitiatorOptions::epipolar_px).
  double epipolar_px = 2.0;
  // The subject: its markers and its extent at one instant (metres, x y z). 0 markers: no
  // two-view ambiguity term.
  int subject_markers = 0;
  Eigen::Vector3d subject_size{0.6, 0.7, 1.6};
};

// The tracker's error predicted over the (point, plane) samples, each a marker at an instant. A
// sample seen by at least two cameras is reported with the triangulation covariance (trace,
// centroid noise MetricOptions::pixel_sigma); one seen by one camera is reported for the share
// t_pub / one_view_episode_s of the time with the coasting error above; one seen by none is not
// reported.
struct TrackingPrediction {
  double rmse_m = 0;  // over the reported samples
  // The same when a two-view sample is as good as one view with the probability that another
  // marker lies in its epipolar band (the tracker cannot tell the pairs apart without a third
  // camera): the correspondence ambiguity charged to the error.
  double rmse_with_ambiguity_m = 0;
  double one_view_share = 0;  // of all samples
  double two_view_share = 0;
  // Of all samples: seen by exactly two cameras, weighted by P(another marker in the epipolar band).
  double ambiguous_share = 0;
  // Share of the samples seen by >= 2 cameras that the tracker can confirm: seen by three, or
  // by two without a competing marker in the epipolar band.
  double confirmable_share = 0;
  // The RMSE over *all* samples, each one that fewer than two cameras see (unseen, or reported
  // only while a one-camera track coasts) charged the mean squared error of such a coasting track,
  // σ_max²/4: rmse_m priced for coverage, the planner's `tracker_rmse` objective
  // (tracker_sample_cost2). docs/planner.md, "Objectives".
  double rmse_gaps_charged_m = 0;
};

// What the search minimises (docs/planner.md, "Objectives"): the seed's quality q, or the
// predicted tracker RMSE with gaps charged (TrackingPrediction::rmse_gaps_charged_m).
enum class Objective { kQuality, kTrackerRmse };

// The share of a one-camera episode the tracker reports, t_pub / one_view_episode_s (at most 1),
// and the mean squared error of what it reports then, σ_max²/4 (TrackerModel).
double one_view_reported_share(const TrackerModel& tracker);
double one_view_error2(const TrackerModel& tracker);

// The squared cost of one (point, plane) sample under the tracker objective, from the number of
// cameras that see it (after the short-baseline rule) and, for two or more, the trace of their
// triangulation covariance: two or more → the trace; fewer → one_view_error2, whether or not the
// tracker publishes it (docs/planner.md, "Objectives": why).
double tracker_sample_cost2(int cameras, double triangulation_trace, const TrackerModel& tracker);

TrackingPrediction predict_tracking(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                                    std::span<const Box> obstacles, const MetricOptions& options,
                                    const TrackerModel& tracker);

// norm_k of `values` weighted by `weights` (empty: equal weights).
double aggregate(std::span<const double> values, std::span<const double> weights, Norm norm);

}  // namespace panoptes::planner
