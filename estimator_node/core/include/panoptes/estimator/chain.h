// SPDX-License-Identifier: Apache-2.0
// Articulated marker chains (a finger, seed 000 §6.4.3–6.4.4): the kinematic model, an EKF whose
// state is the base pose plus joint angles and their rates, identification by the seed's sphere
// search, and grab gestures from the joint angles (§6.4.5's chess application).
//
// Model (seed 000 Fig. 6.22, eqs. 6.12–6.15): the chain's base frame has marker 0 at its origin,
// marker 1 on its x axis, and every joint bends about its z axis, so the markers lie in its
// xy-plane. Marker k (k ≥ 2) is m_k = m_{k-1} + L_{k-1} Rz(θ_0 + … + θ_{k-2}) x̂; joint j sits at
// marker j + 1. Unlike the seed, which filters 3D marker positions, the measurement here is one
// marker's 2D projection in one camera frame, as for rigid bodies (body_ekf.h).
//
// Filter state (error state, like the body filter's, extended):
//   x = (p, v, a, δθ, ω, α | θ_0..θ_2, θ̇_0..θ̇_2)   18 + 6 = 24 elements
// The base blocks follow body_ekf.h exactly (same transition and process noise); each joint is a
// constant-rate model driven by white angular acceleration. Chains with fewer joints than the
// maximum keep the unused entries at zero with zero variance.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "panoptes/camera_model.h"
#include "panoptes/chain_definition.h"
#include "panoptes/estimator/body_ekf.h"
#include "panoptes/estimator/ekf.h"
#include "panoptes/geometry.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

inline constexpr int kMaxChainJoints = kMaxChainMarkers - 2;
inline constexpr int kChainStateSize = kBodyStateSize + 2 * kMaxChainJoints;
inline constexpr int kChainAngle = kBodyStateSize;
inline constexpr int kChainRate = kBodyStateSize + kMaxChainJoints;
using ChainVector = Eigen::Matrix<double, kChainStateSize, 1>;
using ChainMatrix = Eigen::Matrix<double, kChainStateSize, kChainStateSize>;
using JointVector = Eigen::Matrix<double, kMaxChainJoints, 1>;

// Marker and tip positions in the base frame for given joint angles.
struct ChainShape {
  std::array<Eigen::Vector3d, kMaxChainMarkers> markers{};
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  int marker_count = 0;
};
ChainShape chain_shape(const ChainDefinition& chain, const JointVector& angles);

// Defaults from a sweep on the acceptance scene (docs/articulated.md): the hand carrying the chain
// moves smoothly (jerk 5 against the bodies' 50), the joints bend with σ² = 30 rad²/s³.
struct ChainMotionNoise {
  BodyMotionNoise base{.jerk = 5.0, .angular_accel = 0.1, .angular_jerk = 100.0};
  double joint_accel = 30.0;  // σ² of white joint angular acceleration, rad²/s³
};

struct ChainState {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();            // marker 0 (the base), world frame, m
  Eigen::Vector3d v = Eigen::Vector3d::Zero();            // m/s
  Eigen::Vector3d a = Eigen::Vector3d::Zero();            // m/s²
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // R_world_base
  Eigen::Vector3d w = Eigen::Vector3d::Zero();            // base angular velocity, base frame
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();        // base angular acceleration, base frame
  JointVector angles = JointVector::Zero();               // rad
  JointVector rates = JointVector::Zero();                // rad/s
  FilterCovariance<kChainStateSize> P;
  TimeNs stamp_ns = 0;

  RigidTransform base_pose() const { return {q, p}; }
};

struct ChainPriorSigmas {
  BodyPriorSigmas base;
  double angle_rad = 0.0;
  double rate_radps = 0.0;
};
// A prior with independent blocks; entries of joints the chain does not have get zero variance.
FilterCovariance<kChainStateSize> chain_prior(const ChainPriorSigmas& sigmas, int joint_count);

void predict(ChainState& state, TimeNs stamp_ns, const ChainMotionNoise& noise, int joint_count);

// One marker's projection through a camera with its Jacobian (base pose columns as in
// body_ekf.h's pose_measurement, joint columns from ∂m_k/∂θ_j = ẑ × (m_k − m_{j+1})).
using ChainMarkerProjection = PixelMeasurement<kChainStateSize>;
std::optional<ChainMarkerProjection> project_chain_marker(const ChainState& state,
                                                          const ChainDefinition& chain, int marker,
                                                          const CameraModel& camera,
                                                          double measurement_sigma_px,
                                                          double min_depth_m = 0.05);

void update(ChainState& state, const ChainMarkerProjection& projection, const Eigen::Vector2d& measurement,
            double measurement_sigma_px);
void inject(ChainState& state, const ChainVector& dx);

