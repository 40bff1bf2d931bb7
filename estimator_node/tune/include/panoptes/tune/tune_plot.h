// SPDX-License-Identifier: Apache-2.0
// The tuning curves as CSV, and as a PNG drawn by /usr/bin/python3 with matplotlib (one panel
// per searched parameter: criterion against the parameter, log axis, per sweep; the ground-truth
// RMSE on a second axis when it was scored).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "panoptes/tune/search.h"

namespace panoptes::tune {

// Columns: index, sweep, varied, one per parameter, cost, then `extra_names`.
void write_curve_csv(const std::filesystem::path& csv, const SearchResult& result,
                     const std::vector<std::string>& parameters, const std::vector<std::string>& extra_names);

// Runs the embedded matplotlib script on `csv`; throws std::runtime_error with its log on failure.
// `right_axis_column`: a column of the CSV drawn on the second axis ("": none).
void write_curve_png(const std::filesystem::path& csv, const std::filesystem::path& png,
                     const std::string& title, const std::string& cost_label,
                     const std::string& right_axis_column);

}  // namespace panoptes::tune
