// SPDX-License-Identifier: Apache-2.0
#include "chain_motion.h"

#include "panoptes/calibration_file.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace panoptes::sim {

namespace {

// 0 → 1 over [0, 1] with zero rate at both ends.
double raised_cosine(double u) {
  return 0.5 - 0.5 * std::cos(std::numbers::pi * std::clamp(u, 0.0, 1.0));
}

std::vector<double> blend(const std::vector<double>& from, const std::vector<double>& to, double s) {
  std::vector<double> out(from.size());
  for (std::size_t j = 0; j < from.size(); ++j) out[j] = from[j] + s * (to[j] - from[j]);
  return out;
}

std::vector<double> positive_list(const YamlReader& reader, const std::string& key,
                                  std::vector<double> fallback) {
  if (!reader.has(key)) return fallback;
  auto values = reader.get_doubles(key);
  if (values.empty()) reader.fail(key, "expected at least one duration");
  for (const double value : values) {
    if (!(value > 0.0) || !std::isfinite(value)) reader.fail(key, "durations must be > 0 s");
  }
  return values;
}

BendScript read_bend(const YamlReader& reader, int joint_count) {
  reject_unknown_keys(reader, {"open", "closed", "start", "transition", "hold_closed", "hold_open"});
  BendScript bend;
  bend.open_rad = reader.get_doubles("open", joint_count);
  bend.closed_rad = reader.get_doubles("closed", joint_count);
  bend.start_s = reader.get_double("start", bend.start_s);
  bend.transition_s = reader.get_double("transition", bend.transition_s);
  if (!(bend.transition_s > 0.0) || !std::isfinite(bend.transition_s))
    reader.fail("transition", "must be > 0 s");
  if (!(bend.start_s >= 0.0) || !std::isfinite(bend.start_s)) reader.fail("start", "must be >= 0 s");
  bend.hold_closed_s = positive_list(reader, "hold_closed", bend.hold_closed_s);
  bend.hold_open_s = positive_list(reader, "hold_open", bend.hold_open_s);
  return bend;
}

}  // namespace

std::vector<double> BendScript::angles_at(double t_s) const {
  double t = t_s - start_s;
  if (t <= 0.0) return open_rad;
  // Cycle n: close (transition), hold closed, open (transition), hold open; the hold lists cycle.
  for (std::size_t n = 0;; ++n) {
    const double closed_hold = hold_closed_s[n % hold_closed_s.size()];
    const double open_hold = hold_open_s[n % hold_open_s.size()];
    if (t < transition_s) return blend(open_rad, closed_rad, raised_cosine(t / transition_s));
    t -= transition_s;
    if (t < closed_hold) return closed_rad;
    t -= closed_hold;
    if (t < transition_s) return blend(closed_rad, open_rad, raised_cosine(t / transition_s));
    t -= transition_s;
    if (t < open_hold) return open_rad;
    t -= open_hold;
  }
}

ChainSpec read_chain_spec(const YamlReader& reader, double default_marker_radius) {
  reject_unknown_keys(
      reader, {"name", "links", "joint_limits", "tip_offset", "marker_radius", "path", "rotation", "bend"});
  ChainSpec spec;
  spec.definition = read_chain_fields(reader);  // no `base` here: the scene's chains start at their base
  const ChainDefinition& chain = spec.definition;
  spec.marker_radius = reader.get_double("marker_radius", default_marker_radius);
  if (!(spec.marker_radius > 0.0)) reader.fail("marker_radius", "must be > 0 m");
  spec.path = read_path(reader.child("path"));
  if (reader.has("rotation")) spec.rotation = read_rotation(reader.child("rotation"));
  spec.bend = read_bend(reader.child("bend"), chain.joint_count());
  return spec;
}

ChainSample sample_chain(const ChainSpec& chain, double t_s) {
  ChainSample sample;
  sample.T_world_base = RigidTransform{evaluate(chain.rotation, t_s), evaluate(chain.path, t_s)};
  sample.angles = chain.bend.angles_at(t_s);
  const ChainDefinition& definition = chain.definition;
  // chain_definition.h's model: m_k = m_{k-1} + L_{k-1} Rz(θ_0 + … + θ_{k-2}) x̂.
  Eigen::Vector3d local = Eigen::Vector3d::Zero();
  double heading = 0.0;
  sample.markers.push_back(sample.T_world_base.q * local + sample.T_world_base.t);
  for (int k = 1; k < definition.marker_count(); ++k) {
    if (k >= 2) heading += sample.angles[static_cast<std::size_t>(k - 2)];
    local += definition.link_lengths_m[static_cast<std::size_t>(k - 1)] *
             Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
    sample.markers.push_back(sample.T_world_base.q * local + sample.T_world_base.t);
  }
  const Eigen::Vector3d tip_local =
      local + Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) * definition.tip_offset_m;
  sample.tip = sample.T_world_base.q * tip_local + sample.T_world_base.t;
  return sample;
}

}  // namespace panoptes::sim
