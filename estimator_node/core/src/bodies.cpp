// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/bodies.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Dense>

#include "panoptes/estimator/assignment.h"
#include "panoptes/estimator/led_marker.h"

namespace panoptes::estimator {

namespace {

// α is estimated only when angular jerk drives it; otherwise it stays zero (constant ω).
double initial_angular_accel_sigma(const BodyTrackerOptions& o) {
  return o.noise.angular_jerk > 0 ? o.init_angular_accel_sigma : 0.0;
}

// The process noise with its translation terms scaled by `translation` and its rotation terms by
// `rotation`. The causal filter scales both by the body's adaptive factor s; the filter that feeds
// the smoother (docs/bodies.md, "Smoothing") the rotation by √s only: the smoother has the frames
// after the reported instant, and at speed it wants less angular process noise than a filter that
// must extrapolate to the newest frame.
BodyMotionNoise scaled(const BodyMotionNoise& noise, double translation, double rotation) {
  return {noise.jerk * translation, noise.angular_accel * rotation, noise.angular_jerk * rotation};
}

}  // namespace

struct BodySet::Shared {
  std::vector<BodyDefinition> definitions;
  std::vector<double> span;  // largest marker distance per body
  BodyTrackerOptions options;
  std::vector<LedMarkerModel> led_models;  // 7-LED bodies (seed 004), model i is body led_body[i]
  std::vector<std::size_t> led_body;
};

struct BodySet::Body {
  bool tracked = false;
  BodyState state;
  TimeNs acquired_ns = 0;
  TimeNs last_update_ns = 0;
  double nis_average = 0;
  int nis_updates = 0;
  // Adaptive process noise (docs/bodies.md, "Speed"): `noise` × noise_scale, the scale driven by
  // the correlation of successive innovations of the same marker in the same camera.
  double noise_scale = 1.0;
  double correlation_sum = 0, energy_sum = 0;    // moving averages of ν·ν_previous and |ν|²
  std::vector<Eigen::Vector2d> last_innovation;  // by camera × marker, pixels
  std::vector<TimeNs> last_innovation_ns;        // 0: none
  std::uint64_t updates = 0;
  std::vector<TimeNs> marker_last_seen;    // by marker
  std::vector<TimeNs> camera_last_update;  // by camera index
  // When smoothing: a second filter of the same blobs with the smoother's noise (scaled),
  // and its last smoothing_ns of steps. `state` stays the causal filter, the published one.
  BodyState smoother_state;
  BodyFilterHistory history;

  // (Re)starts tracking from an initial state (identification or a monocular detection) with fresh
  // consistency statistics.
  void start(const BodyState& initial, TimeNs stamp_ns) {
    state = initial;
    smoother_state = initial;
    tracked = true;
    acquired_ns = stamp_ns;
    last_update_ns = stamp_ns;
    nis_average = 0;
    nis_updates = 0;
    noise_scale = 1.0;
    correlation_sum = energy_sum = 0;
    last_innovation.clear();
    last_innovation_ns.clear();
    history.clear();
  }

  // The state to report at `at`: without smoothing history the filter's newest state, else the
  // smoothed state of the newest step not after `at` (the oldest step if all are after it).
  BodyState reported_state(TimeNs at) const {
    if (history.size() < 2) return state;
    std::size_t index = 0;
    while (index + 1 < history.size() && history[index + 1].filtered.stamp_ns <= at) ++index;
    return smoothed_state(history, index);
  }

