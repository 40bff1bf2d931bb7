// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling_files/marker_set_file.h"

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"

namespace panoptes::labelling {

namespace {

std::string name_of(const YamlReader& item) {
  if (!item.node().IsScalar() || item.node().Scalar().empty()) item.fail("", "expected a name");
  return item.node().Scalar();
}

std::vector<std::string> names_of(const YamlReader& reader, const std::string& key) {
  std::vector<std::string> names;
  for (const auto& item : reader.sequence(key)) names.push_back(name_of(item));
  return names;
}

// `- R.ASIS` or `- {name: R.Knee.Med, calibration_only: true, optional: false}`.
MarkerDefinition read_marker(const YamlReader& item) {
  if (!item.node().IsMap()) return {name_of(item)};
  item.expect_only({"name", "calibration_only", "optional"});
  return {item.get_string("name"), item.get_bool("calibration_only", false),
          item.get_bool("optional", false)};
}

SegmentDefinition read_segment(const YamlReader& item) {
  item.expect_only({"name", "parent", "markers"});
  return {item.get_string("name"), item.get_string("parent", ""), names_of(item, "markers")};
}

JointDefinition read_joint(const YamlReader& item) {
  item.expect_only({"name", "child", "midpoint", "point"});
  JointDefinition joint{item.get_string("name"), item.get_string("child"), {}};
  if (item.has("midpoint") == item.has("point"))
    item.fail("", "expected one of `midpoint: [a, b]` or `point: name`");
  if (item.has("point")) {
    joint.points = {item.get_string("point")};
  } else {
    joint.points = names_of(item, "midpoint");
    if (joint.points.size() != 2) item.fail("midpoint", "expected two point names");
  }
  return joint;
}

std::array<std::string, 2> read_stick(const YamlReader& item) {
  if (!item.node().IsSequence() || item.node().size() != 2)
    item.fail("", "expected a pair of markers [a, b]");
  return {name_of(YamlReader(item.file(), item.node()[0], item.key_path() + "[0]")),
          name_of(YamlReader(item.file(), item.node()[1], item.key_path() + "[1]"))};
}

}  // namespace

MarkerSet load_marker_set(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path.string(), root);
  if (!root.IsMap()) reader.fail("", "expected a map with name, markers, segments");
  reader.expect_only({"name", "markers", "segments", "sticks", "joints"});
  MarkerSet set;
  set.name = reader.get_string("name");
  for (const auto& item : reader.sequence("markers")) set.markers.push_back(read_marker(item));
  for (const auto& item : reader.sequence("segments")) set.segments.push_back(read_segment(item));
  for (const auto& item : reader.sequence_or_empty("sticks")) set.sticks.push_back(read_stick(item));
  for (const auto& item : reader.sequence_or_empty("joints")) set.joints.push_back(read_joint(item));
  if (const auto problem = find_marker_set_problem(set))
    throw ConfigError(path.string(), problem->entry, problem->reason);
  return set;
}

}  // namespace panoptes::labelling
