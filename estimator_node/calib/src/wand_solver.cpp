// SPDX-License-Identifier: Apache-2.0
// solve_wand_calibration: the cameras checked and the wand sampled, then the stages one after the
// other, each from the previous one's output (docs/calibration.md, "Stages"): two_view.h,
// view_graph.h, bundle_adjustment.h, solve_finish.h.
#include "panoptes/calib/wand_solver.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>

#include "panoptes/calib/bundle_adjustment.h"
#include "panoptes/calib/solve_diagnostics.h"
#include "panoptes/calib/solve_finish.h"
#include "panoptes/calib/two_view.h"
#include "panoptes/calib/view_graph.h"
#include "panoptes/calib/wand_samples.h"

namespace panoptes::calib {

namespace {

using Clock = std::chrono::steady_clock;
using Progress = std::function<void(const std::string&)>;

// Every camera's track (matched by id; empty if the camera has none), and which cameras had one.
struct AlignedTracks {
  std::vector<CameraWandTrack> tracks;
  std::vector<bool> present;
};

AlignedTracks align_tracks(const std::vector<CameraCalibration>& cameras,
                           const std::vector<CameraWandTrack>& tracks) {
  AlignedTracks out;
  for (const auto& camera : cameras) {
    const CameraWandTrack* found = nullptr;
    for (const auto& track : tracks)
      if (track.camera_id == camera.id) found = &track;
    out.tracks.push_back(found != nullptr ? *found : CameraWandTrack{});
    out.present.push_back(found != nullptr);
  }
  return out;
}

// A wand whose ends look alike: the cameras' label runs agree only after resolve_bar_labels.
BarLabelReport resolve_labels(const std::vector<CameraCalibration>& cameras, AlignedTracks& aligned,
                              const SolveOptions& options, const Progress& progress) {
  std::vector<CameraWandTrack> present;
  std::vector<CameraIntrinsics> intrinsics;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    if (!aligned.present[c]) continue;
    present.push_back(std::move(aligned.tracks[c]));
    intrinsics.push_back(cameras[c].intrinsics);
  }
  BarLabelOptions label_options;
  label_options.sample_rate_hz = options.sample_rate_hz;
  label_options.max_gap_frames = options.max_gap_frames;
  label_options.min_pair_samples = options.min_pair_samples;
  const BarLabelReport report = resolve_bar_labels(present, intrinsics, label_options);
  for (std::size_t c = 0, k = 0; c < cameras.size(); ++c)
    if (aligned.present[c]) aligned.tracks[c] = std::move(present[k++]);
  progress("bar ends: " + std::to_string(report.runs) + " label runs, " +
           std::to_string(report.flipped_runs) + " reversed, " + std::to_string(report.dropped_runs) +
           " unrelated runs dropped (" + std::to_string(report.dropped_frames) + " frames); " +
           std::to_string(report.conflicting_votes) + " of " + std::to_string(report.votes) +
           " votes against the labelling");
  return report;
}

// Why a camera without usable wand frames has none; "" if it is usable.
std::string track_failure(const CameraWandTrack& track, bool present, const WandDefinition& wand,
                          const SolveOptions& options) {
  if (!present) return "no features for this camera";
  const auto& counters = track.counters;
  if (track.frames.empty()) {
    std::ostringstream why;
    if (counters.spacing_mismatches > 0 && counters.spacing_mismatches * 2 >= counters.collinear_candidates) {
      why << "lengths never match: " << counters.spacing_mismatches << " frames showed "
          << wand.marker_count()
          << " collinear blobs, but their spacing never matched the wand (2nd marker at "
          << counters.mean_mismatch_spacing << " of the bar, expected "
          << (wand.marker_count() > 2 ? (wand.positions[1] - wand.positions[0]) / wand.length() : 0.0)
          << "); check --wand";
    } else {
      why << "never saw the wand (" << counters.frames << " frames, " << counters.frames_with_enough_blobs
          << " with >= " << wand.marker_count() << " blobs, " << counters.ambiguous << " ambiguous)";
    }
    return why.str();
  }
  const int frames = static_cast<int>(track.frames.size());
  if (frames < options.min_camera_frames)
    return "too few wand observations (" + std::to_string(frames) + " frames, need " +
           std::to_string(options.min_camera_frames) + ")";
  return "";
}

// The result's cameras (given intrinsics, counters, failures); returns which cameras are usable.
std::vector<bool> check_cameras(const std::vector<CameraCalibration>& cameras, const AlignedTracks& aligned,
                                const WandDefinition& wand, const SolveOptions& options,
                                SolveResult& result) {
  std::vector<bool> usable(cameras.size(), false);
  result.cameras.resize(cameras.size());
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    auto& camera = result.cameras[c];
    camera.id = cameras[c].id;
    camera.intrinsics = cameras[c].intrinsics;
    camera.given_intrinsics = cameras[c].intrinsics;
    if (aligned.present[c]) {
      camera.counters = aligned.tracks[c].counters;
      camera.wand_frames = static_cast<int>(aligned.tracks[c].frames.size());
    }
    camera.failure = track_failure(aligned.tracks[c], aligned.present[c], wand, options);
    usable[c] = camera.failure.empty();
  }
  return usable;
}

PairwiseResult pairwise(const std::vector<CameraCalibration>& cameras, const WandInstants& instants,
                        const WandDefinition& wand, const SolveOptions& options, const Progress& progress) {
  TwoViewOptions two_view;
  two_view.min_pair_samples = options.min_pair_samples;
  two_view.max_pair_samples = options.max_pair_samples;
  two_view.ransac_threshold_px = options.ransac_threshold_px;
  PairwiseResult result = pairwise_relative_poses(cameras, instants.instants, wand, two_view, progress);
  progress("pairwise relative poses: " + std::to_string(result.pairs.size()) + " of " +
           std::to_string(result.pairs_with_common) + " camera pairs with common samples");
  return result;
}

