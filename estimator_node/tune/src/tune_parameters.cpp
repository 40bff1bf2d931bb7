// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/tune_parameters.h"

#include "panoptes/errors.h"

namespace panoptes::tune {

namespace {

double* field(estimator::TrackerOptions& o, const std::string& name) {
  if (name == "process_noise") return &o.process_noise;
  if (name == "measurement_noise_px") return &o.measurement_noise_px;
  if (name == "gate_chi2") return &o.gate_chi2;
  if (name == "init.epipolar_px") return &o.init.epipolar_px;
  if (name == "init.reprojection_px") return &o.init.reprojection_px;
  if (name == "init.link_radius_px") return &o.init.link_radius_px;
  return nullptr;
}

}  // namespace

const std::vector<ParameterInfo>& tunable_parameters() {
  static const std::vector<ParameterInfo> parameters = {
      {"process_noise", 1e-2, 1e6, "σ² of white acceleration, m²/s³ (seed 003 A.48)"},
      {"measurement_noise_px", 0.01, 50.0, "σ of a centroid, px (seed 003 A.30)"},
      {"gate_chi2", 2.0, 1000.0, "χ²₂ verify region of a track (seed 003 §2.2.3.2)"},
      {"init.epipolar_px", 0.1, 100.0, "initiation: distance to the epipolar line, px"},
      {"init.reprojection_px", 0.1, 100.0, "initiation: reprojection of every supporting view, px"},
      {"init.link_radius_px", 1.0, 500.0,
       "initiation: a blob continues its camera's tracklet within this, px"},
  };
  return parameters;
}

const ParameterInfo& parameter_info(const std::string& name) {
  std::string known;
  for (const auto& parameter : tunable_parameters()) {
    if (parameter.name == name) return parameter;
    known += (known.empty() ? "" : ", ") + parameter.name;
  }
  throw ConfigError("--params", name, "not a tunable setting (known: " + known + ")");
}

double parameter_value(const session::EstimatorConfig& config, const std::string& name) {
  parameter_info(name);
  auto tracker = config.tracker;
  return *field(tracker, name);
}

void set_parameter_value(session::EstimatorConfig& config, const std::string& name, double value) {
  parameter_info(name);
  *field(config.tracker, name) = value;
}

}  // namespace panoptes::tune