  // A filter whose gain suits the body has white innovations; one that lags behind an acceleration
  // sees the same marker displaced the same way frame after frame. The scale of the process noise
  // rises while successive innovations of a marker in a camera are correlated above
  // process_noise_adapt_correlation and falls (to 1 at least) while they are below, so a slow body
  // keeps the memory of the low noise and a fast one the responsiveness of a high one. The
  // correlation is a ratio of moving averages, independent of how well measurement_noise_px
  // matches the centroids' noise (an NIS target is not: docs/bodies.md, "Speed").
  void adapt_process_noise(std::size_t slot, const Eigen::Vector2d& innovation, TimeNs stamp_ns,
                           const BodyTrackerOptions& o) {
    if (o.process_noise_max_scale <= 1.0) return;
    if (last_innovation.size() <= slot) {
      last_innovation.resize(slot + 1, Eigen::Vector2d::Zero());
      last_innovation_ns.resize(slot + 1, 0);
    }
    // Successive: the same camera's previous frame (any camera faster than 20 Hz).
    constexpr TimeNs kSuccessiveNs = 50'000'000;
    const TimeNs previous_ns = last_innovation_ns[slot];
    if (previous_ns != 0 && stamp_ns > previous_ns && stamp_ns - previous_ns < kSuccessiveNs) {
      const Eigen::Vector2d& previous = last_innovation[slot];
      const double w = o.process_noise_adapt_weight;
      correlation_sum = (1 - w) * correlation_sum + w * innovation.dot(previous);
      energy_sum = (1 - w) * energy_sum + w * 0.5 * (innovation.squaredNorm() + previous.squaredNorm());
      const double correlation = energy_sum > 0 ? correlation_sum / energy_sum : 0.0;
      noise_scale = std::clamp(noise_scale * std::exp(o.process_noise_adapt_gain *
                                                      (correlation - o.process_noise_adapt_correlation)),
                               1.0, o.process_noise_max_scale);
    }
    last_innovation[slot] = innovation;
    last_innovation_ns[slot] = std::max(previous_ns, stamp_ns);
  }

  // The smoother's filter over one camera frame: the step being recorded and the state the
  // frame's marker updates move (from `step.predicted`).
  struct SmootherFrame {
    BodyFilterStep step;
    BodyState state;
  };
  SmootherFrame begin_smoother_frame(TimeNs stamp_ns, const BodyMotionNoise& noise) const {
    SmootherFrame frame;
    frame.state = predicted(smoother_state, stamp_ns, scaled(noise, noise_scale, std::sqrt(noise_scale)));
    frame.step.predicted = frame.state;
    frame.step.A = body_transition(smoother_state, ns_to_seconds(stamp_ns - smoother_state.stamp_ns));
    return frame;
  }
  // Keeps the frame's step for smoothing, and the steps back to the first one at least `lag_ns`
  // older than it.
  void finish_smoother_frame(SmootherFrame frame, TimeNs lag_ns) {
    smoother_state = frame.state;
    frame.step.filtered = smoother_state;
    history.append(std::move(frame.step));
    history.keep_from(history.back().filtered.stamp_ns - lag_ns);
  }

