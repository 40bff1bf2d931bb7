// SPDX-License-Identifier: Apache-2.0
// PNG plot of an evaluation (panoptes_eval --plot): position error over time of the worst markers
// and the overall RMS, ID switches marked, and where markers were trackable but untracked.
// Drawn with OpenCV, which only panoptes_eval links (the estimator core does not).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

#include "panoptes/eval/evaluation.h"

namespace panoptes::estimator {

struct PlotOptions {
  int width = 1600;               // pixels
  int height = 900;               // pixels
  std::size_t worst_markers = 6;  // markers drawn individually, highest RMSE first
  std::string title;
};

// Needs an evaluation made with EvaluationOptions::keep_series. Throws std::runtime_error when
// the series is missing or the file cannot be written.
void write_error_plot(const Evaluation& evaluation, const PlotOptions& options,
                      const std::filesystem::path& png);

}  // namespace panoptes::estimator
