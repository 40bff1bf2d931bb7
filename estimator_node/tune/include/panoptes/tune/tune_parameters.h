// SPDX-License-Identifier: Apache-2.0
// The settings the tuner may search, named by their YAML key paths under `tracker:`
// (docs/estimator.md, "Configuration"): process noise (seed 003 A.48), measurement noise
// (A.30) and the gates. All are positive and searched in log space within fixed limits.
#pragma once

#include <string>
#include <vector>

#include "panoptes/session/estimator_config.h"

namespace panoptes::tune {

struct ParameterInfo {
  std::string name;  // "process_noise", "measurement_noise_px", "gate_chi2", "init.epipolar_px", ...
  double lower = 0;  // the search never leaves [lower, upper]
  double upper = 0;
  std::string meaning;
};

// Every tunable setting, in a fixed order.
const std::vector<ParameterInfo>& tunable_parameters();
// Throws ConfigError("--params", name, ...) listing the known names for an unknown one.
const ParameterInfo& parameter_info(const std::string& name);

double parameter_value(const session::EstimatorConfig& config, const std::string& name);
void set_parameter_value(session::EstimatorConfig& config, const std::string& name, double value);

}  // namespace panoptes::tune