  void note_camera_update(int camera_index, TimeNs stamp_ns) {
    const auto c = static_cast<std::size_t>(camera_index);
    if (camera_last_update.size() <= c) camera_last_update.resize(c + 1, 0);
    camera_last_update[c] = stamp_ns;
  }
};

namespace {

// The smoother's filter takes the blob the causal filter took unless it is outside its own gate.
void update_smoother(BodyState& state, const Eigen::Vector3d& marker, const CameraModel& camera,
                     const Eigen::Vector2d& blob, const BodyTrackerOptions& o) {
  const auto projection = project_marker(state, marker, camera, o.measurement_noise_px);
  if (projection && inside_gate(mahalanobis2(*projection, blob), o.gate_chi2))
    update(state, *projection, blob, o.measurement_noise_px);
}

}  // namespace

BodySet::BodySet() : shared_(std::make_shared<Shared>()) {}
BodySet::BodySet(const BodySet&) = default;
BodySet& BodySet::operator=(const BodySet&) = default;
BodySet::BodySet(BodySet&&) noexcept = default;
BodySet& BodySet::operator=(BodySet&&) noexcept = default;
BodySet::~BodySet() = default;

std::size_t BodySet::size() const {
  return bodies_.size();
}
const std::vector<BodyDefinition>& BodySet::definitions() const {
  return shared_->definitions;
}
const BodyStats& BodySet::stats() const {
  return stats_;
}

std::size_t BodySet::tracked_count() const {
  return static_cast<std::size_t>(
      std::count_if(bodies_.begin(), bodies_.end(), [](const Body& b) { return b.tracked; }));
}

void BodySet::set_definitions(std::vector<BodyDefinition> definitions, const BodyTrackerOptions& options) {
  auto shared = std::make_shared<Shared>();
  shared->options = options;
  std::vector<Body> bodies(definitions.size());
  for (std::size_t b = 0; b < definitions.size(); ++b) {
    const auto& markers = definitions[b].markers;
    double span = 0;
    for (std::size_t i = 0; i < markers.size(); ++i)
      for (std::size_t k = i + 1; k < markers.size(); ++k)
        span = std::max(span, (markers[i] - markers[k]).norm());
    shared->span.push_back(span);
    if (definitions[b].kind == BodyKind::kLed7) {
      shared->led_models.push_back(LedMarkerModel::from_body(definitions[b]));  // throws naming the body
      shared->led_body.push_back(b);
    }
    bodies[b].marker_last_seen.assign(markers.size(), 0);
    // Keep the state of a body whose definition did not change.
    for (std::size_t old = 0; old < bodies_.size(); ++old) {
      const auto& previous = shared_->definitions[old];
      if (previous.name == definitions[b].name && previous.markers == markers &&
          previous.kind == definitions[b].kind)
        bodies[b] = bodies_[old];
    }
  }
  shared->definitions = std::move(definitions);
  shared_ = std::move(shared);
  bodies_ = std::move(bodies);
}

void BodySet::process_frame(int camera_index, const CameraModel& camera, TimeNs stamp_ns,
                            const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& excluded,
                            std::vector<char>& taken) {
  const BodyTrackerOptions& o = shared_->options;
  // Bodies not updated for too long are lost (identification will look for them again).
  for (Body& body : bodies_) {
    if (body.tracked && stamp_ns - body.last_update_ns > o.lost_after_ns) {
      body.tracked = false;
      ++stats_.lost;
    }
  }

  // Project every tracked body's markers and gate the blobs (seed 003 §2.2.3.2's verify region,
  // per marker).
  struct Row {
    std::size_t body;
    std::size_t marker;
  };
  std::vector<Row> rows;
  std::vector<GatedPair> gated;  // (row, blob, d²)
  std::vector<BodyState> predicted_states(bodies_.size());
  std::vector<Body::SmootherFrame> smoother(o.smoothing_ns > 0 ? bodies_.size() : 0);  // when smoothing
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    if (!bodies_[b].tracked) continue;
    predicted_states[b] = predicted(bodies_[b].state, stamp_ns,
                                    scaled(o.noise, bodies_[b].noise_scale, bodies_[b].noise_scale));
    if (!smoother.empty()) smoother[b] = bodies_[b].begin_smoother_frame(stamp_ns, o.noise);
    const auto& markers = shared_->definitions[b].markers;
    for (std::size_t m = 0; m < markers.size(); ++m) {
      const auto projection = project_marker(predicted_states[b], markers[m], camera, o.measurement_noise_px);
      if (!projection || !camera.in_image(projection->pixel, 2.0)) continue;
      const double radius2 = gate_radius2(projection->S, o.gate_chi2);
      bool any = false;
      for (std::size_t j = 0; j < pixels.size(); ++j) {
        if (excluded[j] || (pixels[j] - projection->pixel).squaredNorm() > radius2) continue;
        const double d2 = mahalanobis2(*projection, pixels[j]);
        if (!inside_gate(d2, o.gate_chi2)) continue;
        gated.push_back({rows.size(), j, d2});
        any = true;
      }
      if (any) rows.push_back({b, m});
    }
  }
  if (!rows.empty()) {
    // Sequential updates, one marker at a time, each re-projected with the state the previous
    // ones left (the one-camera-at-a-time idea of seed 003 applied within the frame).
    std::vector<char> body_updated(bodies_.size(), 0);
    for (const auto& [r, blob] : assign_gated(gated, 0.5 * o.gate_chi2)) {
      const std::size_t b = rows[r].body, m = rows[r].marker;
      BodyState& state = predicted_states[b];
      const auto projection =
          project_marker(state, shared_->definitions[b].markers[m], camera, o.measurement_noise_px);
      if (!projection) continue;
      const double d2 = mahalanobis2(*projection, pixels[blob]);
      if (!inside_gate(d2, o.gate_chi2)) {
        ++stats_.markers_gated_out;
        continue;
      }
      Body& body = bodies_[b];
      body.nis_average = body.nis_updates == 0 ? d2 : 0.9 * body.nis_average + 0.1 * d2;
      ++body.nis_updates;
      body.adapt_process_noise(
          static_cast<std::size_t>(camera_index) * shared_->definitions[b].markers.size() + m,
          pixels[blob] - projection->pixel, stamp_ns, o);
      update(state, *projection, pixels[blob], o.measurement_noise_px);
      if (!smoother.empty())
        update_smoother(smoother[b].state, shared_->definitions[b].markers[m], camera, pixels[blob], o);
      body.marker_last_seen[m] = stamp_ns;
      taken[blob] = 1;
      body_updated[b] = 1;
      ++body.updates;
      ++stats_.marker_updates;
    }
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      if (!body_updated[b]) continue;
      Body& body = bodies_[b];
      body.state = predicted_states[b];
      if (!smoother.empty()) body.finish_smoother_frame(std::move(smoother[b]), o.smoothing_ns);
      body.last_update_ns = std::max(body.last_update_ns, stamp_ns);
      body.note_camera_update(camera_index, stamp_ns);
      if (body.nis_updates >= 20 && body.nis_average > o.max_nis) {
        body.tracked = false;  // the measurements contradict the pose: identify again
        ++stats_.lost;
      }
    }
  }
  acquire_monocular(camera_index, camera, stamp_ns, pixels, excluded, taken);
}

