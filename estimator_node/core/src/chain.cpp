// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/chain.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace panoptes::estimator {

namespace {

const Eigen::Vector3d kJointAxis = Eigen::Vector3d::UnitZ();

Eigen::Vector3d planar_direction(double angle) {
  return {std::cos(angle), std::sin(angle), 0.0};
}

double wrap_angle(double angle) {
  return std::atan2(std::sin(angle), std::cos(angle));
}

// A body state carrying the base's motion, for body_transition (which reads only ω and α).
BodyState base_motion(const ChainState& state) {
  BodyState base;
  base.w = state.w;
  base.alpha = state.alpha;
  return base;
}

}  // namespace

ChainShape chain_shape(const ChainDefinition& chain, const JointVector& angles) {
  ChainShape shape;
  shape.marker_count = chain.marker_count();
  shape.markers[0].setZero();
  double heading = 0.0;
  for (int k = 1; k < shape.marker_count; ++k) {
    if (k >= 2) heading += angles(k - 2);
    shape.markers[k] = shape.markers[k - 1] + chain.link_lengths_m[k - 1] * planar_direction(heading);
  }
  // The tip offset lives in the last link's frame (rotated by the sum of all joint angles).
  shape.tip = shape.markers[shape.marker_count - 1] +
              Eigen::AngleAxisd(heading, kJointAxis).toRotationMatrix() * chain.tip_offset_m;
  return shape;
}

FilterCovariance<kChainStateSize> chain_prior(const ChainPriorSigmas& sigmas, int joint_count) {
  ChainVector variances = ChainVector::Zero();
  variances.head<kBodyStateSize>() = body_prior(sigmas.base).matrix().diagonal();
  for (int j = 0; j < joint_count; ++j) {
    variances(kChainAngle + j) = sigmas.angle_rad * sigmas.angle_rad;
    variances(kChainRate + j) = sigmas.rate_radps * sigmas.rate_radps;
  }
  return FilterCovariance<kChainStateSize>::diagonal(variances);
}

void predict(ChainState& state, TimeNs stamp_ns, const ChainMotionNoise& noise, int joint_count) {
  const double dt = ns_to_seconds(stamp_ns - state.stamp_ns);
  if (dt != 0.0) {
    ChainMatrix A = ChainMatrix::Identity();
    A.topLeftCorner<kBodyStateSize, kBodyStateSize>() = body_transition(base_motion(state), dt);
    ChainMatrix Q = ChainMatrix::Zero();
    Q.topLeftCorner<kBodyStateSize, kBodyStateSize>() = body_process_noise(dt, noise.base);
    // Each joint: constant rate driven by white angular acceleration (seed 003 eq. A.28's pair).
    const double sign = dt < 0 ? -1.0 : 1.0;
    for (int j = 0; j < joint_count; ++j) {
      A(kChainAngle + j, kChainRate + j) = dt;
      Q(kChainAngle + j, kChainAngle + j) = sign * noise.joint_accel * dt * dt * dt / 3.0;
      Q(kChainAngle + j, kChainRate + j) = sign * noise.joint_accel * dt * dt / 2.0;
      Q(kChainRate + j, kChainAngle + j) = sign * noise.joint_accel * dt * dt / 2.0;
      Q(kChainRate + j, kChainRate + j) = sign * noise.joint_accel * dt;
    }
    state.p += dt * state.v + 0.5 * dt * dt * state.a;
    state.v += dt * state.a;
    state.q =
        (state.q * rotation_vector_to_quaternion(dt * state.w + 0.5 * dt * dt * state.alpha)).normalized();
    state.w += dt * state.alpha;
    state.angles += dt * state.rates;
    state.P.propagate(A, Q);
  }
  state.stamp_ns = stamp_ns;
}

