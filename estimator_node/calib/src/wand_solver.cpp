// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/wand_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "panoptes/calib/world_frame.h"
#include "panoptes/distortion.h"
#include "panoptes/triangulation.h"
#include "panoptes/union_find.h"

namespace panoptes::calib {

int SolveResult::calibrated_count() const {
  return static_cast<int>(std::count_if(cameras.begin(), cameras.end(),
                                        [](const CameraResult& c) { return c.T_world_cam.has_value(); }));
}

std::optional<Eigen::Vector3d> triangulate(const std::vector<CameraModel>& models,
                                           const std::vector<Eigen::Vector2d>& pixels) {
  if (models.size() != pixels.size()) return std::nullopt;
  std::vector<PixelObservation> observations;
  observations.reserve(models.size());
  for (std::size_t i = 0; i < models.size(); ++i) observations.push_back({&models[i], pixels[i]});
  const auto triangulated = panoptes::triangulate(observations);
  if (!triangulated) return std::nullopt;
  return triangulated->point;
}

namespace {

using Clock = std::chrono::steady_clock;

struct MarkerSegment {
  double t0_s, h_s;
  double p0[2], p1[2], m0[2], m1[2];
};

MarkerSegment marker_segment(const TrackSegment& segment, std::size_t m) {
  MarkerSegment s{};
  s.t0_s = segment.t0_s;
  s.h_s = segment.h_s;
  for (int i = 0; i < 2; ++i) {
    s.p0[i] = segment.p0[m][i];
    s.p1[i] = segment.p1[m][i];
    s.m0[i] = segment.m0[m][i];
    s.m1[i] = segment.m1[m][i];
  }
  return s;
}

template <class T>
void evaluate(const MarkerSegment& s, const T& dt, T* out) {
  for (int i = 0; i < 2; ++i) out[i] = cubic_hermite(s.t0_s, s.h_s, s.p0[i], s.m0[i], s.p1[i], s.m1[i], dt);
}

// Camera parameters as the bundle adjustment holds them: world -> camera (angle-axis, t), then
// intrinsics [fx, fy, cx, cy, k1, k2, p1, p2, k3] (OpenCV model, as CameraModel).
template <class T>
bool project(const T* pose, const T* intrinsics, const T* point, T* pixel) {
  T p[3];
  ceres::AngleAxisRotatePoint(pose, point, p);
  p[0] += pose[3];
  p[1] += pose[4];
  p[2] += pose[5];
  if (p[2] < T(1e-6)) return false;
  const Eigen::Matrix<T, 2, 1> xd = distort_normalized<T>(p[0] / p[2], p[1] / p[2], intrinsics + 4);
  pixel[0] = intrinsics[0] * xd[0] + intrinsics[2];
  pixel[1] = intrinsics[1] * xd[1] + intrinsics[3];
  return true;
}

// The observation is the camera's 2D track evaluated at the sample instant on the camera's own
// clock (instant + offset): the offset moves the observation along the track's velocity. A wand
// sample is one parameter block (all its markers), so that the length residuals stay inside it and
// every sample can be eliminated by the Schur complement.
template <int kMarkers>
struct ReprojectionCost {
  MarkerSegment segment;
  double shift_s;  // the segment was looked up at instant + shift_s
  int marker;
  template <class T>
  bool operator()(const T* pose, const T* intrinsics, const T* offset, const T* sample, T* residual) const {
    T pixel[2], observed[2];
    if (!project(pose, intrinsics, sample + 3 * marker, pixel)) return false;
    evaluate(segment, offset[0] - T(shift_s), observed);
    residual[0] = pixel[0] - observed[0];
    residual[1] = pixel[1] - observed[1];
    return true;
  }
};

template <int kMarkers>
struct LengthCost {
  int i, j;
  double length, inv_sigma;
  template <class T>
  bool operator()(const T* sample, T* residual) const {
    const T* a = sample + 3 * i;
    const T* b = sample + 3 * j;
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz + T(1e-18)) - T(length)) * T(inv_sigma);
    return true;
  }
};

template <int kMarkers>
ceres::CostFunction* reprojection_cost(const MarkerSegment& segment, double shift_s, int marker) {
  return new ceres::AutoDiffCostFunction<ReprojectionCost<kMarkers>, 2, 6, 9, 1, 3 * kMarkers>(
      new ReprojectionCost<kMarkers>{segment, shift_s, marker});
}

template <int kMarkers>
ceres::CostFunction* length_cost(int i, int j, double length, double inv_sigma) {
  return new ceres::AutoDiffCostFunction<LengthCost<kMarkers>, 1, 3 * kMarkers>(
      new LengthCost<kMarkers>{i, j, length, inv_sigma});
}

ceres::CostFunction* make_reprojection(std::size_t markers, const MarkerSegment& segment, double shift_s,
                                       int marker) {
  switch (markers) {
    case 1:
      return reprojection_cost<1>(segment, shift_s, marker);
    case 2:
      return reprojection_cost<2>(segment, shift_s, marker);
    case 3:
      return reprojection_cost<3>(segment, shift_s, marker);
    case 4:
      return reprojection_cost<4>(segment, shift_s, marker);
    default:
      return reprojection_cost<5>(segment, shift_s, marker);
  }
}

ceres::CostFunction* make_length(std::size_t markers, int i, int j, double length, double inv_sigma) {
  switch (markers) {
    case 2:
      return length_cost<2>(i, j, length, inv_sigma);
    case 3:
      return length_cost<3>(i, j, length, inv_sigma);
    case 4:
      return length_cost<4>(i, j, length, inv_sigma);
    default:
      return length_cost<5>(i, j, length, inv_sigma);
  }
}

struct DistanceCost {  // single-light gauge: fixes the scale to the initial one
  double distance;
  template <class T>
  bool operator()(const T* pose_a, const T* pose_b, T* residual) const {
    T center_a[3], center_b[3], minus_a[3], minus_b[3];
    for (int i = 0; i < 3; ++i) {
      minus_a[i] = -pose_a[i];
      minus_b[i] = -pose_b[i];
    }
    ceres::AngleAxisRotatePoint(minus_a, pose_a + 3, center_a);
    ceres::AngleAxisRotatePoint(minus_b, pose_b + 3, center_b);
    const T dx = center_a[0] - center_b[0], dy = center_a[1] - center_b[1], dz = center_a[2] - center_b[2];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz) - T(distance)) * T(1e3);
    return true;
  }
};

struct Observation {
  int camera = 0;
  TrackSegment segment;
  double shift_s = 0;
  bool active = true;
};

struct Sample {
  TimeNs t_ns = 0;
  std::vector<Observation> observations;
};

