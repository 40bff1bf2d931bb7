// SPDX-License-Identifier: Apache-2.0
#include "motion.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <yaml-cpp/yaml.h>

namespace panoptes::sim {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

struct PathEvaluator {
  double t;
  Eigen::Vector3d operator()(const StaticPath& path) const { return path.position; }
  Eigen::Vector3d operator()(const LinearPath& path) const { return path.start + t * path.velocity; }
  Eigen::Vector3d operator()(const CirclePath& path) const {
    const double angle = kTwoPi * path.frequency_hz * t + path.phase_rad;
    return path.center + path.radius * (std::cos(angle) * path.u + std::sin(angle) * path.v);
  }
  Eigen::Vector3d operator()(const LissajousPath& path) const {
    Eigen::Vector3d p = path.center;
    for (int axis = 0; axis < 3; ++axis) {
      p[axis] += path.amplitude[axis] * std::sin(kTwoPi * path.frequency_hz[axis] * t + path.phase_rad[axis]);
    }
    return p;
  }
  Eigen::Vector3d operator()(const WaypointPath& path) const {
    const auto& times = path.times_s;
    double local = t;
    if (path.loop && times.size() > 1) {
      const double period = times.back() - times.front();
      local = times.front() + std::fmod(std::fmod(t - times.front(), period) + period, period);
    }
    if (local <= times.front()) return path.points.front();
    if (local >= times.back()) return path.points.back();
    const auto upper = std::upper_bound(times.begin(), times.end(), local);
    const std::size_t i = static_cast<std::size_t>(upper - times.begin()) - 1;
    const double s = (local - times[i]) / (times[i + 1] - times[i]);
    return (1.0 - s) * path.points[i] + s * path.points[i + 1];
  }
};

struct RotationEvaluator {
  double t;
  Eigen::Quaterniond operator()(const FixedRotation& rotation) const { return rotation.q; }
  Eigen::Quaterniond operator()(const SpinRotation& rotation) const {
    const double angle =
        rotation.rate_rad_s * t +
        rotation.swing_rad * std::sin(kTwoPi * rotation.swing_frequency_hz * t + rotation.swing_phase_rad);
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation.axis)) * rotation.initial;
  }
  Eigen::Quaterniond operator()(const OscillateRotation& rotation) const {
    Eigen::Vector3d rotation_vector;
    for (int axis = 0; axis < 3; ++axis) {
      rotation_vector[axis] = rotation.amplitude_rad[axis] *
                              std::sin(kTwoPi * rotation.frequency_hz[axis] * t + rotation.phase_rad[axis]);
    }
    const double angle = rotation_vector.norm();
    if (angle < 1e-15) return rotation.initial;
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation_vector / angle)) * rotation.initial;
  }
  Eigen::Quaterniond operator()(const WaypointRotation& rotation) const {
    const auto& times = rotation.times_s;
    if (t <= times.front()) return rotation.orientations.front();
    if (t >= times.back()) return rotation.orientations.back();
    const auto upper = std::upper_bound(times.begin(), times.end(), t);
    const std::size_t i = static_cast<std::size_t>(upper - times.begin()) - 1;
    const double s = (t - times[i]) / (times[i + 1] - times[i]);
    return rotation.orientations[i].slerp(s, rotation.orientations[i + 1]);
  }
};

Eigen::Vector3d unit_vector(const YamlReader& reader, const std::string& key,
                            const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d v = read_vector3(reader, key, fallback);
  if (v.norm() < 1e-9) reader.fail(key, "must not be the zero vector");
  return v.normalized();
}

}  // namespace

Eigen::Vector3d evaluate(const Path& path, double t_s) {
  return std::visit(PathEvaluator{t_s}, path);
}

Eigen::Quaterniond evaluate(const Rotation& rotation, double t_s) {
  return std::visit(RotationEvaluator{t_s}, rotation).normalized();
}

void reject_unknown_keys(const YamlReader& reader, std::initializer_list<std::string_view> allowed) {
  const YAML::Node& node = reader.node();
  if (!node.IsMap()) reader.fail("", "expected a map");
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string expected;
    for (std::string_view name : allowed) expected += (expected.empty() ? "" : ", ") + std::string(name);
    reader.fail(key, "unknown key (expected one of: " + expected + ")");
  }
}

Eigen::Vector3d read_vector3(const YamlReader& reader, const std::string& key) {
  const std::vector<double> values = reader.get_doubles(key, 3);
  for (double value : values) {
    if (!std::isfinite(value)) reader.fail(key, "expected finite numbers");
  }
  return {values[0], values[1], values[2]};
}

Eigen::Vector3d read_vector3(const YamlReader& reader, const std::string& key,
                             const Eigen::Vector3d& fallback) {
  return reader.has(key) ? read_vector3(reader, key) : fallback;
}

Eigen::Quaterniond read_quaternion(const YamlReader& reader, const std::string& key) {
  const std::vector<double> q = reader.get_doubles(key, 4);
  const Eigen::Quaterniond quaternion(q[3], q[0], q[1], q[2]);  // files are [x, y, z, w]
  if (!std::isfinite(quaternion.norm()) || quaternion.norm() < 1e-6) {
    reader.fail(key, "expected a quaternion [x, y, z, w] of non-zero norm");
  }
  return quaternion.normalized();
}