void BodySet::acquire_monocular(int camera_index, const CameraModel& camera, TimeNs stamp_ns,
                                const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& excluded,
                                std::vector<char>& taken) {
  const BodyTrackerOptions& o = shared_->options;
  const auto& led_body = shared_->led_body;
  if (std::none_of(led_body.begin(), led_body.end(), [&](std::size_t b) { return !bodies_[b].tracked; }))
    return;
  // Seed 004 §2.2: identification and pose from the blobs of this one camera, in ideal
  // (undistorted, normalised) coordinates; blobs that tracked bodies took are left out.
  std::vector<Eigen::Vector2d> ideal;
  std::vector<std::size_t> index;
  for (std::size_t j = 0; j < pixels.size(); ++j) {
    if (excluded[j] || taken[j]) continue;
    ideal.push_back(camera.pixel_to_normalized(pixels[j]));
    index.push_back(j);
  }
  if (ideal.size() < 7) return;
  LedMarkerOptions options = o.led_marker;
  const double focal = 0.5 * (camera.intrinsics().fx + camera.intrinsics().fy);
  options.centroid_sigma = o.measurement_noise_px / focal;
  options.max_rms = 5.0 * options.centroid_sigma;
  const LedMarkerDetector detector(shared_->led_models, options);
  for (const LedMarkerDetection& detection : detector.detect(ideal)) {
    const std::size_t b = led_body[static_cast<std::size_t>(detection.model)];
    Body& body = bodies_[b];
    if (body.tracked) continue;
    const RigidTransform T_world_body = camera.T_world_cam() * detection.T_cam_marker;
    BodyState state;
    state.p = T_world_body.t;
    state.q = T_world_body.q;
    state.stamp_ns = stamp_ns;
    // A single view: the depth is the least certain (σ_z ≈ z² σ_px / (f · size)).
    const double depth = detection.T_cam_marker.t.z();
    const double size = std::max(1e-3, shared_->span[b]);
    const double sigma_depth = depth * depth * o.measurement_noise_px / (focal * size) * 3.0;
    state.P = body_prior({std::max(o.init_position_sigma_m, sigma_depth), 1.0, o.init_accel_sigma_mps2, 0.05,
                          3.0, initial_angular_accel_sigma(o)});
    body.start(state, stamp_ns);
    // The detection's blobs update the new state at once.
    const auto& markers = shared_->definitions[b].markers;
    for (std::size_t m = 0; m < markers.size(); ++m) {
      const std::size_t blob = index[static_cast<std::size_t>(detection.blob[m])];
      const auto projection = project_marker(body.state, markers[m], camera, o.measurement_noise_px);
      if (!projection) continue;
      update(body.state, *projection, pixels[blob], o.measurement_noise_px);
      body.marker_last_seen[m] = stamp_ns;
      taken[blob] = 1;
    }
    body.smoother_state = body.state;
    body.note_camera_update(camera_index, stamp_ns);
    ++stats_.acquired_monocular;
  }
}