struct CameraState {
  double pose[6] = {0, 0, 0, 0, 0, 0};  // T_cam_world
  double intrinsics[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  double offset = 0;  // s
  bool registered = false;
  bool usable = false;
};

CameraIntrinsics to_intrinsics(const double* v, const CameraIntrinsics& base) {
  CameraIntrinsics k = base;
  k.fx = v[0];
  k.fy = v[1];
  k.cx = v[2];
  k.cy = v[3];
  for (int i = 0; i < 5; ++i) k.distortion[static_cast<std::size_t>(i)] = v[4 + i];
  return k;
}

RigidTransform pose_to_T_world_cam(const double* pose) {
  const Eigen::Vector3d rotation_vector(pose[0], pose[1], pose[2]);
  const double angle = rotation_vector.norm();
  RigidTransform T_cam_world;
  T_cam_world.q = angle > 1e-15 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation_vector / angle))
                                : Eigen::Quaterniond::Identity();
  T_cam_world.t = Eigen::Vector3d(pose[3], pose[4], pose[5]);
  return T_cam_world.inverse();
}

void set_pose(const RigidTransform& T_world_cam, double* pose) {
  const RigidTransform T_cam_world = T_world_cam.inverse();
  const Eigen::AngleAxisd angle_axis(T_cam_world.q.normalized());
  const Eigen::Vector3d v = angle_axis.axis() * angle_axis.angle();
  for (int i = 0; i < 3; ++i) {
    pose[i] = v[i];
    pose[3 + i] = T_cam_world.t[i];
  }
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// Relative pose of a pair: x_a = R_ab x_b + c_b (c_b: b's centre in a's frame, metres if metric).
struct PairPose {
  int a = 0, b = 0;
  Eigen::Matrix3d R_ab = Eigen::Matrix3d::Identity();
  Eigen::Vector3d c_b = Eigen::Vector3d::Zero();
  double score = 0;
  std::size_t edge_index = 0;
};

// kNominal: the focal length (fx and fy together) and k1, k2: a guess at the lens, the image
// centre for the principal point. kSuspect: measured intrinsics that do not fit: fx, fy, cx, cy,
// k1, k2 each. kAll: --refine-intrinsics.
enum class IntrinsicsRefinement { kNone, kNominal, kSuspect, kAll };
constexpr long kMinCamerasForCentre = 8;

// The intrinsics block [fx, fy, cx, cy, k1, k2, p1, p2, k3] moved only along fixed directions:
// x + B delta. The automatic refinement moves fx and fy together (their given ratio, square pixels
// for a nominal camera), k1 and k2, and, if asked, cx and cy; the rest stays as given.
class LinearManifold : public ceres::Manifold {
 public:
  explicit LinearManifold(Eigen::Matrix<double, 9, Eigen::Dynamic> basis)
      : basis_(std::move(basis)), inverse_((basis_.transpose() * basis_).inverse() * basis_.transpose()) {}
  int AmbientSize() const override { return 9; }
  int TangentSize() const override { return static_cast<int>(basis_.cols()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    using Vector9 = Eigen::Matrix<double, 9, 1>;
    Eigen::Map<Vector9> out(x_plus_delta);
    out = Eigen::Map<const Vector9>(x) + basis_ * Eigen::Map<const Eigen::VectorXd>(delta, basis_.cols());
    return true;
  }
  bool PlusJacobian(const double* /*x*/, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 9, Eigen::Dynamic, Eigen::RowMajor>> out(jacobian, 9, basis_.cols());
    out = basis_;
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    using Vector9 = Eigen::Matrix<double, 9, 1>;
    Eigen::Map<Eigen::VectorXd> out(y_minus_x, basis_.cols());
    out = inverse_ * (Eigen::Map<const Vector9>(y) - Eigen::Map<const Vector9>(x));
    return true;
  }
  bool MinusJacobian(const double* /*x*/, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor>> out(jacobian, basis_.cols(), 9);
    out = inverse_;
    return true;
  }

 private:
  Eigen::Matrix<double, 9, Eigen::Dynamic> basis_;
  Eigen::Matrix<double, Eigen::Dynamic, 9> inverse_;
};

ceres::Manifold* refinement_manifold(const double* intrinsics, IntrinsicsRefinement refinement) {
  const bool nominal = refinement == IntrinsicsRefinement::kNominal;
  Eigen::Matrix<double, 9, Eigen::Dynamic> basis =
      Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, nominal ? 3 : 6);
  if (nominal) {
    basis(0, 0) = 1.0;
    basis(1, 0) = intrinsics[1] / intrinsics[0];
    basis(4, 1) = 1.0;
    basis(5, 2) = 1.0;
  } else {
    for (int i = 0; i < 6; ++i) basis(i, i) = 1.0;
  }
  return new LinearManifold(basis);
}

class Solver {
 public:
  Solver(const std::vector<CameraCalibration>& cameras, const std::vector<CameraWandTrack>& tracks,
         const WandDefinition& wand, const SolveOptions& options)
      : input_(cameras), wand_(wand), options_(options) {
    for (const auto& camera : cameras) {
      const CameraWandTrack* found = nullptr;
      for (const auto& track : tracks)
        if (track.camera_id == camera.id) found = &track;
      tracks_.push_back(found);
    }
  }

  SolveResult run();

 private:
  void progress(const std::string& message) const {
    if (!options_.progress) return;
    char elapsed[32];
    std::snprintf(elapsed, sizeof(elapsed), "[%.1f s] ",
                  std::chrono::duration<double>(Clock::now() - start_).count());
    options_.progress(elapsed + message);
  }
  void resolve_labels();
  void check_cameras();
  void build_samples();
  void pairwise();
  void unify();
  void triangulate_all();
  double adjust(bool alternation, bool robust = true);
  void finish();
  void raw_residuals(const std::vector<CameraModel>& models);
  std::vector<std::vector<double>> raw_errors(const std::vector<CameraModel>& models) const;
  std::vector<CameraModel> registered_models() const;
  void adjust_passes();
  void decide_intrinsics(double rms);
  void check_focal_lengths();
  CameraModel model_of(int camera) const {
    return CameraModel(to_intrinsics(state_[camera].intrinsics, input_[camera].intrinsics),
                       pose_to_T_world_cam(state_[camera].pose));
  }
  Eigen::Vector2d observed(const Observation& observation, std::size_t marker) const {
    double out[2];
    evaluate(marker_segment(observation.segment, marker),
             state_[observation.camera].offset - observation.shift_s, out);
    return {out[0], out[1]};
  }
  void fail(int camera, const std::string& reason) {
    if (result_.cameras[camera].failure.empty()) result_.cameras[camera].failure = reason;
    state_[camera].usable = false;
    state_[camera].registered = false;
  }

  const std::vector<CameraCalibration>& input_;
  std::vector<const CameraWandTrack*> tracks_;
  std::vector<CameraWandTrack> relabelled_;  // copies whose bar ends were reconciled
  WandDefinition wand_;
  SolveOptions options_;
  SolveResult result_;
  std::vector<CameraState> state_;
  std::vector<Sample> samples_;
  std::vector<double> points_;  // samples x markers x 3
  std::vector<PairPose> pairs_;
  int reference_ = -1;
  IntrinsicsRefinement intrinsics_ = IntrinsicsRefinement::kNone;
  int passes_ = 0;
  bool all_converged_ = true;
  std::string pass_iterations_;  // iterations per pass, "12, 4, 3"
  Clock::time_point start_ = Clock::now();
};

// A wand whose ends look alike: the cameras' label runs agree only after resolve_bar_labels.
void Solver::resolve_labels() {
  std::vector<CameraIntrinsics> intrinsics;
  for (std::size_t c = 0; c < input_.size(); ++c) {
    if (tracks_[c] == nullptr) continue;
    relabelled_.push_back(*tracks_[c]);
    intrinsics.push_back(input_[c].intrinsics);
  }
  BarLabelOptions options;
  options.sample_rate_hz = options_.sample_rate_hz;
  options.max_gap_frames = options_.max_gap_frames;
  options.min_pair_samples = options_.min_pair_samples;
  const BarLabelReport report = resolve_bar_labels(relabelled_, intrinsics, options);
  for (std::size_t c = 0, k = 0; c < input_.size(); ++c)
    if (tracks_[c] != nullptr) tracks_[c] = &relabelled_[k++];
  result_.bar_labels = report;
  progress("bar ends: " + std::to_string(report.runs) + " label runs, " +
           std::to_string(report.flipped_runs) + " reversed, " + std::to_string(report.dropped_runs) +
           " unrelated runs dropped (" + std::to_string(report.dropped_frames) + " frames); " +
           std::to_string(report.conflicting_votes) + " of " + std::to_string(report.votes) +
           " votes against the labelling");
}

void Solver::check_cameras() {
  const std::size_t n = input_.size();
  result_.cameras.resize(n);
  state_.resize(n);
  for (std::size_t c = 0; c < n; ++c) {
    auto& camera = result_.cameras[c];
    camera.id = input_[c].id;
    camera.intrinsics = input_[c].intrinsics;
    camera.given_intrinsics = input_[c].intrinsics;
    const auto& k = input_[c].intrinsics;
    const double values[9] = {
        k.fx,           k.fy, k.cx, k.cy, k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3],
        k.distortion[4]};
    std::copy(values, values + 9, state_[c].intrinsics);
    const CameraWandTrack* track = tracks_[c];
    const int c_index = static_cast<int>(c);
    if (track == nullptr) {
      fail(c_index, "no features for this camera");
      continue;
    }
    camera.counters = track->counters;
    camera.wand_frames = static_cast<int>(track->frames.size());
    const auto& counters = track->counters;
    if (track->frames.empty()) {
      std::ostringstream why;
      if (counters.spacing_mismatches > 0 &&
          counters.spacing_mismatches * 2 >= counters.collinear_candidates) {
        why << "lengths never match: " << counters.spacing_mismatches << " frames showed "
            << wand_.marker_count()
            << " collinear blobs, but their spacing never matched the wand (2nd marker at "
            << counters.mean_mismatch_spacing << " of the bar, expected "
            << (wand_.marker_count() > 2 ? (wand_.positions[1] - wand_.positions[0]) / wand_.length() : 0.0)
            << "); check --wand";
      } else {
        why << "never saw the wand (" << counters.frames << " frames, " << counters.frames_with_enough_blobs
            << " with >= " << wand_.marker_count() << " blobs, " << counters.ambiguous << " ambiguous)";
      }
      fail(c_index, why.str());
      continue;
    }
    if (camera.wand_frames < options_.min_camera_frames) {
      fail(c_index, "too few wand observations (" + std::to_string(camera.wand_frames) + " frames, need " +
                        std::to_string(options_.min_camera_frames) + ")");
      continue;
    }
    state_[c].usable = true;
  }
}