Path read_path(const YamlReader& reader) {
  const std::string type = reader.get_string("type");
  if (type == "static") {
    reject_unknown_keys(reader, {"type", "position"});
    return StaticPath{read_vector3(reader, "position")};
  }
  if (type == "linear") {
    reject_unknown_keys(reader, {"type", "start", "velocity"});
    return LinearPath{read_vector3(reader, "start"), read_vector3(reader, "velocity")};
  }
  if (type == "circle") {
    reject_unknown_keys(reader, {"type", "center", "radius", "frequency", "axis", "phase"});
    CirclePath path;
    path.center = read_vector3(reader, "center");
    path.radius = reader.get_double("radius");
    if (!(path.radius >= 0.0)) reader.fail("radius", "must be >= 0");
    path.frequency_hz = reader.get_double("frequency");
    path.phase_rad = reader.get_double("phase", 0.0);
    const Eigen::Vector3d axis = unit_vector(reader, "axis", Eigen::Vector3d::UnitZ());
    // Start from world x (or y when the axis is close to x) so that, about +z, phase 0 is +x and
    // the motion is counter-clockwise seen from above.
    const Eigen::Vector3d reference =
        std::abs(axis.x()) > 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    path.u = (reference - reference.dot(axis) * axis).normalized();
    path.v = axis.cross(path.u);
    return path;
  }
  if (type == "lissajous") {
    reject_unknown_keys(reader, {"type", "center", "amplitude", "frequency", "phase"});
    LissajousPath path;
    path.center = read_vector3(reader, "center");
    path.amplitude = read_vector3(reader, "amplitude");
    path.frequency_hz = read_vector3(reader, "frequency");
    path.phase_rad = read_vector3(reader, "phase", Eigen::Vector3d::Zero());
    return path;
  }
  if (type == "waypoints") {
    reject_unknown_keys(reader, {"type", "points", "times", "loop"});
    WaypointPath path;
    const auto rows = reader.get_double_rows("points", 3);
    if (rows.empty()) reader.fail("points", "expected at least one point");
    for (const auto& row : rows) path.points.emplace_back(row[0], row[1], row[2]);
    path.times_s = reader.get_doubles("times", static_cast<int>(rows.size()));
    for (std::size_t i = 1; i < path.times_s.size(); ++i) {
      if (!(path.times_s[i] > path.times_s[i - 1])) reader.fail("times", "must be strictly increasing");
    }
    path.loop = reader.get_bool("loop", false);
    return path;
  }
  reader.fail("type",
              "unknown path type '" + type + "' (expected static, linear, circle, lissajous or waypoints)");
}

Rotation read_rotation(const YamlReader& reader) {
  const std::string type = reader.get_string("type");
  if (type == "fixed") {
    reject_unknown_keys(reader, {"type", "q"});
    return FixedRotation{read_quaternion(reader, "q")};
  }
  const Eigen::Quaterniond initial =
      reader.has("initial") ? read_quaternion(reader, "initial") : Eigen::Quaterniond::Identity();
  if (type == "spin") {
    reject_unknown_keys(reader,
                        {"type", "axis", "rate", "initial", "swing", "swing_frequency", "swing_phase"});
    SpinRotation rotation;
    rotation.axis = unit_vector(reader, "axis", Eigen::Vector3d::UnitZ());
    rotation.rate_rad_s = reader.get_double("rate");
    rotation.swing_rad = reader.get_double("swing", 0.0);
    rotation.swing_frequency_hz = reader.get_double("swing_frequency", 0.0);
    rotation.swing_phase_rad = reader.get_double("swing_phase", 0.0);
    rotation.initial = initial;
    return rotation;
  }
  if (type == "oscillate") {
    reject_unknown_keys(reader, {"type", "amplitude", "frequency", "phase", "initial"});
    OscillateRotation rotation;
    rotation.amplitude_rad = read_vector3(reader, "amplitude");
    rotation.frequency_hz = read_vector3(reader, "frequency");
    rotation.phase_rad = read_vector3(reader, "phase", Eigen::Vector3d::Zero());
    rotation.initial = initial;
    return rotation;
  }
  if (type == "waypoints") {
    reject_unknown_keys(reader, {"type", "q", "times"});
    WaypointRotation rotation;
    const auto rows = reader.get_double_rows("q", 4);
    if (rows.empty()) reader.fail("q", "expected at least one quaternion");
    for (const auto& row : rows) {
      const Eigen::Quaterniond q(row[3], row[0], row[1], row[2]);  // files are [x, y, z, w]
      if (!std::isfinite(q.norm()) || q.norm() < 1e-6)
        reader.fail("q", "expected quaternions [x, y, z, w] of non-zero norm");
      rotation.orientations.push_back(q.normalized());
    }
    rotation.times_s = reader.get_doubles("times", static_cast<int>(rows.size()));
    for (std::size_t i = 1; i < rotation.times_s.size(); ++i) {
      if (!(rotation.times_s[i] > rotation.times_s[i - 1]))
        reader.fail("times", "must be strictly increasing");
    }
    return rotation;
  }
  reader.fail("type", "unknown rotation type '" + type + "' (expected fixed, spin, oscillate or waypoints)");
}

}  // namespace panoptes::sim