// A marker unseen for a while has a wide gate (its joint angle drifts): a reflection alone in that
// gate would be taken for it. Such a stale marker is re-acquired only when two cameras agree — the
// seed's sphere test in 3D: their rays meet at a point at the link lengths from its neighbours.
struct ChainReacquisition {
  TimeNs stale_after_ns = 50'000'000;  // unseen this long: stale
  TimeNs pair_window_ns = 20'000'000;  // the two cameras' frames at most this far apart
  double ray_gap_m = 0.003;            // the two rays pass this close to each other
  double link_tolerance_m = 0.003;     // |distance to a fresh neighbour - link length|
  double plane_tolerance_m = 0.004;    // distance from the chain's plane
};

struct ChainUpdateOptions {
  double measurement_sigma_px = 0.1;
  // Chi-square gate on the squared Mahalanobis distance (2 dof; 13.8 ≈ 99.9 %).
  double gate_chi2 = 13.8;
  ChainReacquisition reacquisition;
};

struct ChainFrameResult {
  int markers_updated = 0;
  int markers_ambiguous = 0;  // more than one blob in a marker's gate, or a blob in two gates: skipped
  int markers_missing = 0;    // projected but no blob in the gate (occluded)
};

// One camera frame (the state already predicted to its stamp): each marker takes the single blob
// inside its gate; a marker whose gate holds several blobs, or whose blob also falls in another
// marker's gate, is skipped rather than forced (a reflection next to a marker costs that marker's
// update, never a wrong one). Updates are sequential, each re-linearised.
ChainFrameResult update_chain_frame(ChainState& state, const ChainDefinition& chain,
                                    const CameraModel& camera, const std::vector<Eigen::Vector2d>& blobs,
                                    const ChainUpdateOptions& options);

// One tracked chain: the filter state plus what re-acquisition needs (when each marker was last
// updated, the recent unconfirmed candidate rays of each stale marker). process() predicts to the
// frame's stamp, associates as update_chain_frame does, and updates fresh markers directly and
// stale ones only once confirmed by a second camera (ChainReacquisition).
class ChainFilter {
 public:
  ChainFilter(ChainDefinition chain, ChainState initial, const ChainMotionNoise& noise,
              const ChainUpdateOptions& options);
  ChainFrameResult process(const CameraModel& camera, TimeNs stamp_ns,
                           const std::vector<Eigen::Vector2d>& blobs);

  const ChainState& state() const { return state_; }
  const ChainDefinition& chain() const { return chain_; }
  TimeNs last_update_ns(int marker) const { return last_update_ns_[marker]; }
  int reacquisitions() const { return reacquisitions_; }

 private:
  struct CandidateRay {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    TimeNs stamp_ns = 0;
  };
  // The point where `ray` and a pending ray of another camera meet, in the chain's plane, at the
  // link lengths from the marker's fresh neighbours; otherwise nullopt and `ray` joins the pending.
  std::optional<Eigen::Vector3d> confirmed(int marker, const CandidateRay& ray);
  // After a confirmed re-acquisition of a marker with no fresh marker beyond it, its joint angle
  // is set from the point (the linearised update cannot bridge a large angle error).
  void reinitialise_outer_joint(int marker, const Eigen::Vector3d& point,
                                const std::array<bool, kMaxChainMarkers>& stale);

  ChainDefinition chain_;
  ChainState state_;
  ChainMotionNoise noise_;
  ChainUpdateOptions options_;
  std::array<TimeNs, kMaxChainMarkers> last_update_ns_{};
  std::array<std::vector<CandidateRay>, kMaxChainMarkers> pending_{};  // within the pair window
  int reacquisitions_ = 0;
};

// World positions of the markers and the tip `horizon_s` ahead (base pose with body_ekf.h's
// extrapolate_pose, joints with their rates).
struct ChainPose {
  std::vector<Eigen::Vector3d> markers;
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  JointVector angles = JointVector::Zero();
  RigidTransform base_pose;
};
ChainPose chain_pose(const ChainState& state, const ChainDefinition& chain, double horizon_s = 0.0);

// ---- Identification (seed 000 §6.4.4 "Matching of markers", Fig. 6.21) ----

struct ChainIdentificationOptions {
  double distance_tolerance_m = 0.003;  // |distance - link length| on each sphere
  double plane_tolerance_m = 0.004;     // markers' distance from the chain's plane
  double limit_tolerance_rad = 0.15;    // joint angles may exceed their limits by this much
  double prediction_gate_m = 0.02;      // with a prediction: each marker within this of it
  int max_paths = 64;                   // give up (ambiguous) beyond this many complete paths
};

enum class ChainIdentificationStatus { kIdentified, kNotFound, kAmbiguous };

struct ChainIdentification {
  ChainIdentificationStatus status = ChainIdentificationStatus::kNotFound;
  std::vector<int> point_indices;  // marker k -> index into the points, base first
  RigidTransform base_pose;        // R_world_base from the identified markers
  JointVector angles = JointVector::Zero();
  int valid_paths = 0;  // complete paths passing every check (1 when identified)
};

