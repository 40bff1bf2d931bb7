// SPDX-License-Identifier: Apache-2.0
#include "panoptes/planner/metric.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace panoptes::planner {

namespace {

using Mask = std::uint64_t;
constexpr std::size_t kMaxCameras = 64;

// What one camera contributes at one point, when it sees it through the static scene.
struct CameraAtPoint {
  Eigen::Vector3d to_camera;  // unit vector from the point to the camera centre
  double width_m = 0;         // the pyramid's half-width at the point: sigma · depth / f
  double depth_over_f = 0;    // metres at the point per pixel in the image: depth / f
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  // JᵀJ / sigma²
};

// A point's figures: its uncertainty over occluder planes, with static occlusion only, and the
// number of cameras that see it under each plane.
struct PointResult {
  double uncertainty = 0;
  double seen_sum2 = 0;  // sum of U_res² over the planes under which at least k cameras see it
  double seen_share = 0;
  double resolution_only = 0;
  double p_k = 0;
  std::vector<double> histogram;
};

// A point's share of the tracker's predicted error (TrackingPrediction), summed over its planes.
struct TrackingPoint {
  double reported = 0;  // share of its planes under which the tracker reports it
  double error2 = 0;    // share-weighted squared error, m²
  double error2_ambiguous = 0;
  double one_view = 0;
  double two_view = 0;
  double ambiguous = 0;
  double seen_by_two = 0;  // at least two cameras
  double confirmable = 0;
  double cost2 = 0;  // share-weighted tracker_sample_cost2, m²
};

class PointEvaluator {
 public:
  PointEvaluator(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                 std::span<const Box> obstacles, const MetricOptions& options)
      : cameras_(cameras), samples_(samples), obstacles_(obstacles), options_(options) {
    at_.resize(cameras.size());
    min_angle_cos_ =
        std::cos(std::clamp(options.min_triangulation_deg, 0.0, 90.0) * std::numbers::pi / 180.0);
  }

  PointResult evaluate(const Eigen::Vector3d& p) {
    const Mask seen = effective(static_visibility(p));
    cache_.clear();
    PointResult result;
    result.histogram.assign(cameras_.size() + 1, 0.0);
    result.resolution_only = uncertainty(seen);
    if (samples_.normals.empty()) {
      result.uncertainty = result.resolution_only;
      const int n = std::popcount(seen);
      result.histogram[static_cast<std::size_t>(n)] = 1.0;
      result.p_k = n >= options_.k_cameras ? 1.0 : 0.0;
      result.seen_sum2 = result.p_k * result.resolution_only * result.resolution_only;
      result.seen_share = result.p_k;
      return result;
    }
    per_plane_.clear();
    const double share = 1.0 / static_cast<double>(samples_.normals.size());
    for (const Eigen::Vector3d& normal : samples_.normals) {
      const Mask mask = facing(seen, normal);
      const double u = uncertainty(mask);
      per_plane_.push_back(u);
      const int n = std::popcount(mask);
      result.histogram[static_cast<std::size_t>(n)] += share;
      if (n >= options_.k_cameras) {
        result.p_k += share;
        result.seen_sum2 += share * u * u;
        result.seen_share += share;
      }
    }
    result.uncertainty = aggregate(per_plane_, {}, options_.over_planes);
    return result;
  }

  // The tracker's error at `p` under each plane (TrackingPrediction).
  TrackingPoint track(const Eigen::Vector3d& p, const TrackerModel& tracker) {
    const Mask seen = effective(static_visibility(p));
    trace_cache_.clear();
    TrackingPoint result;
    if (samples_.normals.empty()) {
      add_tracked(seen, 1.0, tracker, result);
      return result;
    }
    const double share = 1.0 / static_cast<double>(samples_.normals.size());
    for (const Eigen::Vector3d& normal : samples_.normals)
      add_tracked(facing(seen, normal), share, tracker, result);
    return result;
  }

 private:
  // The cameras of `seen` that the plane with `normal` through the point leaves in view.
  Mask facing(Mask seen, const Eigen::Vector3d& normal) const {
    Mask mask = 0;
    for (Mask rest = seen; rest != 0; rest &= rest - 1) {
      const auto c = static_cast<std::size_t>(std::countr_zero(rest));
      if (normal.dot(at_[c].to_camera) > samples_.facing_cos) mask |= Mask{1} << c;
    }
    return effective(mask);
  }