bool BodySet::wants_points(TimeNs stamp_ns) const {
  const BodyTrackerOptions& o = shared_->options;
  if (bodies_.empty()) return false;
  if (!identified_once_) return true;
  const bool any_untracked =
      std::any_of(bodies_.begin(), bodies_.end(), [](const Body& b) { return !b.tracked; });
  return (any_untracked && stamp_ns - last_identify_ns_ >= o.identify_interval_ns) ||
         stamp_ns - last_verify_ns_ >= o.verify_interval_ns;
}

namespace {

// Linear and angular velocity (world) of a rigid motion from its points' velocities:
// v_i = v + ω × (p_i − c), least squares over ≥ 3 non-collinear points.
bool rigid_velocity(const std::vector<TrackedPoint>& points, const std::vector<int>& used,
                    const Eigen::Vector3d& c, Eigen::Vector3d& v, Eigen::Vector3d& w) {
  if (used.size() < 3) return false;
  Eigen::MatrixXd A(3 * used.size(), 6);
  Eigen::VectorXd y(3 * used.size());
  for (std::size_t k = 0; k < used.size(); ++k) {
    const Eigen::Vector3d r = points[static_cast<std::size_t>(used[k])].p - c;
    A.block<3, 3>(3 * k, 0).setIdentity();
    A.block<3, 3>(3 * k, 3) = -skew(r);  // ω × r = −[r]× ω
    y.segment<3>(3 * k) = points[static_cast<std::size_t>(used[k])].v;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  if (svd.singularValues()(5) < 1e-6 * svd.singularValues()(0)) return false;
  const Eigen::VectorXd x = svd.solve(y);
  v = x.head<3>();
  w = x.tail<3>();
  return v.allFinite() && w.allFinite();
}

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return quaternion_to_rotation_vector(a.conjugate() * b).norm();
}

}  // namespace

void BodySet::identify(TimeNs stamp_ns, const std::vector<TrackedPoint>& points) {
  const BodyTrackerOptions& o = shared_->options;
  const bool identify_now = !identified_once_ || stamp_ns - last_identify_ns_ >= o.identify_interval_ns;
  const bool verify_now = !identified_once_ || stamp_ns - last_verify_ns_ >= o.verify_interval_ns;
  if (identify_now) last_identify_ns_ = stamp_ns;
  if (verify_now) last_verify_ns_ = stamp_ns;
  identified_once_ = true;
  if (points.empty()) return;

  std::vector<MeasuredPoint> measured(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) measured[i] = {points[i].p, points[i].sigma_m};
  // Points explained by tracked bodies are not offered to the others.
  std::vector<char> claimed(points.size(), 0);
  std::vector<std::vector<int>> near_body(bodies_.size());
  claim_points_of_tracked(stamp_ns, points, claimed, near_body);
  if (verify_now) verify_tracked(stamp_ns, points, measured, near_body);
  if (identify_now) acquire_untracked(stamp_ns, points, measured, claimed);
}