void Solver::build_samples() {
  TimeNs first = std::numeric_limits<TimeNs>::max(), last = std::numeric_limits<TimeNs>::min();
  double period = 1e9;
  for (std::size_t c = 0; c < state_.size(); ++c) {
    if (!state_[c].usable) continue;
    first = std::min(first, tracks_[c]->frames.front().stamp_ns);
    last = std::max(last, tracks_[c]->frames.back().stamp_ns);
    if (tracks_[c]->frame_period_s > 0) period = std::min(period, tracks_[c]->frame_period_s);
  }
  if (first >= last) return;
  const double rate = options_.sample_rate_hz > 0 ? options_.sample_rate_hz : 1.0 / period;
  const auto step = static_cast<TimeNs>(std::llround(1e9 / rate));
  // Synchronised cameras (every frame stamped on one grid of that period): the instants are the
  // frames themselves, so every observation is a raw frame, not an interpolation.
  bool synchronised = options_.sample_rate_hz <= 0 && step > 0;
  for (std::size_t c = 0; c < state_.size() && synchronised; ++c) {
    if (!state_[c].usable) continue;
    for (const auto& frame : tracks_[c]->frames)
      synchronised = synchronised && (frame.stamp_ns - first) % step == 0;
  }
  result_.synchronised = synchronised;
  // Otherwise start half a step in so that instants fall between frames of cameras running at that
  // rate, where interpolation is well conditioned on both sides.
  for (TimeNs t = first + (synchronised ? 0 : step / 2); synchronised ? t <= last : t < last; t += step) {
    Sample sample;
    sample.t_ns = t;
    for (std::size_t c = 0; c < state_.size(); ++c) {
      if (!state_[c].usable) continue;
      const double max_gap = options_.max_gap_frames * tracks_[c]->frame_period_s;
      if (auto segment = find_segment(*tracks_[c], t, max_gap))
        sample.observations.push_back({static_cast<int>(c), std::move(*segment), 0.0, true});
    }
    if (sample.observations.size() >= 2) samples_.push_back(std::move(sample));
  }
  progress("wand samples: " + std::to_string(samples_.size()) + " instants seen by >= 2 cameras" +
           (synchronised ? " (synchronised cameras: the frames themselves)" : " (interpolated)"));
}

