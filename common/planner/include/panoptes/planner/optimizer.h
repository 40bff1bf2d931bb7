// SPDX-License-Identifier: Apache-2.0
// Camera placement by optimisation of the quality metric (seed 003 §4.5 uses an evolutionary
// optimiser). Each camera is a mount position on one of the room's surfaces, an aim point in the
// working volume and a lens. The search moves one camera at a time, so that each move costs only
// that camera's share of the metric (incremental_metric.h): from several greedy starts, a (1+1)
// evolution strategy per camera, then an iterated local search that re-places one or two cameras
// at a time from the best layout. Deterministic for a seed when it ends on its evaluation budget.
// docs/planner.md, "The optimiser".
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "panoptes/planner/metric.h"

namespace panoptes::planner {

struct PlanProgress {
  int evaluations = 0;
  int start = 0;       // which of the starts is running (0-based); = starts: the iterated search
  double best = 0;     // best quality so far
  double seconds = 0;  // since the plan began
};

struct PlanOptions {
  int cameras = 8;                   // cameras to place (besides `fixed`)
  std::vector<PlannedCamera> fixed;  // an existing rig the new cameras are added to
  int evaluations = 4000;            // budget: one evaluation = the metric after one camera moved
  double seconds = 60.0;             // time cap (a run cut by it is not reproducible)
  bool cpu_clock = false;            // `seconds` counts this process's CPU time, not wall time
  int starts = 3;                    // independent greedy starts before the iterated search
  std::uint64_t seed = 1;
  std::function<void(const PlanProgress&)> progress;  // called about every 2% of the budget
};

struct PlanResult {
  std::vector<PlannedCamera> cameras;  // fixed first, then the placed ones
  Evaluation evaluation;
  std::vector<double> history;  // best quality after each sweep over the cameras
  int evaluations = 0;
  double seconds = 0;      // wall
  double cpu_seconds = 0;  // this process's CPU time
  bool stopped_by_time = false;
};

// Throws std::invalid_argument naming the constraint that makes the plan infeasible (no mounting
// surface, no lens, a volume no mount position can see).
PlanResult plan(const Room& room, const SampleSet& samples, const MetricOptions& metric,
                const PlanOptions& options);

// The quality without each camera in turn: which one costs least to remove.
std::vector<double> removal_costs(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                                  std::span<const Box> obstacles, const MetricOptions& metric);

// A camera from its genes, each in [0, 1]: surface, s, t, aim x, y, z, lens (kGenes per camera).
inline constexpr int kGenes = 7;
PlannedCamera decode_camera(const Room& room, const double* genes, const std::string& id);

}  // namespace panoptes::planner
