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
#include <optional>
#include <string>
#include <vector>

#include "panoptes/planner/metric.h"

namespace panoptes::planner {

struct PlanProgress {
  int evaluations = 0;
  int start = 0;       // which of the starts is running (0-based); = starts: the iterated search
  double best = 0;     // the objective's best value so far
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
  // What the search minimises (docs/planner.md, "Objectives"); `tracker` for kTrackerRmse. The
  // library's default is the seed's q (its examples are q's); panoptes_plan's is the room file's.
  Objective objective = Objective::kQuality;
  TrackerModel tracker;
  std::function<void(const PlanProgress&)> progress;  // called about every 2% of the budget
};

struct PlanResult {
  std::vector<PlannedCamera> cameras;  // fixed first, then the placed ones
  Evaluation evaluation;
  double objective_value = 0;   // of the plan, by a full evaluation (objective_value())
  std::vector<double> history;  // the objective's best value after each sweep over the cameras
  int evaluations = 0;
  double seconds = 0;      // wall
  double cpu_seconds = 0;  // this process's CPU time
  bool stopped_by_time = false;
};

// Throws std::invalid_argument naming the constraint that makes the plan infeasible (no mounting
// surface, no lens, a volume no mount position can see).
PlanResult plan(const Room& room, const SampleSet& samples, const MetricOptions& metric,
                const PlanOptions& options);

// The objective's value for `cameras` by a full evaluation: evaluate(...).quality or
// predict_tracking(...).rmse_gaps_charged_m.
double objective_value(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                       std::span<const Box> obstacles, const MetricOptions& metric, Objective objective,
                       const TrackerModel& tracker);

// The objective without each camera in turn: which one costs least to remove.
std::vector<double> removal_costs(std::span<const PlannedCamera> cameras, const SampleSet& samples,
                                  std::span<const Box> obstacles, const MetricOptions& metric,
                                  Objective objective = Objective::kQuality,
                                  const TrackerModel& tracker = {});

// The objective's name in room files and on the command line ("q", "tracker_rmse"), and back;
// std::nullopt for an unknown name.
const char* objective_name(Objective objective);
std::optional<Objective> objective_from_name(const std::string& name);

// A camera from its genes, each in [0, 1]: surface, s, t, aim x, y, z, lens (kGenes per camera).
inline constexpr int kGenes = 7;
PlannedCamera decode_camera(const Room& room, const double* genes, const std::string& id);

}  // namespace panoptes::planner
