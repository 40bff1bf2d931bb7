// SPDX-License-Identifier: Apache-2.0
#include "panoptes/landmarks_file.h"

#include <cmath>
#include <fstream>
#include <set>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"

namespace panoptes {

namespace {

Eigen::Vector3d finite_point(const YamlReader& entry, const std::string& key,
                             const std::vector<double>& xyz) {
  for (double value : xyz)
    if (!std::isfinite(value)) entry.fail(key, "expected finite numbers");
  return {xyz[0], xyz[1], xyz[2]};
}

LandmarkGroup read_entry(const YamlReader& entry, std::set<std::string>& names) {
  entry.expect_only({"name", "markers", "position"});
  LandmarkGroup group;
  group.name = entry.get_string("name");
  if (group.name.empty()) entry.fail("name", "must not be empty");
  if (!names.insert(group.name).second) entry.fail("name", "duplicate landmark id '" + group.name + "'");
  if (entry.has("markers") == entry.has("position"))
    entry.fail("markers", "landmark '" + group.name + "': give either markers (a constellation) or position");
  if (entry.has("position")) {
    group.constellation = false;
    group.points.push_back(finite_point(entry, "position", entry.get_doubles("position", 3)));
    return group;
  }
  const auto rows = entry.get_double_rows("markers", 3);
  if (rows.size() < 3)
    entry.fail("markers", "constellation '" + group.name + "' needs at least 3 markers, has " +
                              std::to_string(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    group.points.push_back(finite_point(entry, "markers[" + std::to_string(i) + "]", rows[i]));
  return group;
}

}  // namespace

std::vector<LandmarkGroup> read_landmarks(const YamlReader& root) {
  const std::vector<YamlReader> entries = root.sequence("landmarks");
  if (entries.empty()) root.fail("landmarks", "expected at least one landmark");
  std::vector<LandmarkGroup> landmarks;
  landmarks.reserve(entries.size());
  std::set<std::string> names;
  for (const YamlReader& entry : entries) landmarks.push_back(read_entry(entry, names));
  return landmarks;
}

std::vector<LandmarkGroup> load_landmarks(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  return read_landmarks(YamlReader(path.string(), root));
}

RigMarkers load_rig_markers(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path.string(), root);
  RigMarkers markers;
  if (!reader.has("rig_markers")) return markers;
  const YamlReader rigs = reader.child("rig_markers");
  if (!rigs.node().IsMap()) reader.fail("rig_markers", "expected a map of rig name to markers");
  for (const auto& entry : rigs.node()) {
    const std::string name = entry.first.as<std::string>();
    auto& points = markers[name];
    const auto rows = rigs.get_double_rows(name, 3);
    for (std::size_t i = 0; i < rows.size(); ++i)
      points.push_back(finite_point(rigs, name + "[" + std::to_string(i) + "]", rows[i]));
    if (points.empty()) rigs.fail(name, "expected at least one marker");
  }
  return markers;
}

void save_landmarks(const std::vector<LandmarkGroup>& landmarks, const std::filesystem::path& path,
                    const RigMarkers& rig_markers) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap << YAML::Key << "landmarks" << YAML::Value << YAML::BeginSeq;
  const auto emit_point = [&](const Eigen::Vector3d& p) {
    out << YAML::Flow << YAML::BeginSeq << p.x() << p.y() << p.z() << YAML::EndSeq;
  };
  for (const LandmarkGroup& group : landmarks) {
    out << YAML::BeginMap << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << group.name;
    if (group.constellation) {
      out << YAML::Key << "markers" << YAML::Value << YAML::BeginSeq;
      for (const auto& point : group.points) emit_point(point);
      out << YAML::EndSeq;
    } else {
      out << YAML::Key << "position" << YAML::Value;
      emit_point(group.points.front());
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  if (!rig_markers.empty()) {
    out << YAML::Key << "rig_markers" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, points] : rig_markers) {
      out << YAML::Key << YAML::DoubleQuoted << name << YAML::Value << YAML::BeginSeq;
      for (const auto& point : points) emit_point(point);
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  std::ofstream file(path, std::ios::out | std::ios::trunc);
  if (!file) throw ConfigError(path.string(), "", "cannot open file for writing");
  file << out.c_str() << "\n";
  if (!file) throw ConfigError(path.string(), "", "write failed");
}

}  // namespace panoptes