  // One (point, plane) sample seen by the cameras of `mask`, weighted by `share`.
  void add_tracked(Mask mask, double share, const TrackerModel& tracker, TrackingPoint& out) {
    const int n = std::popcount(mask);
    const double triangulation2 = n >= 2 ? covariance_trace(mask) : 0.0;
    out.cost2 += share * tracker_sample_cost2(n, triangulation2, tracker);
    if (n == 0) return;  // not reported: a track nobody sees loses its depth within tens of ms
    const double coast2 = one_view_error2(tracker);
    if (n == 1) {
      const double published = share * one_view_reported_share(tracker);
      out.one_view += share;
      out.reported += published;
      out.error2 += published * coast2;
      out.error2_ambiguous += published * coast2;
      return;
    }
    out.reported += share;
    out.seen_by_two += share;
    out.error2 += share * triangulation2;
    if (n > 2) {
      out.confirmable += share;
      out.error2_ambiguous += share * triangulation2;
      return;
    }
    const double p = two_view_ambiguity(mask, tracker);
    out.two_view += share;
    out.ambiguous += share * p;
    out.confirmable += share * (1.0 - p);
    out.error2_ambiguous += share * ((1.0 - p) * triangulation2 + p * coast2);
  }

  // P(another of the subject's markers lies within the epipolar tolerance of the point's pairing
  // by its two cameras): in camera b's image the band of ±epipolar_px about the epipolar line is,
  // at the point, a slab of ±epipolar_px · depth_b / f_b about the epipolar plane (through both
  // centres and the point). The subject's other markers spread evenly over its extent along the
  // plane's normal fall in it in proportion; both directions of pairing (a's blob with b's, b's
  // with a's) count. Poisson: P = 1 − exp(−expected).
  double two_view_ambiguity(Mask mask, const TrackerModel& tracker) const {
    if (tracker.subject_markers < 2) return 0.0;
    const CameraAtPoint& a = at_[static_cast<std::size_t>(std::countr_zero(mask))];
    const CameraAtPoint& b = at_[static_cast<std::size_t>(std::countr_zero(mask & (mask - 1)))];
    const Eigen::Vector3d normal = a.to_camera.cross(b.to_camera).normalized();
    const double extent = normal.cwiseAbs().dot(tracker.subject_size.cwiseAbs());
    if (!(extent > 0.0)) return 1.0;
    double expected = 0.0;
    for (const CameraAtPoint* camera : {&a, &b})
      expected += static_cast<double>(tracker.subject_markers - 1) *
                  std::min(1.0, 2.0 * tracker.epipolar_px * camera->depth_over_f / extent);
    return 1.0 - std::exp(-expected);
  }

  // trace of the triangulation covariance of the cameras in `mask` (the expected squared 3D error).
  double covariance_trace(Mask mask) {
    for (const auto& [m, t] : trace_cache_)
      if (m == mask) return t;
    const double huge = options_.unseen_m;
    Eigen::Matrix3d information = Eigen::Matrix3d::Identity() / (huge * huge);
    for (Mask rest = mask; rest != 0; rest &= rest - 1)
      information += at_[static_cast<std::size_t>(std::countr_zero(rest))].information;
    const double trace = information.inverse().trace();
    trace_cache_.emplace_back(mask, trace);
    return trace;
  }

  // `mask`, or only its first camera when no two of its rays are min_triangulation_deg apart as
  // lines: rays from opposite sides (cameras facing each other across P) are as useless for
  // triangulation as rays from one side.
  Mask effective(Mask mask) const {
    if (std::popcount(mask) < 2 || options_.min_triangulation_deg <= 0.0) return mask;
    for (Mask a = mask; a != 0; a &= a - 1) {
      const Eigen::Vector3d& ray = at_[static_cast<std::size_t>(std::countr_zero(a))].to_camera;
      for (Mask b = a & (a - 1); b != 0; b &= b - 1)
        if (std::abs(ray.dot(at_[static_cast<std::size_t>(std::countr_zero(b))].to_camera)) <= min_angle_cos_)
          return mask;
    }
    return mask & (~mask + 1);
  }