void Solver::pairwise() {
  const int n = static_cast<int>(state_.size());
  const std::size_t markers = wand_.marker_count();
  // Common samples per pair.
  std::map<std::pair<int, int>, std::vector<std::pair<const Observation*, const Observation*>>> common;
  for (const auto& sample : samples_)
    for (std::size_t i = 0; i < sample.observations.size(); ++i)
      for (std::size_t j = i + 1; j < sample.observations.size(); ++j) {
        const auto& a = sample.observations[i];
        const auto& b = sample.observations[j];
        common[{std::min(a.camera, b.camera), std::max(a.camera, b.camera)}].push_back(
            a.camera < b.camera ? std::make_pair(&a, &b) : std::make_pair(&b, &a));
      }
  int done = 0;
  for (auto& [key, list] : common) {
    const auto [a, b] = key;
    PairEdge edge;
    edge.camera_a = input_[a].id;
    edge.camera_b = input_[b].id;
    edge.samples = static_cast<int>(list.size());
    if (edge.samples < options_.min_pair_samples) {
      result_.edges.push_back(edge);
      continue;
    }
    const CameraModel model_a(input_[a].intrinsics, RigidTransform{});
    const CameraModel model_b(input_[b].intrinsics, RigidTransform{});
    const std::size_t stride =
        std::max<std::size_t>(1, list.size() / static_cast<std::size_t>(options_.max_pair_samples));
    std::vector<cv::Point2d> points_a, points_b;
    std::vector<std::size_t> sample_of;
    for (std::size_t s = 0; s < list.size(); s += stride)
      for (std::size_t m = 0; m < markers; ++m) {
        const Eigen::Vector2d xa = model_a.pixel_to_normalized(observed(*list[s].first, m));
        const Eigen::Vector2d xb = model_b.pixel_to_normalized(observed(*list[s].second, m));
        points_a.emplace_back(xa.x(), xa.y());
        points_b.emplace_back(xb.x(), xb.y());
        sample_of.push_back(s);
      }
    const double focal = 0.25 * (input_[a].intrinsics.fx + input_[a].intrinsics.fy + input_[b].intrinsics.fx +
                                 input_[b].intrinsics.fy);
    cv::Mat mask;
    const cv::Mat E = cv::findEssentialMat(points_a, points_b, 1.0, cv::Point2d(0, 0), cv::RANSAC, 0.999,
                                           options_.ransac_threshold_px / focal, mask);
    if (E.rows != 3 || E.cols != 3) {
      result_.edges.push_back(edge);
      continue;
    }
    cv::Mat R, t;
    const int inliers = cv::recoverPose(E, points_a, points_b, R, t, 1.0, cv::Point2d(0, 0), mask);
    edge.inliers = inliers;
    if (inliers < std::max<int>(8, static_cast<int>(0.5 * static_cast<double>(points_a.size())))) {
      result_.edges.push_back(edge);
      continue;
    }
    Eigen::Matrix3d R_ba;
    Eigen::Vector3d t_ba;
    for (int r = 0; r < 3; ++r) {
      t_ba[r] = t.at<double>(r);
      for (int c = 0; c < 3; ++c) R_ba(r, c) = R.at<double>(r, c);
    }
    // Two-view reconstruction in a's frame with unit baseline: residual and wand scale.
    RigidTransform T_world_a;  // a at the origin
    RigidTransform T_world_b;
    T_world_b.q = Eigen::Quaterniond(R_ba.transpose());
    T_world_b.t = -R_ba.transpose() * t_ba;
    const CameraModel ma(input_[a].intrinsics, T_world_a), mb(input_[b].intrinsics, T_world_b);
    double squared = 0;
    int count = 0;
    std::vector<double> lengths;
    for (std::size_t s = 0; s < list.size(); s += stride) {
      std::vector<Eigen::Vector3d> X;
      bool all = true;
      for (std::size_t m = 0; m < markers; ++m) {
        const Eigen::Vector2d pa = observed(*list[s].first, m), pb = observed(*list[s].second, m);
        const auto x = triangulate({ma, mb}, {pa, pb});
        if (!x) {
          all = false;
          continue;
        }
        const double ea = (*ma.project(*x) - pa).squaredNorm(), eb = (*mb.project(*x) - pb).squaredNorm();
        if (ea + eb > 25.0 * options_.ransac_threshold_px * options_.ransac_threshold_px) {
          all = false;
          continue;
        }
        squared += ea + eb;
        count += 2;
        X.push_back(*x);
      }
      if (all && markers >= 2) lengths.push_back((X.back() - X.front()).norm());
    }
    if (count == 0) {
      result_.edges.push_back(edge);
      continue;
    }
    edge.residual_px = std::sqrt(squared / count);
    if (!lengths.empty()) {
      std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
      edge.scale = wand_.length() / lengths[lengths.size() / 2];
    }
    PairPose pose;
    pose.a = a;
    pose.b = b;
    pose.R_ab = R_ba.transpose();
    pose.c_b = -R_ba.transpose() * t_ba * (edge.scale > 0 ? edge.scale : 1.0);
    // Seed 003 §3.3.1 ranks pairs by their structure-from-motion residual; few correspondences
    // make a residual look better than it is, so pairs under 100 inliers are penalised.
    pose.score = (edge.residual_px + 0.01) * std::sqrt(100.0 / std::min(100, inliers));
    pose.edge_index = result_.edges.size();
    result_.edges.push_back(edge);
    pairs_.push_back(pose);
    if (++done % 10 == 0) progress("pairwise relative poses: " + std::to_string(done) + " pairs");
  }
  progress("pairwise relative poses: " + std::to_string(pairs_.size()) + " of " +
           std::to_string(common.size()) + " camera pairs with common samples");
  (void)n;
}