std::optional<ChainMarkerProjection> project_chain_marker(const ChainState& state,
                                                          const ChainDefinition& chain, int marker,
                                                          const CameraModel& camera,
                                                          double measurement_sigma_px, double min_depth_m) {
  const ChainShape shape = chain_shape(chain, state.angles);
  const auto projected = marker_pixel(state.base_pose(), shape.markers[marker], camera, min_depth_m);
  if (!projected) return std::nullopt;
  Eigen::Matrix<double, 2, kChainStateSize> H = Eigen::Matrix<double, 2, kChainStateSize>::Zero();
  H.block<2, 3>(0, kBodyP) = projected->J.leftCols<3>();
  H.block<2, 3>(0, kBodyTheta) = projected->J.rightCols<3>();
  // Joint j (at marker j + 1) turns every marker beyond it about the base frame's z axis.
  const Eigen::Matrix<double, 2, 3> J_base = projected->J.leftCols<3>() * state.q.toRotationMatrix();
  for (int j = 0; j + 2 <= marker; ++j)
    H.col(kChainAngle + j) = J_base * kJointAxis.cross(shape.markers[marker] - shape.markers[j + 1]);
  return state.P.pixel_measurement(projected->pixel, H, measurement_sigma_px);
}

void inject(ChainState& state, const ChainVector& dx) {
  inject_pose_blocks(state, dx);
  state.angles += dx.segment<kMaxChainJoints>(kChainAngle);
  state.rates += dx.segment<kMaxChainJoints>(kChainRate);
}

void update(ChainState& state, const ChainMarkerProjection& projection, const Eigen::Vector2d& measurement,
            double /*measurement_sigma_px: already in the projection's S*/) {
  inject(state, state.P.update(projection, measurement));
}

namespace {

// Each marker's blob (-1: none or ambiguous) after gating every marker against every blob before
// any update, so that a blob in two markers' gates is seen as such.
struct ChainAssociation {
  std::array<int, kMaxChainMarkers> blob{};
  std::vector<bool> fresh_claim;  // per blob: inside a fresh marker's gate
  ChainFrameResult counts;
};

// Markers flagged `stale` gate only the blobs no fresh marker has in its gate: a stale marker's wide
// gate must not take blobs from the markers that are being tracked.
ChainAssociation associate_chain_markers(const ChainState& state, const ChainDefinition& chain,
                                         const CameraModel& camera, const std::vector<Eigen::Vector2d>& blobs,
                                         const ChainUpdateOptions& options,
                                         const std::array<bool, kMaxChainMarkers>& stale) {
  ChainAssociation association;
  association.blob.fill(-1);
  std::vector<int> claims(blobs.size(), 0);
  std::vector<bool>& fresh_claim = association.fresh_claim;
  fresh_claim.assign(blobs.size(), false);
  for (const bool stale_pass : {false, true}) {
    for (int k = 0; k < chain.marker_count(); ++k) {
      if (stale[k] != stale_pass) continue;
      const auto projection = project_chain_marker(state, chain, k, camera, options.measurement_sigma_px);
      if (!projection) continue;
      int in_gate = 0;
      for (std::size_t b = 0; b < blobs.size(); ++b) {
        if (stale_pass && fresh_claim[b]) continue;
        if (mahalanobis2(*projection, blobs[b]) > options.gate_chi2) continue;
        ++in_gate;
        ++claims[b];
        if (!stale_pass) fresh_claim[b] = true;
        association.blob[k] = static_cast<int>(b);
      }
      if (in_gate == 0) ++association.counts.markers_missing;
      if (in_gate > 1) {
        association.blob[k] = -1;
        ++association.counts.markers_ambiguous;
      }
    }
  }
  for (int k = 0; k < chain.marker_count(); ++k) {
    if (association.blob[k] >= 0 && claims[association.blob[k]] > 1) {
      association.blob[k] = -1;
      ++association.counts.markers_ambiguous;
    }
  }
  return association;
}

// Joint angles beyond their limits (plus a margin) are pulled back and their rates stopped: an
// unobserved joint (its marker occluded) must not drift through the finger.
void clamp_to_limits(ChainState& state, const ChainDefinition& chain) {
  constexpr double kMargin = 0.2;
  for (int j = 0; j < chain.joint_count(); ++j) {
    const JointLimits& limits = chain.joint_limits[j];
    const double clamped = std::clamp(state.angles(j), limits.min_rad - kMargin, limits.max_rad + kMargin);
    if (clamped != state.angles(j)) {
      state.angles(j) = clamped;
      state.rates(j) = 0.0;
    }
  }
}

bool update_marker(ChainState& state, const ChainDefinition& chain, int marker, const CameraModel& camera,
                   const Eigen::Vector2d& blob, double sigma_px) {
  const auto projection = project_chain_marker(state, chain, marker, camera, sigma_px);
  if (!projection) return false;
  update(state, *projection, blob, sigma_px);
  return true;
}

}  // namespace