  Mask static_visibility(const Eigen::Vector3d& p) {
    Mask seen = 0;
    const double sigma = options_.pixel_sigma;
    for (std::size_t c = 0; c < cameras_.size(); ++c) {
      const PlannedCamera& camera = cameras_[c];
      const Eigen::Vector3d p_cam = camera.model.T_cam_world().apply(p);
      const double distance = p_cam.norm();
      if (p_cam.z() <= 0.0 || distance < camera.min_depth_m || distance > camera.max_depth_m) continue;
      Eigen::Matrix<double, 2, 3> J;
      const auto pixel = camera.model.project(p, &J);
      if (!pixel || !camera.model.in_image(*pixel)) continue;
      const Eigen::Vector3d centre = camera.model.center_world();
      if (std::any_of(obstacles_.begin(), obstacles_.end(),
                      [&](const Box& box) { return box.blocks(p, centre); }))
        continue;
      const auto& K = camera.model.intrinsics();
      CameraAtPoint& at = at_[c];
      at.to_camera = (centre - p) / distance;
      at.depth_over_f = p_cam.z() / (0.5 * (K.fx + K.fy));
      at.width_m = sigma * at.depth_over_f;
      at.information = J.transpose() * J / (sigma * sigma);
      seen |= Mask{1} << c;
    }
    return seen;
  }

  // U_res(P, plane) for the cameras in `mask`, cached: a point's planes share few subsets.
  double uncertainty(Mask mask) {
    for (const auto& [m, u] : cache_)
      if (m == mask) return u;
    const double u = options_.resolution == ResolutionModel::kPyramid ? pyramid(mask) : covariance(mask);
    cache_.emplace_back(mask, u);
    return u;
  }

  // Eq. 4.2: in each direction the shortest extent of any camera's ray pyramid, then norm_k.
  double pyramid(Mask mask) {
    const double huge = options_.unseen_m;
    lengths_.assign(samples_.directions.size(), huge);
    for (Mask rest = mask; rest != 0; rest &= rest - 1) {
      const CameraAtPoint& at = at_[static_cast<std::size_t>(std::countr_zero(rest))];
      for (std::size_t k = 0; k < samples_.directions.size(); ++k) {
        const double cosine = samples_.directions[k].dot(at.to_camera);
        const double sine = std::sqrt(std::max(0.0, 1.0 - cosine * cosine));
        const double length = sine * huge > at.width_m ? at.width_m / sine : huge;
        lengths_[k] = std::min(lengths_[k], length);
      }
    }
    return aggregate(lengths_, {}, options_.over_directions);
  }

  // The triangulation covariance of the cameras in `mask` with a prior of `unseen_m` in every
  // direction (so that an unconstrained direction reads "huge", as in the pyramid model).
  double covariance(Mask mask) {
    const double huge = options_.unseen_m;
    Eigen::Matrix3d information = Eigen::Matrix3d::Identity() / (huge * huge);
    for (Mask rest = mask; rest != 0; rest &= rest - 1)
      information += at_[static_cast<std::size_t>(std::countr_zero(rest))].information;
    const Eigen::Matrix3d covariance = information.inverse();
    switch (options_.over_directions) {
      case Norm::kRms:  // the mean of dᵀΣd over the sphere is trace/3
        return std::sqrt(std::max(0.0, covariance.trace() / 3.0));
      case Norm::kMax:
        return std::sqrt(
            std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
                              .eigenvalues()
                              .maxCoeff()));
      case Norm::kMean:
        break;
    }
    lengths_.clear();
    for (const Eigen::Vector3d& d : samples_.directions) lengths_.push_back(std::sqrt(d.dot(covariance * d)));
    return aggregate(lengths_, {}, Norm::kMean);
  }

  std::span<const PlannedCamera> cameras_;
  const SampleSet& samples_;
  std::span<const Box> obstacles_;
  const MetricOptions& options_;
  std::vector<CameraAtPoint> at_;
  std::vector<std::pair<Mask, double>> cache_;
  std::vector<std::pair<Mask, double>> trace_cache_;
  std::vector<double> per_plane_;
  std::vector<double> lengths_;
  double min_angle_cos_ = 1.0;
};

