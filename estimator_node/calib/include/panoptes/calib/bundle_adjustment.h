// SPDX-License-Identifier: Apache-2.0
// Stage 3 of the wand solver: one bundle adjustment over cameras (pose, intrinsics, clock offset)
// and wand instants (all markers of an instant in one block), with the wand's lengths as
// residuals (seed 000 eq. 4.76), in passes that drop outliers and decide what intrinsics move; or
// seed 003 §3.3.2's alternation. docs/calibration.md, "Stages". No Ceres type in this header.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

#include "panoptes/calib/solve_options.h"
#include "panoptes/calib/solve_stats.h"
#include "panoptes/calib/wand_samples.h"
#include "panoptes/calibration.h"

namespace panoptes::calib {

// One camera as the adjustment holds it.
struct CameraParameters {
  std::array<double, 6> pose{};        // T_cam_world: angle-axis, translation
  std::array<double, 9> intrinsics{};  // fx, fy, cx, cy, k1, k2, p1, p2, k3 (OpenCV, as CameraModel)
  double offset_s = 0;                 // camera clock minus reference clock
  bool registered = false;             // placed, and taking part
};

// `given` into parameters; registered (with its pose) iff T_world_cam is given.
CameraParameters camera_parameters(const CameraIntrinsics& given,
                                   const std::optional<RigidTransform>& T_world_cam);
RigidTransform T_world_cam_of(const CameraParameters& camera);
// `given` with the nine parameters replaced (its image size and other fields kept).
CameraIntrinsics intrinsics_of(const CameraParameters& camera, const CameraIntrinsics& given);
CameraModel model_of(const CameraParameters& camera, const CameraIntrinsics& given);

// What the adjustment moves: cameras, which observations take part, and the wand.
struct BundleState {
  std::vector<CameraParameters> cameras;
  std::vector<WandInstant> instants;
  std::vector<double> points;  // instants x markers x 3: marker positions in the world, m
};

// The wand at every instant triangulated from its registered cameras; observations of cameras not
// registered are deactivated, and all of an instant's when one of its markers cannot be triangulated.
BundleState triangulate_instants(BundleState state, const std::vector<CameraIntrinsics>& given,
                                 std::size_t markers);

// kNominal: the focal length (fx and fy together, keeping their ratio) and k1, k2. kSuspect: fx,
// fy, cx, cy, k1, k2 each. kEvidence: per camera what PassOptions::free_intrinsics names (the
// focal length as in kNominal). kAll: all nine (--refine-intrinsics).
enum class IntrinsicsRefinement { kNone, kNominal, kSuspect, kEvidence, kAll };

// kEvidence's per-camera groups (bits), in tangent order: focal length (fx, fy together), aspect
// (fy alone), principal point (cx, cy), k1, k2.
enum IntrinsicsGroup : unsigned {
  kFreeFocal = 1U,
  kFreeCentre = 2U,
  kFreeK1 = 4U,
  kFreeK2 = 8U,
  kFreeAspect = 16U
};
constexpr unsigned kFreeEvidenceAll = kFreeFocal | kFreeAspect | kFreeCentre | kFreeK1 | kFreeK2;
// The tangent size of a kEvidence block with groups `free`.
constexpr int evidence_tangent_size(unsigned free) {
  return ((free & kFreeFocal) != 0U ? 1 : 0) + ((free & kFreeAspect) != 0U ? 1 : 0) +
         ((free & kFreeCentre) != 0U ? 2 : 0) + ((free & kFreeK1) != 0U ? 1 : 0) +
         ((free & kFreeK2) != 0U ? 1 : 0);
}

struct PassOptions {
  int reference = 0;  // camera whose pose (and clock) is the gauge
  IntrinsicsRefinement refinement = IntrinsicsRefinement::kNone;
  std::vector<unsigned> free_intrinsics;  // kEvidence: IntrinsicsGroup bits per camera (none: fixed)
  bool time_offsets = false;
  double huber_px = 1.0;           // robust loss (robust passes only)
  double length_sigma_m = 0.0005;  // weight of the wand-length residuals
  int max_iterations = 100;
  int threads = 2;
  int alternation_iterations = 0;  // for alternate()
};

struct PassReport {
  double rms_px = 0;        // reprojection RMS after the pass (2D norm, robust loss applied)
  int iterations = 0;       // counted into SolveResult::iterations
  int steps = 0;            // Ceres iterations after the initial evaluation
  bool converged = false;   // Ceres CONVERGENCE
  std::string termination;  // Ceres's message
  std::string summary;      // "bundle adjustment: n iterations, ..." for progress
};

struct PassResult {
  BundleState state;
  PassReport report;
};

// One Levenberg-Marquardt pass over the active observations. A robust pass (Huber loss) stops at a
// relative cost change of 1e-6 (it only seeds the outlier test), a plain one at 1e-10.
PassResult adjust_pass(BundleState state, const WandDefinition& wand, const PassOptions& options,
                       bool robust);
// Seed 003 §3.3.2: cameras resected on the fixed trace, then the trace rebuilt, alternation_iterations times.
PassResult alternate(BundleState state, const WandDefinition& wand, const PassOptions& options);

// Every raw (not interpolated) wand frame of every registered camera against the solved wand path at
// the frame's instant on the reference clock: 2D errors per camera, px, per marker observation.
// `tracks` one per camera.
std::vector<std::vector<double>> raw_frame_errors(const BundleState& state,
                                                  const std::vector<CameraModel>& models,
                                                  const std::vector<CameraWandTrack>& tracks,
                                                  std::size_t markers);
ErrorStats error_stats(std::vector<double> errors);
// Models of the registered cameras (default models elsewhere).
std::vector<CameraModel> registered_models(const BundleState& state,
                                           const std::vector<CameraIntrinsics>& given);

// The adjustment's Jacobian at `state` (no robust loss), for the solve's diagnostics
// (solve_diagnostics.h): the reprojection rows (px) apart from the other rows (wand lengths and the
// single-light gauge, already weighted), over the same columns: the tangent space of every block
// the adjustment moves, cameras first, then the wand instants.
struct AdjustmentJacobian {
  Eigen::SparseMatrix<double> reprojection, constraints;
  Eigen::VectorXd reprojection_residuals;  // px
  struct CameraColumns {
    int pose = -1;        // first of 6 (angle-axis, translation of T_cam_world); -1: constant
    int intrinsics = -1;  // first of the intrinsics' tangent; -1: constant
    int offset = -1;      // the clock offset; -1: constant
  };
  std::vector<CameraColumns> cameras;  // per camera of the state
  std::vector<int> instant_columns;    // per instant: first of its 3 x markers, -1: not adjusted
  IntrinsicsRefinement refinement = IntrinsicsRefinement::kNone;
  std::vector<unsigned> free_intrinsics;  // as PassOptions
  int columns = 0;
};

AdjustmentJacobian adjustment_jacobian(BundleState state, const WandDefinition& wand,
                                       const PassOptions& options);

struct BundleAdjustmentResult {
  BundleState state;
  std::vector<std::string> failures;     // per camera: a refined focal length far from the given, or ""
  std::vector<bool> intrinsics_refined;  // per camera
  IntrinsicsRefinement refinement = IntrinsicsRefinement::kNone;
  std::vector<unsigned> free_intrinsics;  // kEvidence: per camera
  std::string intrinsics_refined_why;     // SolveResult::intrinsics_refined
  std::string intrinsics_declined;        // SolveResult::intrinsics_declined
  bool converged = false;                 // every pass
  std::string convergence;                // SolveResult::convergence
  int iterations = 0;
};

// The whole stage from the view graph's cameras: triangulation, intrinsics decision, the passes
// with outlier removal (and clock-offset re-lookups), the focal-length check; or the alternation
// when options.alternation_iterations > 0. `cameras` supplies ids, given intrinsics and whether they
// are nominal; `tracks` one per camera.
BundleAdjustmentResult bundle_adjust(BundleState state, int reference,
                                     const std::vector<CameraCalibration>& cameras,
                                     const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand,
                                     const SolveOptions& options,
                                     const std::function<void(const std::string&)>& progress = {});

}  // namespace panoptes::calib
