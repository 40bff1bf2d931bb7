// SPDX-License-Identifier: Apache-2.0
// Analytic trajectories and orientation laws of scene markers and bodies (docs/simulator.md).
#pragma once

#include <initializer_list>
#include <string_view>
#include <variant>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "panoptes/config.h"

namespace panoptes::sim {

struct StaticPath {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};
struct LinearPath {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
};
struct CirclePath {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;
  double frequency_hz = 0.0;
  double phase_rad = 0.0;
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();  // in-plane basis; u x v = axis
  Eigen::Vector3d v = Eigen::Vector3d::UnitY();
};
struct LissajousPath {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d amplitude = Eigen::Vector3d::Zero();
  Eigen::Vector3d frequency_hz = Eigen::Vector3d::Zero();
  Eigen::Vector3d phase_rad = Eigen::Vector3d::Zero();
};
struct WaypointPath {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> times_s;  // strictly increasing, same length as points
  bool loop = false;
};
using Path = std::variant<StaticPath, LinearPath, CirclePath, LissajousPath, WaypointPath>;

struct FixedRotation {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};
struct SpinRotation {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit
  double rate_rad_s = 0.0;
  // A head looking about while it turns: the angle swings by swing_rad sin(2π f t + phase) on top.
  double swing_rad = 0.0;
  double swing_frequency_hz = 0.0;
  double swing_phase_rad = 0.0;
  Eigen::Quaterniond initial = Eigen::Quaterniond::Identity();
};
struct OscillateRotation {
  Eigen::Vector3d amplitude_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d frequency_hz = Eigen::Vector3d::Zero();
  Eigen::Vector3d phase_rad = Eigen::Vector3d::Zero();
  Eigen::Quaterniond initial = Eigen::Quaterniond::Identity();
};
// Orientations held at given instants (e.g. a wand laid down at several places): spherical linear
// interpolation between them; the first before times[0], the last after the end.
struct WaypointRotation {
  std::vector<Eigen::Quaterniond> orientations;
  std::vector<double> times_s;  // strictly increasing, same length as orientations
};
using Rotation = std::variant<FixedRotation, SpinRotation, OscillateRotation, WaypointRotation>;

Eigen::Vector3d evaluate(const Path& path, double t_s);
Eigen::Quaterniond evaluate(const Rotation& rotation, double t_s);

Path read_path(const YamlReader& reader);
Rotation read_rotation(const YamlReader& reader);

// Typos in optional keys would otherwise be silently ignored and the default used.
void reject_unknown_keys(const YamlReader& reader, std::initializer_list<std::string_view> allowed);
Eigen::Vector3d read_vector3(const YamlReader& reader, const std::string& key);
Eigen::Vector3d read_vector3(const YamlReader& reader, const std::string& key,
                             const Eigen::Vector3d& fallback);
// [x, y, z, w], normalised; rejects a near-zero norm.
Eigen::Quaterniond read_quaternion(const YamlReader& reader, const std::string& key);

}  // namespace panoptes::sim