// Unit vectors uniform over the band between `min_angle` and `max_angle` from `axis`.
Eigen::Vector3d random_normal(std::mt19937_64& rng, const Eigen::Vector3d& axis, double min_angle_rad,
                              double max_angle_rad) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double cos_min = std::cos(std::clamp(min_angle_rad, 0.0, std::numbers::pi));
  const double cos_max = std::cos(std::clamp(max_angle_rad, 0.0, std::numbers::pi));
  const double z = cos_min - uniform(rng) * (cos_min - cos_max);  // uniform in area over the band
  const double phi = 2.0 * std::numbers::pi * uniform(rng);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const Eigen::Vector3d local(r * std::cos(phi), r * std::sin(phi), z);
  return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis.normalized()) * local;
}

Eigen::Vector3d uniform_in(std::mt19937_64& rng, const Box& box) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  return box.min + Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)).cwiseProduct(box.max - box.min);
}

}  // namespace

double one_view_reported_share(const TrackerModel& tracker) {
  const double sigma2 = tracker.publish_max_sigma_m * tracker.publish_max_sigma_m;
  const double published_s = std::cbrt(3.0 * sigma2 / std::max(tracker.process_noise, 1e-12));
  return std::min(1.0, published_s / std::max(tracker.one_view_episode_s, 1e-9));
}

double one_view_error2(const TrackerModel& tracker) {
  return 0.25 * tracker.publish_max_sigma_m * tracker.publish_max_sigma_m;
}

double tracker_sample_cost2(int cameras, double triangulation_trace, const TrackerModel& tracker) {
  return cameras >= 2 ? triangulation_trace : one_view_error2(tracker);
}

double aggregate(std::span<const double> values, std::span<const double> weights, Norm norm) {
  if (values.empty()) return 0.0;
  if (norm == Norm::kMax) return *std::max_element(values.begin(), values.end());
  double sum = 0.0, total = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    sum += w * (norm == Norm::kRms ? values[i] * values[i] : values[i]);
    total += w;
  }
  const double mean = total > 0.0 ? sum / total : 0.0;
  return norm == Norm::kRms ? std::sqrt(mean) : mean;
}

SampleSet draw_samples(const Room& room, const OccluderModel& occluders, int points, int directions,
                       std::uint64_t seed) {
  if (points <= 0) throw std::invalid_argument("planner: the number of sample points must be > 0");
  std::mt19937_64 rng(seed);
  SampleSet samples;
  samples.facing_cos =
      std::cos(std::clamp(occluders.facing_angle_deg, 0.0, 180.0) * std::numbers::pi / 180.0);
  std::vector<Region> regions = room.regions;
  if (regions.empty()) regions.push_back({room.volume, 1.0});
  std::vector<double> mass;
  mass.reserve(regions.size());
  for (const Region& region : regions) mass.push_back(std::max(0.0, region.weight));
  std::discrete_distribution<std::size_t> pick(mass.begin(), mass.end());
  for (int i = 0; i < points; ++i) samples.points.push_back(uniform_in(rng, regions[pick(rng)].box));
  samples.weights.assign(samples.points.size(), 1.0 / static_cast<double>(samples.points.size()));
  for (int i = 0; i < occluders.planes; ++i)
    samples.normals.push_back(random_normal(rng, occluders.axis,
                                            occluders.min_angle_deg * std::numbers::pi / 180.0,
                                            occluders.max_angle_deg * std::numbers::pi / 180.0));
  // Directions: a Fibonacci lattice over the upper hemisphere (a direction and its opposite give
  // the same extent), deterministic and even.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < directions; ++k) {
    const double z = (static_cast<double>(k) + 0.5) / static_cast<double>(directions);
    const double r = std::sqrt(1.0 - z * z);
    const double phi = golden * static_cast<double>(k);
    samples.directions.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return samples;
}