ViewGraphResult view_graph(const std::vector<CameraCalibration>& cameras, const std::vector<bool>& usable,
                           const PairwiseResult& pairs, const WandDefinition& wand,
                           const SolveOptions& options, SolveResult& result) {
  ViewGraphInput input;
  for (const auto& camera : cameras) input.camera_ids.push_back(camera.id);
  input.usable = usable;
  input.pairs = pairs.pairs;
  input.metric = wand.marker_count() >= 2;
  input.reference_camera = options.reference_camera;
  input.min_pair_samples = options.min_pair_samples;
  ViewGraphResult graph = unify_view_graph(input);
  for (std::size_t c = 0; c < cameras.size(); ++c)
    if (result.cameras[c].failure.empty()) result.cameras[c].failure = graph.failures[c];
  for (std::size_t edge : graph.used_edges) result.edges[edge].used = true;
  if (graph.reference >= 0) result.reference_camera = cameras[graph.reference].id;
  return graph;
}

// The bundle adjustment from the view graph's placement, its outcome into `result`.
BundleState adjust(const std::vector<CameraCalibration>& cameras, const AlignedTracks& aligned,
                   WandInstants instants, const ViewGraphResult& graph, const WandDefinition& wand,
                   const SolveOptions& options, const Progress& progress, SolveResult& result) {
  BundleState state;
  for (std::size_t c = 0; c < cameras.size(); ++c)
    state.cameras.push_back(camera_parameters(cameras[c].intrinsics, graph.T_world_cam[c]));
  state.instants = std::move(instants.instants);
  BundleAdjustmentResult adjusted =
      bundle_adjust(std::move(state), graph.reference, cameras, aligned.tracks, wand, options, progress);
  result.intrinsics_refined = adjusted.intrinsics_refined_why;
  result.intrinsics_declined = adjusted.intrinsics_declined;
  result.converged = adjusted.converged;
  result.convergence = adjusted.convergence;
  result.iterations += adjusted.iterations;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    if (adjusted.intrinsics_refined[c]) result.cameras[c].intrinsics_refined = true;
    if (!adjusted.failures[c].empty() && result.cameras[c].failure.empty())
      result.cameras[c].failure = adjusted.failures[c];
  }
  if (options.alternation_iterations == 0) {
    PassOptions last;  // the final pass's problem: plain least squares, the chosen refinement
    last.reference = graph.reference;
    last.refinement = adjusted.refinement;
    last.free_intrinsics = adjusted.free_intrinsics;
    last.time_offsets = options.time_offsets;
    last.length_sigma_m = options.length_sigma_m;
    last.threads = options.threads;
    const SolveDiagnostics diagnostics = solve_diagnostics(adjusted.state, wand, last);
    for (std::size_t c = 0; c < cameras.size(); ++c) result.cameras[c].focal_depth = diagnostics.cameras[c];
    result.predicted_length_rms_mm = diagnostics.predicted_length_rms_mm;
    progress("solve diagnostics: focal length and depth from the final adjustment's normal equations");
  }
  return std::move(adjusted.state);
}

SolveResult solve(const std::vector<CameraCalibration>& cameras, const std::vector<CameraWandTrack>& tracks,
                  const WandDefinition& wand, const SolveOptions& options) {
  const auto start = Clock::now();
  const Progress progress = [&](const std::string& message) {
    if (!options.progress) return;
    char elapsed[32];
    std::snprintf(elapsed, sizeof(elapsed), "[%.1f s] ",
                  std::chrono::duration<double>(Clock::now() - start).count());
    options.progress(elapsed + message);
  };
  SolveResult result;
  if (const std::string problem = wand.validate(); !problem.empty()) {
    result.errors.push_back("wand: " + problem);
    return result;
  }
  result.metric = wand.marker_count() >= 2;
  AlignedTracks aligned = align_tracks(cameras, tracks);
  if (wand.ends_indistinguishable()) result.bar_labels = resolve_labels(cameras, aligned, options, progress);
  const std::vector<bool> usable = check_cameras(cameras, aligned, wand, options, result);
  WandInstants instants =
      sample_wand_instants(aligned.tracks, usable, {options.sample_rate_hz, options.max_gap_frames});
  result.synchronised = instants.synchronised;
  progress("wand samples: " + std::to_string(instants.instants.size()) + " instants seen by >= 2 cameras" +
           (instants.synchronised ? " (synchronised cameras: the frames themselves)" : " (interpolated)"));
  const PairwiseResult pairs = pairwise(cameras, instants, wand, options, progress);
  result.edges = pairs.edges;
  const ViewGraphResult graph = view_graph(cameras, usable, pairs, wand, options, result);
  if (graph.reference >= 0) {
    progress("global unification: " + std::to_string(graph.placed) + " cameras placed, reference " +
             result.reference_camera);
    const BundleState adjusted =
        adjust(cameras, aligned, std::move(instants), graph, wand, options, progress, result);
    result = finish_solution(std::move(result), adjusted, cameras, aligned.tracks, wand);
    result.warnings = solve_warnings(result, options);
  }
  for (const auto& camera : result.cameras)
    if (!camera.failure.empty()) result.errors.push_back(camera.id + ": " + camera.failure);
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace

SolveResult solve_wand_calibration(const std::vector<CameraCalibration>& cameras,
                                   const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand,
                                   const SolveOptions& options) {
  return solve(cameras, tracks, wand, options);
}

}  // namespace panoptes::calib
