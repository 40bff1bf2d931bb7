// SPDX-License-Identifier: Apache-2.0
// Monocular 7-LED markers (seed 004: Tjaden et al., "High-Speed and Robust Monocular Tracking",
// VISAPP 2015; docs/monocular_markers.md). Pure maths on undistorted normalised image coordinates
// (x/z, y/z) of one camera: LED identification (§2.2.2), pose with the pointer LED (§2.2.3),
// several markers by k-means and cross-ratio (§2.2.4), and self-calibration (§3, Algorithm 3.1).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/geometry.h"

namespace panoptes::estimator {

inline constexpr int kLedCount = 7;
// One marker's seven image points, ordered m_0 .. m_6 (normalised coordinates).
using LedPoints = std::array<Eigen::Vector2d, kLedCount>;

// CR(a, b; c, d) = |a - c| |b - d| / (|b - c| |a - d|); the marker ID is CR(M0, M3; M2, M1), eq. 6.
double led_cross_ratio(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                       const Eigen::Vector2d& d);

// The seven LEDs M_0..M_6 of one marker in its model frame (metres). The paper's frame (§2.1): M3 at
// the origin, x along M3->M2 (M0, M1, M2 on +x), y along M3->M5, M0..M5 in the xy-plane, M6 elevated
// (z != 0) on the far side of the line M4-M5 from M0. Any rigid frame is accepted (e.g. a body
// frame); poses are then T_cam_<that frame>.
class LedMarkerModel {
 public:
  // Validates the layout: M0..M3 collinear in this order, M0..M5 coplanar, M4 and M5 on opposite
  // sides of M0-M3 with M3 between them, M6 off the plane and beyond the line M4-M5. Tolerances
  // are a fraction of |M0 M3| (2% for the line/plane, M6 at least 3% off the plane).
  // create(): nullopt and *error says what is wrong; from_points()/from_body() throw
  // std::invalid_argument with that message (prefixed by the name).
  static std::optional<LedMarkerModel> create(std::string name, const std::array<Eigen::Vector3d, 7>& leds,
                                              std::string* error = nullptr);
  static LedMarkerModel from_points(std::string name, const std::array<Eigen::Vector3d, 7>& leds);
  static LedMarkerModel from_body(const BodyDefinition& body);  // needs exactly 7 markers, M_i = markers[i]

  const std::string& name() const { return name_; }
  const std::array<Eigen::Vector3d, 7>& leds() const { return leds_; }
  double cross_ratio() const { return cross_ratio_; }  // eq. 6
  double d03() const { return d03_; }                  // |M0 M3|, the scale of the marker

  // Internal plane frame (origin M3, x to M0, y to the M5 side, z = x cross y) used by the pose:
  // LED positions in it (M0..M5 have z ~ 0) and the transform into the model frame.
  const std::array<Eigen::Vector3d, 7>& plane_leds() const { return plane_leds_; }
  const RigidTransform& T_model_plane() const { return T_model_plane_; }
  // +1 when a camera in front of the marker (on M6's side) sees cross(m0 - m3, m5 - m3) > 0 in
  // image coordinates (x right, y down), i.e. the paper's layout; -1 for a mirrored layout.
  int handedness() const { return handedness_; }