void Solver::unify() {
  const int n = static_cast<int>(state_.size());
  // Connected components of the view graph.
  UnionFind view_graph(static_cast<std::size_t>(n));
  // b's root stays the root (the components below are keyed by it).
  for (const auto& pair : pairs_)
    view_graph.unite(static_cast<std::size_t>(pair.b), static_cast<std::size_t>(pair.a));
  const auto find = [&](int c) { return static_cast<int>(view_graph.find(static_cast<std::size_t>(c))); };
  std::map<int, std::vector<int>> components;
  std::map<int, int> degree;
  for (const auto& pair : pairs_) {
    ++degree[pair.a];
    ++degree[pair.b];
  }
  for (int c = 0; c < n; ++c)
    if (state_[c].usable) components[find(c)].push_back(c);
  // The reference: asked for, else the camera with most pairs in the largest component.
  int main_root = -1;
  std::size_t best_size = 0;
  for (const auto& [root, members] : components)
    if (members.size() > best_size) {
      best_size = members.size();
      main_root = root;
    }
  if (!options_.reference_camera.empty()) {
    for (int c = 0; c < n; ++c)
      if (input_[c].id == options_.reference_camera && state_[c].usable) main_root = find(c);
  }
  if (main_root < 0) return;
  for (const auto& [root, members] : components) {
    if (root == main_root) continue;
    std::vector<std::string> names, main_names;
    for (int c : members) names.push_back(input_[c].id);
    for (int c : components[main_root]) main_names.push_back(input_[c].id);
    const std::string reason = members.size() == 1 && degree[members[0]] == 0
                                   ? "shares too few wand samples with any other camera (need " +
                                         std::to_string(options_.min_pair_samples) + " for a relative pose)"
                                   : "disconnected view graph: {" + join(names) +
                                         "} share no usable wand samples with {" + join(main_names) + "}";
    for (int c : members) fail(c, reason);
  }
  for (int c : components[main_root]) {
    if (input_[c].id == options_.reference_camera) reference_ = c;
  }
  if (reference_ < 0) {
    int best = -1;
    for (int c : components[main_root])
      if (best < 0 || degree[c] > degree[best]) best = c;
    reference_ = best;
  }
  result_.reference_camera = input_[reference_].id;

  std::vector<Eigen::Matrix3d> R_world_cam(n, Eigen::Matrix3d::Identity());
  std::vector<Eigen::Vector3d> center(n, Eigen::Vector3d::Zero());
  state_[reference_].registered = true;
  const bool metric = wand_.marker_count() >= 2;
  int registered = 1;
  while (true) {
    // Candidates: unregistered cameras with a pair to a registered one; the best-ranked pair wins.
    int next = -1;
    double next_score = 1e300;
    for (const auto& pair : pairs_) {
      const bool a_in = state_[pair.a].registered, b_in = state_[pair.b].registered;
      if (a_in == b_in) continue;
      const int candidate = a_in ? pair.b : pair.a;
      if (!state_[candidate].usable) continue;
      int neighbours = 0;
      for (const auto& other : pairs_)
        if ((other.a == candidate && state_[other.b].registered) ||
            (other.b == candidate && state_[other.a].registered))
          ++neighbours;
      // A single light gives no scale: place by intersecting rays from two registered cameras
      // (seed 003 §3.3.1), or along the first pair's unit baseline.
      if (!metric && neighbours < 2 && registered > 1) continue;
      if (pair.score < next_score) {
        next_score = pair.score;
        next = candidate;
      }
    }
    if (next < 0) break;
    // Every pair to a registered camera votes, weighted by its rank.
    Eigen::Vector4d q_sum = Eigen::Vector4d::Zero();
    Eigen::Vector3d c_sum = Eigen::Vector3d::Zero();
    double w_sum = 0;
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    std::optional<Eigen::Quaterniond> first_q;
    for (auto& pair : pairs_) {
      int known;
      Eigen::Matrix3d R_known_next;
      Eigen::Vector3d c_next_in_known;
      if (pair.a == next && state_[pair.b].registered) {
        known = pair.b;
        R_known_next = pair.R_ab.transpose();
        c_next_in_known = -pair.R_ab.transpose() * pair.c_b;
      } else if (pair.b == next && state_[pair.a].registered) {
        known = pair.a;
        R_known_next = pair.R_ab;
        c_next_in_known = pair.c_b;
      } else {
        continue;
      }
      const double w = 1.0 / (pair.score * pair.score);
      Eigen::Quaterniond q(R_world_cam[known] * R_known_next);
      if (!first_q) first_q = q;
      if (first_q->coeffs().dot(q.coeffs()) < 0) q.coeffs() *= -1;
      q_sum += w * q.coeffs();
      // Seed 003 eq. 3.4: T_WC = T_WA + alpha R_WA T_AC. With a metric wand alpha is known.
      const Eigen::Vector3d direction = R_world_cam[known] * c_next_in_known;
      c_sum += w * (center[known] + direction);
      w_sum += w;
      const Eigen::Vector3d d = direction.normalized();
      const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d * d.transpose();
      A += w * P;
      b += w * P * center[known];
      result_.edges[pair.edge_index].used = true;
    }
    R_world_cam[next] = Eigen::Quaterniond(q_sum.normalized()).toRotationMatrix();
    if (metric || registered == 1) {
      center[next] = c_sum / w_sum;
    } else {
      center[next] = A.ldlt().solve(b);  // closest point to all rays
    }
    state_[next].registered = true;
    ++registered;
  }
  for (int c = 0; c < n; ++c) {
    if (!state_[c].usable) continue;
    if (!state_[c].registered) {
      fail(c, metric
                  ? "could not be placed from its pairwise relative poses"
                  : "connected to only one calibrated camera: a single light gives no scale for that pair");
      continue;
    }
    RigidTransform T_world_cam;
    T_world_cam.q = Eigen::Quaterniond(R_world_cam[c]);
    T_world_cam.t = center[c];
    set_pose(T_world_cam, state_[c].pose);
  }
  progress("global unification: " + std::to_string(registered) + " cameras placed, reference " +
           result_.reference_camera);
}

void Solver::triangulate_all() {
  const std::size_t markers = wand_.marker_count();
  points_.assign(samples_.size() * markers * 3, 0.0);
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    auto& sample = samples_[s];
    std::vector<CameraModel> models;
    std::vector<const Observation*> used;
    for (auto& observation : sample.observations) {
      if (!state_[observation.camera].registered) observation.active = false;
      if (!observation.active) continue;
      models.push_back(model_of(observation.camera));
      used.push_back(&observation);
    }
    for (std::size_t m = 0; m < markers; ++m) {
      std::vector<Eigen::Vector2d> pixels;
      pixels.reserve(used.size());
      for (const auto* observation : used) pixels.push_back(observed(*observation, m));
      const auto x = triangulate(models, pixels);
      if (!x) {
        for (auto& observation : sample.observations) observation.active = false;
        break;
      }
      std::copy(x->data(), x->data() + 3, &points_[(s * markers + m) * 3]);
    }
  }
}

