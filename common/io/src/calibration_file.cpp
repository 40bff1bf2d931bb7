// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calibration_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"

namespace panoptes {

namespace {

// A quaternion within this of unit norm is kept as written: renormalising it would flip low
// bits and break the exact save/load round trip that calibration tools rely on.
constexpr double kUnitNormTolerance = 1e-12;
constexpr double kMinQuaternionNorm = 1e-6;

void require_finite(const YamlReader& reader, const std::string& key, const std::vector<double>& values) {
  for (double value : values) {
    if (!std::isfinite(value)) reader.fail(key, "expected finite numbers");
  }
}

int positive_int(const YamlReader& reader, const std::string& key) {
  const long long value = reader.get_int(key);
  if (value <= 0 || value > std::numeric_limits<int>::max()) {
    reader.fail(key, "expected a positive integer, got " + std::to_string(value));
  }
  return static_cast<int>(value);
}

RigidTransform read_transform(const YamlReader& reader) {
  const std::vector<double> q = reader.get_doubles("q", 4);
  const std::vector<double> t = reader.get_doubles("t", 3);
  require_finite(reader, "q", q);
  require_finite(reader, "t", t);
  RigidTransform transform;
  // Files store [x, y, z, w] (ROS order); Eigen's constructor takes w first.
  transform.q = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
  const double norm = transform.q.norm();
  if (norm < kMinQuaternionNorm) reader.fail("q", "quaternion has near-zero norm");
  if (std::abs(transform.q.squaredNorm() - 1.0) > kUnitNormTolerance) transform.q.normalize();
  transform.t = Eigen::Vector3d(t[0], t[1], t[2]);
  return transform;
}

CameraCalibration read_camera(const YamlReader& reader) {
  CameraCalibration camera;
  camera.id = reader.get_string("id");
  if (camera.id.empty()) reader.fail("id", "must not be empty");
  camera.intrinsics.width = positive_int(reader, "width");
  camera.intrinsics.height = positive_int(reader, "height");
  const std::vector<double> K = reader.get_doubles("K", 4);
  require_finite(reader, "K", K);
  if (K[0] <= 0.0 || K[1] <= 0.0) reader.fail("K", "fx and fy must be positive");
  camera.intrinsics.fx = K[0];
  camera.intrinsics.fy = K[1];
  camera.intrinsics.cx = K[2];
  camera.intrinsics.cy = K[3];
  if (reader.has("distortion")) {
    const std::vector<double> distortion = reader.get_doubles("distortion", 5);
    require_finite(reader, "distortion", distortion);
    std::copy(distortion.begin(), distortion.end(), camera.intrinsics.distortion.begin());
  }
  if (reader.has("T_world_cam")) camera.T_world_cam = read_transform(reader.child("T_world_cam"));
  camera.nominal_intrinsics = reader.get_bool("nominal", false);
  camera.moving = reader.get_bool("moving", false);
  camera.rig = reader.get_string("rig", "");
  if (!camera.rig.empty() && !camera.moving)
    reader.fail("rig", "names the rig of a moving camera: add moving: true");
  return camera;
}

// Shortest text that parses back to the same double (std::to_chars guarantees the round trip),
// which keeps files exact without printing 0.10000000000000001.
std::string format_double(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

void emit_numbers(YAML::Emitter& out, std::initializer_list<double> values) {
  out << YAML::Flow << YAML::BeginSeq;
  for (double value : values) out << format_double(value);
  out << YAML::EndSeq;
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::out | std::ios::trunc);
  if (!out) throw ConfigError(path.string(), "", "cannot open file for writing");
  out << text;
  out.flush();
  if (!out) throw ConfigError(path.string(), "", "write failed");
}

}  // namespace

SystemCalibration load_calibration(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path.string(), root);
  const std::vector<YamlReader> items = reader.sequence("cameras");
  if (items.empty()) reader.fail("cameras", "expected at least one camera");
  SystemCalibration calibration;
  calibration.cameras.reserve(items.size());
  std::set<std::string> ids;
  for (const YamlReader& item : items) {
    CameraCalibration camera = read_camera(item);
    if (!ids.insert(camera.id).second) item.fail("id", "duplicate camera id '" + camera.id + "'");
    calibration.cameras.push_back(std::move(camera));
  }
  return calibration;
}