 private:
  std::string name_;
  std::array<Eigen::Vector3d, 7> leds_{};
  std::array<Eigen::Vector3d, 7> plane_leds_{};
  RigidTransform T_model_plane_;
  double cross_ratio_ = 0;
  double d03_ = 0;
  int handedness_ = 1;
};

// The three projection configurations of §2.2.2 (Fig. 2).
enum class LedCase { kL5, kL41, kL42 };
std::string_view to_string(LedCase c);

// Homography G with to[i] ~ G from[i] from the first six points of each (the marker's coplanar
// LEDs M0..M5): DLT on Hartley-normalised coordinates with h33 = 1 in the normalised frames, where
// it is bounded away from zero. nullopt for coincident points or a singular system.
std::optional<Eigen::Matrix3d> six_point_homography(const LedPoints& from, const LedPoints& to);

// Model-free 2D identification (§2.2.2) of the seven points of one cluster, for the paper's
// handedness (+1; swap 4 and 5 for a mirrored model). index[i] is the input index of m_i. For
// L42 the 2D criteria cannot tell m4/m5 from m6 (Figs. 2c, 2d): `alternative` then holds the
// assignment with those two swapped, to be decided in 3D (see LedMarkerDetector).
struct LedIdentification {
  LedCase led_case = LedCase::kL41;
  std::array<int, 7> index{};
  std::optional<std::array<int, 7>> alternative;
};
// `line_tolerance`: a point belongs to a line if it is within this fraction of the cluster's
// diameter (largest distance between two of its points). nullopt: not a 7-LED pattern (no line
// of four, non-finite input, contradictory geometry).
std::optional<LedIdentification> identify_led_pattern(const LedPoints& points, double line_tolerance = 0.02);

// How the pose is chosen among the minima of eq. 3 (§2.2.3 and the comparison methods of §4.4).
enum class LedPoseMethod {
  kPointer,            // the paper's method: P1, P2 on the six coplanar LEDs, eq. 5, then all seven
  kCoplanar,           // method 1, eq. 9: P1 only
  kCoplanarBestOfTwo,  // method 2, eq. 10: smaller coplanar error of P1, P2 (Schweighofer & Pinz)
  kAllSeven,           // method 3, eq. 11: LM on all seven from the homography pose
};

struct LedPose {
  RigidTransform T_cam_marker;  // maps model-frame coordinates into the camera frame
  double rms = 0;               // reprojection RMS over the seven LEDs, normalised units
};

// Pose from known correspondences: points[i] is the image of M_i. Homography from M0..M5 (Xu et
// al. style planar decomposition), Levenberg-Marquardt on eq. 3, second planar minimum, pointer
// choice (eq. 4-5) and a final refinement with all seven. nullopt on degenerate input.
std::optional<LedPose> estimate_led_marker_pose(const LedMarkerModel& model, const LedPoints& points,
                                                LedPoseMethod method = LedPoseMethod::kPointer);
// The homography pose P_H alone (M0..M5 only), as used to resolve L42.
std::optional<RigidTransform> led_marker_homography_pose(const LedMarkerModel& model,
                                                         const LedPoints& points);
// Mean squared reprojection error per LED of a pose over all seven LEDs (eq. 3 / 7).
double led_reprojection_error(const LedMarkerModel& model, const RigidTransform& T_cam_marker,
                              const LedPoints& points);

// k-means of §2.2.4 with k clusters and the seven-member initialisation. Deterministic for a
// seed. Returns the input indices of each cluster (clusters may have any size, even zero).
std::vector<std::vector<int>> cluster_led_points(const std::vector<Eigen::Vector2d>& points, int k,
                                                 std::uint64_t seed = 0, int max_iterations = 20);

struct LedMarkerOptions {
  double line_tolerance = 0.02;  // see identify_led_pattern
  // Which model (eq. 6): the nearest cross-ratio, accepted if |CR - CR_model| / CR_model is within
  // max(cross_ratio_tolerance, cross_ratio_sigmas * sigma), sigma being the relative CR error
  // that `centroid_sigma` (normalised units: pixel noise / focal length) gives this cluster.
  // Models are told apart reliably while their CRs differ by more than twice that bound.
  double cross_ratio_tolerance = 0.02;
  double cross_ratio_sigmas = 4.0;
  double centroid_sigma = 0.1 / 1600.0;
  double max_rms = 1.5e-3;  // normalised units; reject above (~2.4 px at f = 1600 px)
  std::uint64_t seed = 0;   // k-means initialisation
  int kmeans_iterations = 20;
  // Extension to §2.2.4: if k = floor(n/7) leaves a cluster with != 7 members and points are
  // left over, try again with k + 1 so a partial marker or stray blobs get a cluster of their own.
  bool retry_extra_cluster = true;
};

struct LedMarkerDetection {
  int model = -1;               // index into the detector's models
  std::array<int, 7> blob{};    // blob[i]: input index of the image of M_i
  RigidTransform T_cam_marker;  // model frame -> camera frame
  double rms = 0;               // normalised units over the seven LEDs
  LedCase led_case = LedCase::kL41;
};

class LedMarkerDetector {
 public:
  explicit LedMarkerDetector(std::vector<LedMarkerModel> models, LedMarkerOptions options = {});
  const std::vector<LedMarkerModel>& models() const { return models_; }
  const LedMarkerOptions& options() const { return options_; }

  // All markers found among one frame's points (undistorted normalised coordinates, e.g. from
  // CameraModel::pixel_to_normalized). Non-finite points are ignored.
  std::vector<LedMarkerDetection> detect(const std::vector<Eigen::Vector2d>& ideal_points) const;
  // One cluster of exactly seven points (indices into `ideal_points`).
  std::optional<LedMarkerDetection> detect_cluster(const std::vector<Eigen::Vector2d>& ideal_points,
                                                   const std::array<int, 7>& cluster) const;

 private:
  std::vector<LedMarkerModel> models_;
  LedMarkerOptions options_;
};

// Semi-automatic marker calibration (§3, Algorithm 3.1) from one camera's frames of a single
// marker, each with its seven identified normalised points, and the measured |M0 M3| = d03.
struct LedCalibrationOptions {
  int subsample = 50;  // o: every o-th frame for the initialisation (fewer if needed
                       //    to keep at least `min_init_frames`)
  int min_init_frames = 8;
  int max_iterations = 300;  // refinement
  double epsilon = 1e-7;     // metres (the paper's 0.0001 mm): stop when e, the total LED motion
                             // of an iteration, or its change Delta e falls below this (§3.2)
};
struct LedCalibrationResult {
  std::array<Eigen::Vector3d, 7> initial{};  // after the initialisation (median), marker frame
  std::array<Eigen::Vector3d, 7> leds{};     // refined, marker frame (M3 origin, M0 on +x, M5 in xy)
  int pairs_used = 0;                        // initialisation pairs that gave a structure
  int frames_used = 0;                       // frames with a pose in the last refinement pass
  int iterations = 0;
  double rms = 0;  // final reprojection RMS, normalised units
};
// Throws std::invalid_argument (too few frames, d03 <= 0) or std::runtime_error (no usable pair,
// the result is not a valid marker layout).
LedCalibrationResult calibrate_led_marker(const std::vector<LedPoints>& frames, double d03,
                                          const LedCalibrationOptions& options = {});
// Expresses LEDs in the canonical frame of eq. 7: M3 origin, M0 = (|M0 M3|, 0, 0), M5 in the
// xy-plane with y > 0.
std::array<Eigen::Vector3d, 7> canonical_led_frame(const std::array<Eigen::Vector3d, 7>& leds);

}  // namespace panoptes::estimator