// One bundle adjustment pass (or seed 003's alternation). Returns the reprojection RMS.
// A robust pass (Huber loss) starts from the unified poses, with outliers still in: Ceres handles
// the loss by reweighting, which converges only linearly near the minimum (each iteration gains a
// fixed fraction), so it stops at Ceres's default relative cost change (1e-6): its result only
// seeds the outlier test. After the outliers are gone the passes are plain least squares, which
// converge quadratically to the tight tolerance.
double Solver::adjust(bool alternation, bool robust) {
  const std::size_t markers = wand_.marker_count();
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::LossFunction* loss = robust ? new ceres::HuberLoss(options_.huber_px) : nullptr;
  std::vector<double*> point_blocks;
  std::set<int> cameras_in_problem;
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    auto& sample = samples_[s];
    int active = 0;
    for (const auto& observation : sample.observations) active += observation.active ? 1 : 0;
    if (active < 2) continue;
    for (const auto& observation : sample.observations) {
      if (!observation.active) continue;
      CameraState& camera = state_[observation.camera];
      cameras_in_problem.insert(observation.camera);
      for (std::size_t m = 0; m < markers; ++m)
        problem.AddResidualBlock(make_reprojection(markers, marker_segment(observation.segment, m),
                                                   observation.shift_s, static_cast<int>(m)),
                                 loss, camera.pose, camera.intrinsics, &camera.offset,
                                 &points_[s * markers * 3]);
    }
    point_blocks.push_back(&points_[s * markers * 3]);
    // Wand-length residuals between every pair of markers: they fix the scale and, with three
    // or more markers, keep the bar straight (seed 000 eq. 4.76).
    for (std::size_t i = 0; i < markers; ++i)
      for (std::size_t j = i + 1; j < markers; ++j)
        problem.AddResidualBlock(
            make_length(markers, static_cast<int>(i), static_cast<int>(j),
                        wand_.positions[j] - wand_.positions[i], 1.0 / options_.length_sigma_m),
            nullptr, &points_[s * markers * 3]);
  }
  if (markers < 2) {
    // Gauge of scale for a single light: the distance from the reference to its nearest camera.
    int nearest = -1;
    double best = 1e300;
    const Eigen::Vector3d c_ref = pose_to_T_world_cam(state_[reference_].pose).t;
    for (int c : cameras_in_problem) {
      if (c == reference_) continue;
      const double d = (pose_to_T_world_cam(state_[c].pose).t - c_ref).norm();
      if (d < best) {
        best = d;
        nearest = c;
      }
    }
    if (nearest >= 0)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<DistanceCost, 1, 6, 6>(new DistanceCost{best}),
                               nullptr, state_[reference_].pose, state_[nearest].pose);
  }
  for (int c : cameras_in_problem) {
    CameraState& camera = state_[c];
    if (c == reference_) problem.SetParameterBlockConstant(camera.pose);
    if (intrinsics_ == IntrinsicsRefinement::kNone) problem.SetParameterBlockConstant(camera.intrinsics);
    // Automatic refinement: only along the directions the data determines (docs/calibration.md).
    if (intrinsics_ == IntrinsicsRefinement::kNominal || intrinsics_ == IntrinsicsRefinement::kSuspect)
      problem.SetManifold(camera.intrinsics, refinement_manifold(camera.intrinsics, intrinsics_));
    if (!options_.time_offsets || c == reference_) problem.SetParameterBlockConstant(&camera.offset);
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.max_num_iterations = options_.max_iterations;
  solver_options.num_threads = options_.threads;
  solver_options.function_tolerance = robust ? 1e-6 : 1e-10;
  solver_options.parameter_tolerance = 1e-10;
  solver_options.gradient_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  if (!alternation) {
    ceres::Solve(solver_options, &problem, &summary);
    result_.iterations += static_cast<int>(summary.iterations.size());
    const bool converged = summary.termination_type == ceres::CONVERGENCE;
    ++passes_;
    if (!converged && result_.convergence.empty())
      result_.convergence = "pass " + std::to_string(passes_) + " did not converge after " +
                            std::to_string(summary.iterations.size() - 1) + " iterations (" +
                            summary.message + ")";
    pass_iterations_ +=
        (pass_iterations_.empty() ? "" : ", ") + std::to_string(summary.iterations.size() - 1);
    all_converged_ = all_converged_ && converged;
  } else {
    // Seed 003 §3.3.2: the reconstructed trace is a virtual calibration object; each camera is
    // re-calibrated against it, then the trace is rebuilt, and so on.
    solver_options.max_num_iterations = 20;
    for (int iteration = 0; iteration < options_.alternation_iterations; ++iteration) {
      for (double* block : point_blocks) problem.SetParameterBlockConstant(block);
      for (int c : cameras_in_problem) {
        if (c != reference_) problem.SetParameterBlockVariable(state_[c].pose);
        if (options_.time_offsets && c != reference_) problem.SetParameterBlockVariable(&state_[c].offset);
      }
      ceres::Solve(solver_options, &problem, &summary);
      for (double* block : point_blocks) problem.SetParameterBlockVariable(block);
      for (int c : cameras_in_problem) {
        problem.SetParameterBlockConstant(state_[c].pose);
        if (options_.time_offsets && c != reference_) problem.SetParameterBlockConstant(&state_[c].offset);
      }
      ceres::Solve(solver_options, &problem, &summary);
      result_.iterations += 1;
    }
  }
  const double rms = std::sqrt(2.0 * summary.final_cost / std::max(1, summary.num_residuals));
  progress("bundle adjustment: " + std::to_string(summary.iterations.size()) + " iterations, " +
           std::to_string(summary.num_residual_blocks) + " residual blocks, cost " +
           std::to_string(summary.initial_cost) + " -> " + std::to_string(summary.final_cost) + " (" +
           summary.message + ")");
  return rms;
}

void Solver::finish() {
  const std::size_t markers = wand_.marker_count();
  const int n = static_cast<int>(state_.size());
  // Per-camera statistics over the final residuals.
  std::vector<double> squared(n, 0.0);
  std::vector<int> count(n, 0);
  double total = 0;
  int total_count = 0;
  std::vector<CameraModel> models(n);
  for (int c = 0; c < n; ++c)
    if (state_[c].registered) models[c] = model_of(c);
  std::vector<double> length_errors;
  std::vector<std::vector<double>> spacing_errors;  // per consecutive marker pair, m
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    const auto& sample = samples_[s];
    std::vector<const Observation*> active;
    for (const auto& observation : sample.observations)
      if (observation.active) active.push_back(&observation);
    if (active.size() < 2) continue;
    WandSample out;
    out.t_ns = sample.t_ns;
    out.cameras = static_cast<int>(active.size());
    std::vector<Eigen::Vector3d> free_points;
    for (std::size_t m = 0; m < markers; ++m) {
      const Eigen::Vector3d X(&points_[(s * markers + m) * 3]);
      out.markers.push_back(X);
      std::vector<CameraModel> used;
      std::vector<Eigen::Vector2d> pixels;
      for (const auto* observation : active) {
        const Eigen::Vector2d pixel = observed(*observation, m);
        const auto projected = models[observation->camera].project(X);
        if (!projected) continue;
        const Eigen::Vector2d error = *projected - pixel;
        squared[observation->camera] += error.squaredNorm();
        count[observation->camera] += 1;
        auto& camera = result_.cameras[observation->camera];
        camera.max_px = std::max(camera.max_px, error.norm());
        total += error.squaredNorm();
        ++total_count;
        result_.residuals.push_back({observation->camera, static_cast<int>(m), sample.t_ns, pixel, error});
        used.push_back(models[observation->camera]);
        pixels.push_back(pixel);
      }
      if (auto x = triangulate(used, pixels)) free_points.push_back(*x);
    }
    // The wand length as the calibrated cameras measure it, without the length constraint.
    if (markers >= 2 && free_points.size() == markers) {
      length_errors.push_back(((free_points.back() - free_points.front()).norm() - wand_.length()) * 1e3);
      spacing_errors.resize(markers - 1);
      for (std::size_t m = 0; m + 1 < markers; ++m)
        spacing_errors[m].push_back((free_points[m + 1] - free_points[m]).norm() -
                                    (wand_.positions[m + 1] - wand_.positions[m]));
    }
    result_.samples.push_back(std::move(out));
  }
  for (int c = 0; c < n; ++c) {
    auto& camera = result_.cameras[c];
    camera.observations = count[c];
    camera.rms_px = count[c] > 0 ? std::sqrt(squared[c] / count[c]) : 0.0;
    if (state_[c].registered) {
      camera.T_world_cam = pose_to_T_world_cam(state_[c].pose);
      camera.intrinsics = to_intrinsics(state_[c].intrinsics, input_[c].intrinsics);
      camera.time_offset_s = state_[c].offset;
    }
  }
  result_.rms_px = total_count > 0 ? std::sqrt(total / total_count) : 0.0;
  raw_residuals(models);
  if (!length_errors.empty()) {
    auto& stats = result_.lengths;
    stats.count = static_cast<int>(length_errors.size());
    stats.mean_error_mm = std::accumulate(length_errors.begin(), length_errors.end(), 0.0) / stats.count;
    double variance = 0;
    for (double e : length_errors) {
      variance += (e - stats.mean_error_mm) * (e - stats.mean_error_mm);
      stats.max_abs_error_mm = std::max(stats.max_abs_error_mm, std::abs(e));
    }
    stats.sigma_mm = std::sqrt(variance / std::max(1, stats.count - 1));
  }
  // Spacing check: the distances between neighbouring markers, as the calibrated cameras measure
  // them without the length constraint, against --wand. A wrong --wand cannot be fitted: the
  // adjustment splits the difference and the free measurements show it.
  for (std::size_t m = 0; m < spacing_errors.size(); ++m) {
    const auto& errors = spacing_errors[m];
    if (errors.size() < 10) continue;
    const double mean =
        std::accumulate(errors.begin(), errors.end(), 0.0) / static_cast<double>(errors.size());
    const double given = wand_.positions[m + 1] - wand_.positions[m];
    if (std::abs(mean) > std::max(0.002, 0.005 * given)) {
      std::string ids;
      for (int c = 0; c < n; ++c)
        if (state_[c].registered) ids += (ids.empty() ? "" : ", ") + input_[c].id;
      std::ostringstream why;
      why.precision(4);
      why << "wand lengths never match: markers " << m << "-" << m + 1 << " measure " << given + mean
          << " m, --wand says " << given << " m; cameras " << ids
          << " are not calibrated (check --wand and the wand itself)";
      result_.errors.push_back(why.str());
      for (int c = 0; c < n; ++c)
        if (state_[c].registered) {
          result_.cameras[c].failure = "lengths never match --wand";
          result_.cameras[c].T_world_cam.reset();
        }
      break;
    }
  }
}