ChainFrameResult update_chain_frame(ChainState& state, const ChainDefinition& chain,
                                    const CameraModel& camera, const std::vector<Eigen::Vector2d>& blobs,
                                    const ChainUpdateOptions& options) {
  const ChainAssociation association = associate_chain_markers(state, chain, camera, blobs, options, {});
  ChainFrameResult result = association.counts;
  for (int k = 0; k < chain.marker_count(); ++k) {
    if (association.blob[k] < 0) continue;
    if (update_marker(state, chain, k, camera, blobs[association.blob[k]], options.measurement_sigma_px))
      ++result.markers_updated;
  }
  return result;
}

ChainFilter::ChainFilter(ChainDefinition chain, ChainState initial, const ChainMotionNoise& noise,
                         const ChainUpdateOptions& options)
    : chain_(std::move(chain)), state_(std::move(initial)), noise_(noise), options_(options) {
  last_update_ns_.fill(state_.stamp_ns);
}

ChainFrameResult ChainFilter::process(const CameraModel& camera, TimeNs stamp_ns,
                                      const std::vector<Eigen::Vector2d>& blobs) {
  predict(state_, stamp_ns, noise_, chain_.joint_count());
  std::array<bool, kMaxChainMarkers> stale{};
  for (int k = 0; k < chain_.marker_count(); ++k)
    stale[k] = stamp_ns - last_update_ns_[k] > options_.reacquisition.stale_after_ns;
  // A joint whose outer markers are all unseen is unobservable: hold its angle rather than let
  // its rate carry it through the finger.
  for (int j = 0; j < chain_.joint_count(); ++j) {
    bool outer_unseen = true;
    for (int k = j + 2; k < chain_.marker_count(); ++k) outer_unseen = outer_unseen && stale[k];
    if (outer_unseen) state_.rates(j) = 0.0;
  }
  clamp_to_limits(state_, chain_);
  const ChainAssociation association =
      associate_chain_markers(state_, chain_, camera, blobs, options_, stale);
  ChainFrameResult result = association.counts;
  for (int k = 0; k < chain_.marker_count(); ++k) {
    int blob = association.blob[k];
    if (stale[k]) {
      // Any blob no fresh marker claims may be this marker (its linearised gate cannot be
      // trusted far from the estimate); two cameras must agree in 3D.
      blob = -1;
      for (std::size_t b = 0; b < blobs.size() && blob < 0; ++b) {
        if (association.fresh_claim[b]) continue;
        const CandidateRay ray{camera.center_world(), camera.pixel_to_world_ray(blobs[b]), stamp_ns};
        if (const auto point = confirmed(k, ray)) {
          reinitialise_outer_joint(k, *point, stale);
          blob = static_cast<int>(b);
          ++reacquisitions_;
        }
      }
    }
    if (blob < 0) continue;
    if (update_marker(state_, chain_, k, camera, blobs[blob], options_.measurement_sigma_px)) {
      ++result.markers_updated;
      last_update_ns_[k] = stamp_ns;
    }
  }
  clamp_to_limits(state_, chain_);
  return result;
}

void ChainFilter::reinitialise_outer_joint(int marker, const Eigen::Vector3d& point,
                                           const std::array<bool, kMaxChainMarkers>& stale) {
  // Only the last joint before an unseen end of the chain is unobservable; inner markers are
  // pinned by their neighbours on both sides.
  if (marker < 2) return;
  for (int k = marker + 1; k < chain_.marker_count(); ++k)
    if (!stale[k]) return;
  const int joint = marker - 2;
  const RigidTransform base = state_.base_pose();
  const ChainShape shape = chain_shape(chain_, state_.angles);
  const Eigen::Vector3d in_base = base.inverse().apply(point);
  const Eigen::Vector3d previous_link = shape.markers[marker - 1] - shape.markers[marker - 2];
  const Eigen::Vector3d link = in_base - shape.markers[marker - 1];
  const double heading_before = std::atan2(previous_link.y(), previous_link.x());
  state_.angles(joint) = wrap_angle(std::atan2(link.y(), link.x()) - heading_before);
  state_.rates(joint) = 0.0;
}