void BodySet::claim_points_of_tracked(TimeNs stamp_ns, const std::vector<TrackedPoint>& points,
                                      std::vector<char>& claimed,
                                      std::vector<std::vector<int>>& near_body) const {
  const BodyTrackerOptions& o = shared_->options;
  const double near = 4.0 * o.identification.tolerance_floor_m;
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    if (!bodies_[b].tracked) continue;
    const RigidTransform pose = predicted(bodies_[b].state, stamp_ns, o.noise).pose();
    for (std::size_t i = 0; i < points.size(); ++i) {
      if ((points[i].p - pose.t).norm() > shared_->span[b] + 0.05) continue;
      near_body[b].push_back(static_cast<int>(i));
      for (const auto& marker : shared_->definitions[b].markers) {
        if ((pose.apply(marker) - points[i].p).norm() < near) claimed[i] = 1;
      }
    }
  }
}

void BodySet::start_from_match(std::size_t b, const BodyMatch& match, const std::vector<int>& point_index,
                               const std::vector<TrackedPoint>& points, TimeNs stamp_ns) {
  const BodyTrackerOptions& o = shared_->options;
  Body& body = bodies_[b];
  BodyState state;
  state.p = match.T_world_body.t;
  state.q = match.T_world_body.q;
  state.stamp_ns = stamp_ns;
  std::vector<int> used;
  for (const auto& pair : match.pairs) used.push_back(point_index[static_cast<std::size_t>(pair.first)]);
  Eigen::Vector3d v = Eigen::Vector3d::Zero(), w_world = Eigen::Vector3d::Zero();
  const bool have_velocity = rigid_velocity(points, used, state.p, v, w_world);
  state.v = v;
  state.w = state.q.conjugate() * w_world;
  state.P = body_prior({std::max(o.init_position_sigma_m, match.rms_m),
                        have_velocity ? o.init_velocity_sigma_mps : 2.0, o.init_accel_sigma_mps2,
                        o.init_angle_sigma_rad, have_velocity ? o.init_angular_velocity_sigma : 5.0,
                        initial_angular_accel_sigma(o)});
  body.start(state, stamp_ns);
  for (const auto& pair : match.pairs)
    body.marker_last_seen[static_cast<std::size_t>(pair.second)] = stamp_ns;
}

// Verification: a tracked body whose identification among nearby points disagrees with its filter
// pose (a wrong acquisition, or markers swapped) is restarted from the identification.
void BodySet::verify_tracked(TimeNs stamp_ns, const std::vector<TrackedPoint>& points,
                             const std::vector<MeasuredPoint>& measured,
                             const std::vector<std::vector<int>>& near_body) {
  const BodyTrackerOptions& o = shared_->options;
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    if (!bodies_[b].tracked || near_body[b].size() < 3) continue;
    std::vector<MeasuredPoint> local;
    for (int i : near_body[b]) local.push_back(measured[static_cast<std::size_t>(i)]);
    const auto& markers = shared_->definitions[b].markers;
    const auto match = identify_body(markers, local, o.identification);
    if (!match || match->pairs.size() < std::min<std::size_t>(4, markers.size())) continue;
    const RigidTransform pose = predicted(bodies_[b].state, stamp_ns, o.noise).pose();
    if ((match->T_world_body.t - pose.t).norm() > o.verify_position_m ||
        angle_between(match->T_world_body.q, pose.q) > o.verify_angle_rad) {
      start_from_match(b, *match, near_body[b], points, stamp_ns);
      ++stats_.reidentified;
    }
  }
}