ErrorStats error_stats(std::vector<double> errors) {
  ErrorStats stats;
  stats.count = static_cast<int>(errors.size());
  if (errors.empty()) return stats;
  double sum = 0, squared = 0;
  int within = 0;
  for (double e : errors) {
    sum += e;
    squared += e * e;
    within += e <= 5.0 ? 1 : 0;
  }
  const auto n = static_cast<double>(errors.size());
  stats.mean_px = sum / n;
  stats.rms_axis_px = std::sqrt(squared / (2 * n));
  stats.within_5px = within / n;
  const std::size_t half = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(half), errors.end());
  stats.median_px = errors[half];
  if (errors.size() % 2 == 0)
    stats.median_px =
        0.5 * (stats.median_px +
               *std::max_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(half)));
  return stats;
}

// Every raw wand frame against the wand path at the frame's instant on the reference clock: the
// sample itself where the frame is one (synchronised cameras), else interpolated (cubic Hermite
// over the samples). 2D errors per camera, px, per marker observation.
std::vector<std::vector<double>> Solver::raw_errors(const std::vector<CameraModel>& models) const {
  const std::size_t markers = wand_.marker_count();
  std::vector<std::vector<double>> errors(state_.size());
  std::vector<TimeNs> times;
  std::vector<bool> valid;
  for (const auto& sample : samples_) {
    int active = 0;
    for (const auto& observation : sample.observations) active += observation.active ? 1 : 0;
    times.push_back(sample.t_ns);
    valid.push_back(active >= 2);
  }
  if (times.size() < 4) return errors;
  const TimeNs step = times[1] - times[0];
  for (std::size_t c = 0; c < state_.size(); ++c) {
    if (!state_[c].registered || tracks_[c] == nullptr) continue;
    for (const auto& frame : tracks_[c]->frames) {
      const TimeNs t = frame.stamp_ns - static_cast<TimeNs>(std::llround(state_[c].offset * 1e9));
      const auto after = std::upper_bound(times.begin(), times.end(), t);
      if (after == times.begin()) continue;
      const std::size_t i = static_cast<std::size_t>(after - times.begin()) - 1;
      const bool exact = times[i] == t;
      if (exact && !valid[i]) continue;
      if (!exact) {
        if (i < 1 || i + 2 >= times.size()) continue;
        bool usable = true;
        for (std::size_t k = i - 1; k <= i + 2; ++k) usable = usable && valid[k];
        for (std::size_t k = i - 1; k < i + 2; ++k) usable = usable && times[k + 1] - times[k] == step;
        if (!usable) continue;
      }
      const double tau = static_cast<double>(t - times[i]) / static_cast<double>(step);
      const double tau2 = tau * tau, tau3 = tau2 * tau;
      const double h00 = 2 * tau3 - 3 * tau2 + 1, h10 = tau3 - 2 * tau2 + tau, h01 = -2 * tau3 + 3 * tau2,
                   h11 = tau3 - tau2;
      for (std::size_t m = 0; m < markers; ++m) {
        const auto point = [&](std::size_t k) { return Eigen::Vector3d(&points_[(k * markers + m) * 3]); };
        const Eigen::Vector3d X =
            exact ? point(i)
                  : Eigen::Vector3d(h00 * point(i) + h10 * 0.5 * (point(i + 1) - point(i - 1)) +
                                    h01 * point(i + 1) + h11 * 0.5 * (point(i + 2) - point(i)));
        const auto projected = models[c].project(X);
        if (!projected) continue;
        errors[c].push_back((*projected - frame.pixels[m]).norm());
      }
    }
  }
  return errors;
}

// Raw-frame statistics per camera and overall: every frame, and the inliers (kRawInlierPx).
void Solver::raw_residuals(const std::vector<CameraModel>& models) {
  const auto errors = raw_errors(models);
  std::vector<double> all, inliers;
  for (std::size_t c = 0; c < errors.size(); ++c) {
    if (!state_[c].registered) continue;
    std::vector<double> camera_inliers;
    for (double e : errors[c])
      if (e <= kRawInlierPx) camera_inliers.push_back(e);
    auto& camera = result_.cameras[c];
    camera.raw_all = error_stats(errors[c]);
    camera.raw_inliers = error_stats(camera_inliers);
    camera.raw_observations = camera.raw_inliers.count;
    camera.raw_rms_axis_px = camera.raw_inliers.rms_axis_px;
    all.insert(all.end(), errors[c].begin(), errors[c].end());
    inliers.insert(inliers.end(), camera_inliers.begin(), camera_inliers.end());
  }
  result_.raw_all = error_stats(std::move(all));
  result_.raw_inliers = error_stats(std::move(inliers));
  result_.raw_rms_axis_px = result_.raw_inliers.rms_axis_px;
}

std::vector<CameraModel> Solver::registered_models() const {
  std::vector<CameraModel> models(state_.size());
  for (std::size_t c = 0; c < state_.size(); ++c)
    if (state_[c].registered) models[c] = model_of(static_cast<int>(c));
  return models;
}