namespace {

// The point where two rays (unit directions) pass closest, if they pass within `max_gap_m` in
// front of both cameras and are not parallel.
std::optional<Eigen::Vector3d> ray_meeting_point(const Eigen::Vector3d& origin_a,
                                                 const Eigen::Vector3d& direction_a,
                                                 const Eigen::Vector3d& origin_b,
                                                 const Eigen::Vector3d& direction_b, double max_gap_m) {
  const Eigen::Vector3d w0 = origin_a - origin_b;
  const double b = direction_a.dot(direction_b);
  const double denominator = 1.0 - b * b;
  if (denominator < 1e-6) return std::nullopt;
  const double d = direction_a.dot(w0), e = direction_b.dot(w0);
  const double s = (b * e - d) / denominator;
  const double u = (e - b * d) / denominator;
  const Eigen::Vector3d on_a = origin_a + s * direction_a;
  const Eigen::Vector3d on_b = origin_b + u * direction_b;
  if (s <= 0 || u <= 0 || (on_a - on_b).norm() > max_gap_m) return std::nullopt;
  return 0.5 * (on_a + on_b);
}

}  // namespace

std::optional<Eigen::Vector3d> ChainFilter::confirmed(int marker, const CandidateRay& ray) {
  const ChainReacquisition& rules = options_.reacquisition;
  std::vector<CandidateRay>& pending = pending_[marker];
  std::erase_if(pending, [&](const CandidateRay& other) {
    return ray.stamp_ns - other.stamp_ns > rules.pair_window_ns;
  });
  const ChainPose pose = chain_pose(state_, chain_);
  const Eigen::Vector3d plane_normal = state_.q * Eigen::Vector3d::UnitZ();
  for (const CandidateRay& other : pending) {
    if ((ray.origin - other.origin).norm() < 0.05) continue;  // the same camera again
    auto point = ray_meeting_point(ray.origin, ray.direction, other.origin, other.direction, rules.ray_gap_m);
    if (!point) continue;
    if (std::abs(plane_normal.dot(*point - pose.markers[0])) > rules.plane_tolerance_m) continue;
    // The sphere test against every fresh neighbour (seed 000 Fig. 6.21).
    int checked = 0, passed = 0;
    for (const int neighbour : {marker - 1, marker + 1}) {
      if (neighbour < 0 || neighbour >= chain_.marker_count()) continue;
      if (ray.stamp_ns - last_update_ns_[neighbour] > rules.stale_after_ns) continue;
      const double link = chain_.link_lengths_m[std::min(marker, neighbour)];
      ++checked;
      if (std::abs((*point - pose.markers[neighbour]).norm() - link) <= rules.link_tolerance_m) ++passed;
    }
    if (checked > 0 && passed == checked) {
      pending.clear();
      return point;
    }
  }
  pending.push_back(ray);
  return std::nullopt;
}

ChainPose chain_pose(const ChainState& state, const ChainDefinition& chain, double horizon_s) {
  BodyState base = base_motion(state);
  base.p = state.p;
  base.v = state.v;
  base.a = state.a;
  base.q = state.q;
  ChainPose pose;
  pose.base_pose = horizon_s == 0.0 ? state.base_pose() : extrapolate_pose(base, horizon_s);
  pose.angles = state.angles + horizon_s * state.rates;
  const ChainShape shape = chain_shape(chain, pose.angles);
  for (int k = 0; k < shape.marker_count; ++k) pose.markers.push_back(pose.base_pose.apply(shape.markers[k]));
  pose.tip = pose.base_pose.apply(shape.tip);
  return pose;
}