// Acquisition: the best match over all untracked bodies first (most markers, then lowest RMS), its
// points claimed, then the next.
void BodySet::acquire_untracked(TimeNs stamp_ns, const std::vector<TrackedPoint>& points,
                                const std::vector<MeasuredPoint>& measured, std::vector<char>& claimed) {
  const BodyTrackerOptions& o = shared_->options;
  std::vector<char> pending(bodies_.size(), 0);
  for (std::size_t b = 0; b < bodies_.size(); ++b) pending[b] = !bodies_[b].tracked;
  for (;;) {
    std::vector<int> free_index;
    std::vector<MeasuredPoint> free_points;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (claimed[i]) continue;
      free_index.push_back(static_cast<int>(i));
      free_points.push_back(measured[i]);
    }
    std::optional<BodyMatch> best;
    std::size_t best_body = 0;
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      if (!pending[b]) continue;
      auto match = identify_body(shared_->definitions[b].markers, free_points, o.identification);
      if (!match) continue;
      // Fewer than four markers of a larger constellation: three points of other bodies can form
      // the triangle within tolerance while several bodies are being found (docs/bodies.md,
      // "The grid"), so such a match must fit twice as well.
      if (match->pairs.size() < std::min<std::size_t>(4, shared_->definitions[b].markers.size()) &&
          match->rms_m > 0.5 * o.identification.max_rms_m)
        continue;
      if (!best || match->pairs.size() > best->pairs.size() ||
          (match->pairs.size() == best->pairs.size() && match->rms_m < best->rms_m)) {
        best = std::move(match);
        best_body = b;
      }
    }
    if (!best) break;
    start_from_match(best_body, *best, free_index, points, stamp_ns);
    ++stats_.identified;
    pending[best_body] = 0;
    for (const auto& pair : best->pairs)
      claimed[static_cast<std::size_t>(free_index[static_cast<std::size_t>(pair.first)])] = 1;
  }
}

std::vector<PoseRecord> BodySet::poses_at(TimeNs stamp_ns, TimeNs horizon_ns, bool smoothed) const {
  const BodyTrackerOptions& o = shared_->options;
  std::vector<PoseRecord> poses;
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const Body& body = bodies_[b];
    if (!body.tracked) continue;
    const TimeNs at = smoothed ? stamp_ns - o.smoothing_ns : stamp_ns;
    const BodyState state = predicted(smoothed ? body.reported_state(at) : body.state, at, o.noise);
    const RigidTransform pose = extrapolate_pose(state, ns_to_seconds(horizon_ns));
    PoseRecord record;
    record.stamp_ns = at;
    record.body = shared_->definitions[b].name;
    record.p = pose.t;
    record.q = Eigen::Vector4d(pose.q.x(), pose.q.y(), pose.q.z(), pose.q.w());
    record.v = state.v + ns_to_seconds(horizon_ns) * state.a;
    record.w = pose.q * (state.w + ns_to_seconds(horizon_ns) * state.alpha);
    record.horizon_ns = horizon_ns;
    int seen = 0;
    for (TimeNs t : body.marker_last_seen) seen += (t != 0 && stamp_ns - t <= o.quality_window_ns) ? 1 : 0;
    record.quality = static_cast<double>(seen) / static_cast<double>(body.marker_last_seen.size());
    for (TimeNs t : body.camera_last_update)
      record.cameras += (t != 0 && stamp_ns - t <= 500'000'000) ? 1 : 0;
    for (int k = 0; k < 3; ++k) {
      record.sigma[static_cast<std::size_t>(k)] = std::sqrt(std::max(0.0, state.P(kBodyP + k, kBodyP + k)));
      record.sigma[3 + static_cast<std::size_t>(k)] =
          std::sqrt(std::max(0.0, state.P(kBodyTheta + k, kBodyTheta + k)));
    }
    poses.push_back(std::move(record));
  }
  return poses;
}

}  // namespace panoptes::estimator