std::string calibration_to_yaml(const SystemCalibration& calibration) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "cameras" << YAML::Value << YAML::BeginSeq;
  for (const auto& camera : calibration.cameras) {
    const CameraIntrinsics& in = camera.intrinsics;
    out << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << YAML::DoubleQuoted << camera.id;
    out << YAML::Key << "width" << YAML::Value << in.width;
    out << YAML::Key << "height" << YAML::Value << in.height;
    out << YAML::Key << "K" << YAML::Value;
    emit_numbers(out, {in.fx, in.fy, in.cx, in.cy});
    out << YAML::Key << "distortion" << YAML::Value;
    const auto& d = in.distortion;
    emit_numbers(out, {d[0], d[1], d[2], d[3], d[4]});
    if (camera.nominal_intrinsics) out << YAML::Key << "nominal" << YAML::Value << true;
    if (camera.moving) out << YAML::Key << "moving" << YAML::Value << true;
    if (!camera.rig.empty()) out << YAML::Key << "rig" << YAML::Value << YAML::DoubleQuoted << camera.rig;
    if (camera.T_world_cam) {
      const RigidTransform& T = *camera.T_world_cam;
      out << YAML::Key << "T_world_cam" << YAML::Value << YAML::BeginMap;
      out << YAML::Key << "q" << YAML::Value;
      emit_numbers(out, {T.q.x(), T.q.y(), T.q.z(), T.q.w()});
      out << YAML::Key << "t" << YAML::Value;
      emit_numbers(out, {T.t.x(), T.t.y(), T.t.z()});
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void save_calibration(const SystemCalibration& calibration, const std::filesystem::path& path) {
  write_text_file(path, calibration_to_yaml(calibration));
}

namespace {

// Bodies and chains share one file and one namespace of names (`type: chain` entries are chains).
struct BodiesFile {
  std::vector<BodyDefinition> bodies;
  std::vector<ChainDefinition> chains;
};

BodiesFile read_bodies_file(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path.string(), root);
  const std::vector<YamlReader> items = reader.sequence("bodies");
  if (items.empty()) reader.fail("bodies", "expected at least one body");
  BodiesFile file;
  file.bodies.reserve(items.size());
  std::set<std::string> names;
  for (const YamlReader& item : items) {
    if (item.get_string("type", "passive") == "chain") {
      file.chains.push_back(read_chain_definition(item, names));
    } else {
      file.bodies.push_back(read_body_definition(item, names));
    }
  }
  return file;
}

}  // namespace

std::vector<BodyDefinition> load_bodies(const std::filesystem::path& path) {
  return read_bodies_file(path).bodies;
}

std::vector<ChainDefinition> load_chains(const std::filesystem::path& path) {
  return read_bodies_file(path).chains;
}

ChainDefinition read_chain_definition(const YamlReader& item, std::set<std::string>& names) {
  item.expect_only({"name", "type", "links", "joint_limits", "base", "tip_offset"});
  ChainDefinition chain = read_chain_fields(item);
  if (!names.insert(chain.name).second) item.fail("name", "duplicate body name '" + chain.name + "'");
  return chain;
}

ChainDefinition read_chain_fields(const YamlReader& item) {
  ChainDefinition chain;
  chain.name = item.get_string("name");
  if (chain.name.empty()) item.fail("name", "must not be empty");
  chain.link_lengths_m = item.get_doubles("links");
  for (const auto& row : item.get_double_rows("joint_limits", 2))
    chain.joint_limits.push_back({row[0], row[1]});
  const std::string base = item.get_string("base", "first");
  if (base == "last") {
    std::reverse(chain.link_lengths_m.begin(), chain.link_lengths_m.end());
    std::reverse(chain.joint_limits.begin(), chain.joint_limits.end());
  } else if (base != "first") {
    item.fail("base", "expected 'first' or 'last', got '" + base + "'");
  }
  if (item.has("tip_offset")) {
    const auto tip = item.get_doubles("tip_offset", 3);
    chain.tip_offset_m = Eigen::Vector3d(tip[0], tip[1], tip[2]);
  }
  if (const auto error = chain_definition_error(chain)) {
    const std::string field = error->substr(0, error->find(':'));
    item.fail(field.substr(0, field.find('[')), "chain '" + chain.name + "': " + *error);
  }
  return chain;
}

BodyDefinition read_body_definition(const YamlReader& item, std::set<std::string>& names) {
  BodyDefinition body;
  body.name = item.get_string("name");
  if (body.name.empty()) item.fail("name", "must not be empty");
  if (!names.insert(body.name).second) item.fail("name", "duplicate body name '" + body.name + "'");
  const auto rows = item.get_double_rows("markers", 3);
  if (rows.empty()) item.fail("markers", "expected at least one marker");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    require_finite(item, "markers[" + std::to_string(i) + "]", rows[i]);
    body.markers.emplace_back(rows[i][0], rows[i][1], rows[i][2]);
  }
  const std::string type = item.get_string("type", "passive");
  if (type == "led7") {
    body.kind = BodyKind::kLed7;
    if (body.markers.size() != 7)
      item.fail("markers", "a led7 body has exactly 7 markers (M0..M6 of seed 004)");
  } else if (type != "passive") {
    item.fail("type", "expected 'passive' or 'led7', got '" + type + "'");
  }
  return body;
}

void save_bodies(const std::vector<BodyDefinition>& bodies, const std::filesystem::path& path) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "bodies" << YAML::Value << YAML::BeginSeq;
  for (const auto& body : bodies) {
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << body.name;
    if (body.kind == BodyKind::kLed7) out << YAML::Key << "type" << YAML::Value << "led7";
    out << YAML::Key << "markers" << YAML::Value << YAML::BeginSeq;
    for (const Eigen::Vector3d& marker : body.markers)
      emit_numbers(out, {marker.x(), marker.y(), marker.z()});
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  write_text_file(path, std::string(out.c_str()) + "\n");
}

}  // namespace panoptes