// The base frame and joint angles of a chain from its markers' world positions (base first):
// x̂ towards marker 1, ẑ from the bends (so that the dominant bend is positive); for a straight
// chain ẑ is any perpendicular (the roll about the chain is then unobservable). Also returns the
// largest distance of a marker from the chain's plane.
struct ChainFit {
  RigidTransform base_pose;
  JointVector angles = JointVector::Zero();
  double plane_residual_m = 0.0;
};
ChainFit fit_chain(const std::vector<Eigen::Vector3d>& markers);

// Sphere search from every point for consecutive markers at the link lengths, then the plane and
// joint-limit checks. Identified only when exactly one path passes (after the optional prediction
// gate); otherwise not found or ambiguous, never a guess.
ChainIdentification identify_chain(const ChainDefinition& chain, const std::vector<Eigen::Vector3d>& points,
                                   const ChainIdentificationOptions& options,
                                   const std::vector<Eigen::Vector3d>* predicted_markers = nullptr);

// A filter state from an identification, with the given prior.
ChainState chain_state_from_identification(const ChainIdentification& identification, TimeNs stamp_ns,
                                           const ChainPriorSigmas& prior, int joint_count);

// ---- Grab gestures (seed 000 §6.4.5) ----

struct GrabOptions {
  double grab_bend_rad = 1.6;        // sum of joint angles above which the finger grabs
  double release_bend_rad = 1.0;     // ... below which it releases (hysteresis)
  TimeNs min_dwell_ns = 20'000'000;  // beyond the threshold this long before the event fires
};

enum class GrabEventKind { kGrab, kRelease };

struct GrabEvent {
  GrabEventKind kind = GrabEventKind::kGrab;
  TimeNs stamp_ns = 0;  // when the bend crossed the threshold
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  double bend_rad = 0.0;
};

class GrabDetector {
 public:
  explicit GrabDetector(const GrabOptions& options) : options_(options) {}
  // Feeds one estimate (in time order); returns an event when the state changes.
  std::optional<GrabEvent> observe(TimeNs stamp_ns, double bend_rad, const Eigen::Vector3d& tip);
  bool grabbing() const { return grabbing_; }

 private:
  GrabOptions options_;
  bool grabbing_ = false;
  std::optional<TimeNs> crossed_ns_;
};

}  // namespace panoptes::estimator

namespace panoptes::estimator {

// ---- Several chains, from identification to outputs (what the estimator application wires) ----

enum class ChainStatus {
  kNotIdentified,  // no complete chain among the points (or lost: every marker unseen too long)
  kAmbiguous,      // several candidate chains: reported, never forced
  kTracking,
};

struct ChainTrackerOptions {
  ChainMotionNoise noise;
  ChainUpdateOptions update;
  ChainIdentificationOptions identification;
  // After identification from triangulated points (millimetres, a few degrees; the motion
  // unknown within what a hand does).
  ChainPriorSigmas prior{.base = {.position_m = 0.002,
                                  .velocity_mps = 0.3,
                                  .acceleration_mps2 = 2.0,
                                  .angle_rad = 0.05,
                                  .angular_velocity_radps = 1.0,
                                  .angular_acceleration_radps2 = 5.0},
                         .angle_rad = 0.05,
                         .rate_radps = 3.0};
  TimeNs lost_after_ns = 300'000'000;  // every marker unseen this long: lost, identify again
  GrabOptions grab;
};

struct ChainOutput {
  std::string name;
  ChainStatus status = ChainStatus::kNotIdentified;
  TimeNs stamp_ns = 0;
  ChainPose pose;                  // valid when tracking
  std::vector<bool> marker_valid;  // updated within the stale time
  bool grabbing = false;
};

struct NamedGrabEvent {
  std::string chain;
  GrabEvent event;
};

class ChainTracker {
 public:
  ChainTracker(std::vector<ChainDefinition> chains, const ChainTrackerOptions& options);

  // 3D points at `stamp_ns` (confirmed point tracks, or triangulated markers): every chain not
  // being tracked is searched for among them.
  void identify(TimeNs stamp_ns, const std::vector<Eigen::Vector3d>& points);
  // One camera frame (in stamp order) for every tracked chain; grab events are queued.
  void process(const CameraModel& camera, TimeNs stamp_ns, const std::vector<Eigen::Vector2d>& blobs);

  std::vector<ChainOutput> outputs(double horizon_s = 0.0) const;
  std::vector<NamedGrabEvent> take_events();

 private:
  struct Entry {
    ChainDefinition definition;
    ChainStatus status = ChainStatus::kNotIdentified;
    std::optional<ChainFilter> filter;
    GrabDetector grab;
  };
  ChainTrackerOptions options_;
  std::vector<Entry> entries_;
  std::vector<NamedGrabEvent> events_;
};

}  // namespace panoptes::estimator