ChainFit fit_chain(const std::vector<Eigen::Vector3d>& markers) {
  ChainFit fit;
  const Eigen::Vector3d x_axis = (markers[1] - markers[0]).normalized();
  // Each bend's cross product points along ±ẑ; their sum follows the dominant bend.
  Eigen::Vector3d bends = Eigen::Vector3d::Zero();
  for (std::size_t k = 2; k < markers.size(); ++k)
    bends += (markers[k - 1] - markers[k - 2]).normalized().cross((markers[k] - markers[k - 1]).normalized());
  Eigen::Vector3d z_axis = bends - bends.dot(x_axis) * x_axis;
  if (z_axis.norm() < 1e-3) {
    // Straight: any perpendicular (the roll is unobservable until the chain bends).
    z_axis = x_axis.cross(std::abs(x_axis.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX());
  }
  z_axis.normalize();
  const Eigen::Vector3d y_axis = z_axis.cross(x_axis);
  Eigen::Matrix3d R;
  R << x_axis, y_axis, z_axis;  // columns
  fit.base_pose = RigidTransform{Eigen::Quaterniond(R).normalized(), markers[0]};
  double previous_heading = 0.0;
  for (std::size_t k = 1; k < markers.size(); ++k) {
    const Eigen::Vector3d link = markers[k] - markers[k - 1];
    const double heading = std::atan2(link.dot(y_axis), link.dot(x_axis));
    if (k >= 2) fit.angles(static_cast<Eigen::Index>(k) - 2) = wrap_angle(heading - previous_heading);
    previous_heading = heading;
    fit.plane_residual_m = std::max(fit.plane_residual_m, std::abs((markers[k] - markers[0]).dot(z_axis)));
  }
  return fit;
}

namespace {

struct ChainSearch {
  const ChainDefinition& chain;
  const std::vector<Eigen::Vector3d>& points;
  const ChainIdentificationOptions& options;
  const std::vector<Eigen::Vector3d>* predicted;
  std::vector<std::vector<int>> paths;
  std::vector<int> path;

  bool near_prediction(int marker, int point) const {
    return predicted == nullptr || (points[point] - (*predicted)[marker]).norm() <= options.prediction_gate_m;
  }

  bool passes_shape_checks() const {
    std::vector<Eigen::Vector3d> markers;
    for (const int index : path) markers.push_back(points[index]);
    const ChainFit fit = fit_chain(markers);
    if (fit.plane_residual_m > options.plane_tolerance_m) return false;
    for (int j = 0; j < chain.joint_count(); ++j) {
      const JointLimits& limits = chain.joint_limits[j];
      if (fit.angles(j) < limits.min_rad - options.limit_tolerance_rad ||
          fit.angles(j) > limits.max_rad + options.limit_tolerance_rad)
        return false;
    }
    return true;
  }

  // Depth-first along the spheres (seed 000 Fig. 6.21).
  void extend() {
    if (static_cast<int>(paths.size()) > options.max_paths) return;
    const int marker = static_cast<int>(path.size());
    if (marker == chain.marker_count()) {
      if (passes_shape_checks()) paths.push_back(path);
      return;
    }
    for (int candidate = 0; candidate < static_cast<int>(points.size()); ++candidate) {
      if (std::find(path.begin(), path.end(), candidate) != path.end()) continue;
      if (!near_prediction(marker, candidate)) continue;
      if (marker > 0) {
        const double distance = (points[candidate] - points[path.back()]).norm();
        if (std::abs(distance - chain.link_lengths_m[marker - 1]) > options.distance_tolerance_m) continue;
      }
      path.push_back(candidate);
      extend();
      path.pop_back();
    }
  }
};

}  // namespace

ChainIdentification identify_chain(const ChainDefinition& chain, const std::vector<Eigen::Vector3d>& points,
                                   const ChainIdentificationOptions& options,
                                   const std::vector<Eigen::Vector3d>* predicted_markers) {
  ChainSearch search{chain, points, options, predicted_markers, {}, {}};
  search.extend();
  ChainIdentification result;
  result.valid_paths = static_cast<int>(search.paths.size());
  if (search.paths.empty()) return result;
  if (search.paths.size() > 1) {
    result.status = ChainIdentificationStatus::kAmbiguous;
    return result;
  }
  result.status = ChainIdentificationStatus::kIdentified;
  result.point_indices = search.paths.front();
  std::vector<Eigen::Vector3d> markers;
  for (const int index : result.point_indices) markers.push_back(points[index]);
  const ChainFit fit = fit_chain(markers);
  result.base_pose = fit.base_pose;
  result.angles = fit.angles;
  return result;
}

ChainState chain_state_from_identification(const ChainIdentification& identification, TimeNs stamp_ns,
                                           const ChainPriorSigmas& prior, int joint_count) {
  ChainState state;
  state.p = identification.base_pose.t;
  state.q = identification.base_pose.q;
  state.angles = identification.angles;
  state.P = chain_prior(prior, joint_count);
  state.stamp_ns = stamp_ns;
  return state;
}

std::optional<GrabEvent> GrabDetector::observe(TimeNs stamp_ns, double bend_rad, const Eigen::Vector3d& tip) {
  const bool beyond = grabbing_ ? bend_rad < options_.release_bend_rad : bend_rad > options_.grab_bend_rad;
  if (!beyond) {
    crossed_ns_.reset();
    return std::nullopt;
  }
  if (!crossed_ns_) crossed_ns_ = stamp_ns;
  if (stamp_ns - *crossed_ns_ < options_.min_dwell_ns) return std::nullopt;
  grabbing_ = !grabbing_;
  GrabEvent event;
  event.kind = grabbing_ ? GrabEventKind::kGrab : GrabEventKind::kRelease;
  event.stamp_ns = *crossed_ns_;
  event.tip = tip;
  event.bend_rad = bend_rad;
  crossed_ns_.reset();
  return event;
}

}  // namespace panoptes::estimator

