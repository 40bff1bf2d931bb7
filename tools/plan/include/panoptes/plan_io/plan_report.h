// SPDX-License-Identifier: Apache-2.0
// The planner's report (docs/planner.md, "Reading the report"): top and side views with the
// cameras' frusta and the coverage of the sample points, the optimisation history, and a
// self-contained HTML page with the figures and a table per camera.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "panoptes/planner/metric.h"

namespace panoptes::planner {

struct ReportInput {
  std::string title;
  const Room* room = nullptr;
  const SampleSet* samples = nullptr;
  MetricOptions metric;
  std::vector<PlannedCamera> cameras;
  Evaluation evaluation;
  TrackingPrediction tracking;        // the tracker's predicted error (docs/planner.md, "Validation")
  std::string objective = "q";        // what the history and the removal costs are of
  std::vector<double> removal_costs;  // the objective without each camera (may be empty)
  std::vector<double> history;        // the objective's best value per sweep (may be empty)
  std::string notes;                  // how the plan was made (command, budget, time)
};

// Writes top.png, side.png, history.png (when there is a history) and report.html into `dir`.
void write_report(const ReportInput& input, const std::filesystem::path& dir);

}  // namespace panoptes::planner