Evaluation evaluate(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                    std::span<const Box> obstacles, const MetricOptions& options) {
  if (cameras.size() > kMaxCameras)
    throw std::invalid_argument("planner: at most " + std::to_string(kMaxCameras) +
                                " cameras per evaluation");
  const std::size_t n = samples.points.size();
  Evaluation result;
  result.point_uncertainty.assign(n, 0.0);
  result.point_p_k.assign(n, 0.0);
  std::vector<double> resolution(n, 0.0), seen_sum2(n, 0.0), seen_share(n, 0.0);
  std::vector<std::vector<double>> histograms(n);
  const auto run = [&](std::size_t begin, std::size_t end) {
    PointEvaluator evaluator(cameras, samples, obstacles, options);
    for (std::size_t i = begin; i < end; ++i) {
      PointResult point = evaluator.evaluate(samples.points[i]);
      result.point_uncertainty[i] = point.uncertainty;
      result.point_p_k[i] = point.p_k;
      resolution[i] = point.resolution_only;
      seen_sum2[i] = point.seen_sum2;
      seen_share[i] = point.seen_share;
      histograms[i] = std::move(point.histogram);
    }
  };
  const auto threads = static_cast<std::size_t>(std::clamp(options.threads, 1, 64));
  if (threads == 1 || n < 256) {
    run(0, n);
  } else {
    std::vector<std::thread> workers;
    for (std::size_t t = 0; t < threads; ++t)
      workers.emplace_back(run, n * t / threads, n * (t + 1) / threads);
    for (auto& worker : workers) worker.join();
  }
  result.quality = aggregate(result.point_uncertainty, samples.weights, options.over_points);
  result.resolution_only = aggregate(resolution, samples.weights, options.over_points);
  result.p_at_least_k = aggregate(result.point_p_k, samples.weights, Norm::kMean);
  double sum2 = 0.0, share = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sum2 += samples.weights[i] * seen_sum2[i];
    share += samples.weights[i] * seen_share[i];
  }
  result.seen_uncertainty = share > 0.0 ? std::sqrt(sum2 / share) : options.unseen_m;
  result.visible_histogram.assign(cameras.size() + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < histograms[i].size(); ++k)
      result.visible_histogram[k] += samples.weights[i] * histograms[i][k];
  return result;
}

TrackingPrediction predict_tracking(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                                    std::span<const Box> obstacles, const MetricOptions& options,
                                    const TrackerModel& tracker) {
  if (cameras.size() > kMaxCameras)
    throw std::invalid_argument("planner: at most " + std::to_string(kMaxCameras) +
                                " cameras per evaluation");
  PointEvaluator evaluator(cameras, samples, obstacles, options);
  TrackingPoint sum;
  std::vector<double> point_cost2(samples.points.size(), 0.0);
  for (std::size_t i = 0; i < samples.points.size(); ++i) {
    const TrackingPoint point = evaluator.track(samples.points[i], tracker);
    point_cost2[i] = point.cost2;
    const double w = samples.weights[i];
    sum.reported += w * point.reported;
    sum.error2 += w * point.error2;
    sum.error2_ambiguous += w * point.error2_ambiguous;
    sum.one_view += w * point.one_view;
    sum.two_view += w * point.two_view;
    sum.ambiguous += w * point.ambiguous;
    sum.seen_by_two += w * point.seen_by_two;
    sum.confirmable += w * point.confirmable;
  }
  TrackingPrediction result;
  result.rmse_m = sum.reported > 0.0 ? std::sqrt(sum.error2 / sum.reported) : options.unseen_m;
  result.rmse_with_ambiguity_m =
      sum.reported > 0.0 ? std::sqrt(sum.error2_ambiguous / sum.reported) : options.unseen_m;
  result.one_view_share = sum.one_view;
  result.two_view_share = sum.two_view;
  result.ambiguous_share = sum.ambiguous;
  result.confirmable_share = sum.seen_by_two > 0.0 ? sum.confirmable / sum.seen_by_two : 0.0;
  // As IncrementalMetric aggregates it, so that the two agree to rounding.
  result.rmse_gaps_charged_m = std::sqrt(aggregate(point_cost2, samples.weights, Norm::kMean));
  return result;
}

}  // namespace panoptes::planner