namespace panoptes::estimator {

ChainTracker::ChainTracker(std::vector<ChainDefinition> chains, const ChainTrackerOptions& options)
    : options_(options) {
  for (ChainDefinition& chain : chains)
    entries_.push_back(
        {std::move(chain), ChainStatus::kNotIdentified, std::nullopt, GrabDetector(options.grab)});
}

void ChainTracker::identify(TimeNs stamp_ns, const std::vector<Eigen::Vector3d>& points) {
  for (Entry& entry : entries_) {
    if (entry.status == ChainStatus::kTracking) continue;
    const ChainIdentification found = identify_chain(entry.definition, points, options_.identification);
    if (found.status == ChainIdentificationStatus::kAmbiguous) entry.status = ChainStatus::kAmbiguous;
    if (found.status == ChainIdentificationStatus::kNotFound) entry.status = ChainStatus::kNotIdentified;
    if (found.status != ChainIdentificationStatus::kIdentified) continue;
    entry.filter.emplace(
        entry.definition,
        chain_state_from_identification(found, stamp_ns, options_.prior, entry.definition.joint_count()),
        options_.noise, options_.update);
    entry.status = ChainStatus::kTracking;
  }
}

void ChainTracker::process(const CameraModel& camera, TimeNs stamp_ns,
                           const std::vector<Eigen::Vector2d>& blobs) {
  for (Entry& entry : entries_) {
    if (!entry.filter || stamp_ns < entry.filter->state().stamp_ns) continue;
    entry.filter->process(camera, stamp_ns, blobs);
    TimeNs newest_ns = entry.filter->last_update_ns(0);
    for (int k = 1; k < entry.definition.marker_count(); ++k)
      newest_ns = std::max(newest_ns, entry.filter->last_update_ns(k));
    if (stamp_ns - newest_ns > options_.lost_after_ns) {
      entry.filter.reset();
      entry.status = ChainStatus::kNotIdentified;
      continue;
    }
    const ChainPose pose = chain_pose(entry.filter->state(), entry.definition);
    const double bend = entry.filter->state().angles.head(entry.definition.joint_count()).sum();
    if (auto event = entry.grab.observe(stamp_ns, bend, pose.tip))
      events_.push_back({entry.definition.name, *event});
  }
}

std::vector<ChainOutput> ChainTracker::outputs(double horizon_s) const {
  std::vector<ChainOutput> outputs;
  for (const Entry& entry : entries_) {
    ChainOutput output;
    output.name = entry.definition.name;
    output.status = entry.status;
    output.grabbing = entry.grab.grabbing();
    output.marker_valid.assign(entry.definition.marker_count(), false);
    if (entry.filter) {
      const ChainState& state = entry.filter->state();
      output.stamp_ns = state.stamp_ns;
      output.pose = chain_pose(state, entry.definition, horizon_s);
      for (int k = 0; k < entry.definition.marker_count(); ++k)
        output.marker_valid[k] =
            state.stamp_ns - entry.filter->last_update_ns(k) <= options_.update.reacquisition.stale_after_ns;
    }
    outputs.push_back(std::move(output));
  }
  return outputs;
}

std::vector<NamedGrabEvent> ChainTracker::take_events() {
  std::vector<NamedGrabEvent> taken;
  taken.swap(events_);
  return taken;
}

}  // namespace panoptes::estimator