// Intrinsics are refined when asked (all nine), when the cameras file marks them nominal (focal
// length, k1, k2), or when the first adjustment leaves raw-frame errors far above any centroid
// noise (fx, fy, cx, cy, k1, k2).
void Solver::decide_intrinsics(double rms) {
  if (options_.refine_intrinsics) {
    intrinsics_ = IntrinsicsRefinement::kAll;
    result_.intrinsics_refined = "--refine-intrinsics";
    return;
  }
  if (!options_.auto_intrinsics || intrinsics_ != IntrinsicsRefinement::kNone) return;
  if (rms < 0) {  // before the first adjustment
    std::vector<std::string> nominal;
    for (std::size_t c = 0; c < state_.size(); ++c)
      if (state_[c].registered && input_[c].nominal_intrinsics) nominal.push_back(input_[c].id);
    if (nominal.empty()) return;
    intrinsics_ = IntrinsicsRefinement::kNominal;
    result_.intrinsics_refined = "nominal intrinsics (" + join(nominal) + "): focal length, k1, k2";
    return;
  }
  std::vector<double> all;
  for (const auto& errors : raw_errors(registered_models()))
    all.insert(all.end(), errors.begin(), errors.end());
  const double median = error_stats(all).median_px;
  if (all.empty() || median <= options_.intrinsics_suspect_px) return;
  // The principal point and the aspect ratio need many views: with fewer than
  // kMinCamerasForCentre cameras only the focal length and k1, k2 move (on the real 4-camera set,
  // freeing cx, cy, fx/fy too left the adjustment crawling to the iteration cap).
  const auto cameras =
      std::count_if(state_.begin(), state_.end(), [](const CameraState& c) { return c.registered; });
  const bool centre = cameras >= kMinCamerasForCentre;
  intrinsics_ = centre ? IntrinsicsRefinement::kSuspect : IntrinsicsRefinement::kNominal;
  char why[240];
  std::snprintf(why, sizeof(why),
                "raw-frame error median %.2f px (2D) after the first adjustment, above %.2f px: the given "
                "intrinsics do not fit; %s",
                median, options_.intrinsics_suspect_px,
                centre ? "fx, fy, cx, cy, k1, k2" : "focal length, k1, k2 (fewer than 8 cameras)");
  result_.intrinsics_refined = why;
}

// Pass 1 from the unified start; then outliers (mislabelled frames, reflections) go, and with
// clock offsets the tracks are looked up again at the shifted instants. Intrinsics suspected after
// pass 1 are refined in an extra pass before any outlier is judged.
void Solver::adjust_passes() {
  decide_intrinsics(-1);
  double rms = adjust(false);
  if (intrinsics_ == IntrinsicsRefinement::kNone) {
    decide_intrinsics(rms);
    if (intrinsics_ != IntrinsicsRefinement::kNone) {
      progress("refining intrinsics: " + result_.intrinsics_refined);
      rms = adjust(false);
    }
  }
  const int passes = options_.time_offsets ? 3 : 2;
  const std::size_t markers = wand_.marker_count();
  for (int pass = 1; pass < passes; ++pass) {
    const double limit = std::max(5.0 * rms, 3.0 * options_.huber_px);
    int removed = 0;
    for (std::size_t s = 0; s < samples_.size(); ++s) {
      for (auto& observation : samples_[s].observations) {
        if (!observation.active) continue;
        const CameraModel model = model_of(observation.camera);
        for (std::size_t m = 0; m < markers; ++m) {
          const auto projected = model.project(Eigen::Vector3d(&points_[(s * markers + m) * 3]));
          if (!projected || (*projected - observed(observation, m)).norm() > limit) {
            observation.active = false;
            ++removed;
            break;
          }
        }
        if (options_.time_offsets && observation.active) {
          const double offset = state_[observation.camera].offset;
          const TimeNs shift = static_cast<TimeNs>(std::llround(offset * 1e9));
          const double max_gap = options_.max_gap_frames * tracks_[observation.camera]->frame_period_s;
          if (auto segment = find_segment(*tracks_[observation.camera], samples_[s].t_ns + shift, max_gap)) {
            observation.segment = std::move(*segment);
            observation.shift_s = static_cast<double>(shift) * 1e-9;
          }
        }
      }
    }
    progress("pass " + std::to_string(pass + 1) + ": " + std::to_string(removed) +
             " outlier observations removed");
    rms = adjust(false, false);
  }
  result_.converged = all_converged_;
  if (all_converged_) result_.convergence = "converged in every pass";
  result_.convergence += " (iterations per pass: " + pass_iterations_ + ")";
}

// Refined focal lengths far from the given ones mean the given intrinsics were wrong, not just
// imprecise: such a camera is not calibrated, and the message says what to check.
void Solver::check_focal_lengths() {
  if (intrinsics_ == IntrinsicsRefinement::kNone) return;
  for (std::size_t c = 0; c < state_.size(); ++c) {
    if (!state_[c].registered) continue;
    result_.cameras[c].intrinsics_refined = true;
    const auto& given = input_[c].intrinsics;
    const double fx = state_[c].intrinsics[0], fy = state_[c].intrinsics[1];
    const double factor = std::max({fx / given.fx, given.fx / fx, fy / given.fy, given.fy / fy});
    if (!(factor <= options_.max_focal_factor)) {
      char why[400];
      std::snprintf(
          why, sizeof(why),
          "focal length %.0f x %.0f px fits the data, the cameras file gives %.0f x %.0f px (a factor "
          "%.2f, more than %.1f): check K (fx, fy = lens focal length / pixel pitch, in pixels of the "
          "%d x %d image) and the image size",
          fx, fy, given.fx, given.fy, factor, options_.max_focal_factor, given.width, given.height);
      fail(static_cast<int>(c), why);
      for (auto& sample : samples_)
        for (auto& observation : sample.observations)
          if (observation.camera == static_cast<int>(c)) observation.active = false;
    }
  }
}

SolveResult Solver::run() {
  const auto start = Clock::now();
  if (const std::string problem = wand_.validate(); !problem.empty()) {
    result_.errors.push_back("wand: " + problem);
    return result_;
  }
  result_.metric = wand_.marker_count() >= 2;
  if (wand_.ends_indistinguishable()) resolve_labels();
  check_cameras();
  build_samples();
  pairwise();
  unify();
  if (reference_ >= 0) {
    triangulate_all();
    if (options_.alternation_iterations > 0) {
      adjust(true);
    } else {
      adjust_passes();
      check_focal_lengths();
    }
    finish();
    // Provisional world frame: z up from the cameras' layout (docs/calibration.md); `calibrate
    // world` replaces it with the floor or an L-frame.
    std::vector<RigidTransform> poses;
    std::vector<Eigen::Vector3d> points;
    for (const auto& camera : result_.cameras)
      if (camera.T_world_cam) poses.push_back(*camera.T_world_cam);
    for (const auto& sample : result_.samples)
      for (const auto& p : sample.markers) points.push_back(p);
    const RigidTransform T_new_old = provisional_world_frame(poses, points);
    apply_world_transform(result_, T_new_old);
  }
  for (const auto& camera : result_.cameras)
    if (!camera.failure.empty()) result_.errors.push_back(camera.id + ": " + camera.failure);
  result_.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result_;
}

}  // namespace

SolveResult solve_wand_calibration(const std::vector<CameraCalibration>& cameras,
                                   const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand,
                                   const SolveOptions& options) {
  Solver solver(cameras, tracks, wand, options);
  return solver.run();
}

}  // namespace panoptes::calib
