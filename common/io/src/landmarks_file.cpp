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

void save_landmarks(const std::vector<LandmarkGroup>& landmarks, const std::filesystem::path& path) {
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
  out << YAML::EndSeq << YAML::EndMap;
  std::ofstream file(path, std::ios::out | std::ios::trunc);
  if (!file) throw ConfigError(path.string(), "", "cannot open file for writing");
  file << out.c_str() << "\n";
  if (!file) throw ConfigError(path.string(), "", "write failed");
}

}  // namespace panoptes
