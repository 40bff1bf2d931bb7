// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling_files/subject_model_file.h"

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"

namespace panoptes::labelling {

namespace {

constexpr int kFormatVersion = 1;

// Metres to the micrometre: finer than any marker, and a file a person can read.
std::string metres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6f", value);
  return text;
}

const char* kind_name(MarkerFlag::Kind kind) {
  switch (kind) {
    case MarkerFlag::Kind::kAbsent:
      return "absent";
    case MarkerFlag::Kind::kMissingFrames:
      return "missing_frames";
    case MarkerFlag::Kind::kMoved:
      return "moved";
    case MarkerFlag::Kind::kRepeated:
      return "repeated";
  }
  return "moved";
}

void emit_vector(YAML::Emitter& out, const char* key, const Eigen::Vector3d& v) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << metres(v.x()) << metres(v.y())
      << metres(v.z()) << YAML::EndSeq;
}

void emit_marker(YAML::Emitter& out, const ModelMarker& marker) {
  out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << marker.name;
  if (marker.calibration_only) out << YAML::Key << "calibration_only" << YAML::Value << true;
  emit_vector(out, "position_m", marker.position_m);
  out << YAML::Key << "missing_frames" << YAML::Value << marker.missing_frames;
  out << YAML::Key << "spread_m" << YAML::Value << metres(marker.spread_m) << YAML::EndMap;
}

void emit_distance(YAML::Emitter& out, const DistanceStatistics& d) {
  out << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "markers" << YAML::Value << YAML::Flow << YAML::BeginSeq << d.markers[0] << d.markers[1]
      << YAML::EndSeq;
  out << YAML::Key << "mean_m" << YAML::Value << metres(d.mean_m) << YAML::Key << "sd_m" << YAML::Value
      << metres(d.sd_m) << YAML::Key << "min_m" << YAML::Value << metres(d.min_m) << YAML::Key << "max_m"
      << YAML::Value << metres(d.max_m) << YAML::Key << "tolerance_m" << YAML::Value << metres(d.tolerance_m)
      << YAML::Key << "frames" << YAML::Value << d.frames << YAML::EndMap;
}

void emit_segment(YAML::Emitter& out, const SegmentLayout& segment) {
  out << YAML::BeginMap << YAML::Key << "name" << YAML::Value << segment.name;
  if (!segment.parent.empty()) out << YAML::Key << "parent" << YAML::Value << segment.parent;
  out << YAML::Key << "has_pose" << YAML::Value << segment.has_pose;
  out << YAML::Key << "static_fit_rms_m" << YAML::Value << metres(segment.static_fit_rms_m);
  emit_vector(out, "origin_m", segment.origin_m);
  out << YAML::Key << "markers" << YAML::Value << YAML::BeginSeq;
  for (const auto& marker : segment.markers) emit_marker(out, marker);
  out << YAML::EndSeq << YAML::Key << "distances" << YAML::Value << YAML::BeginSeq;
  for (const auto& distance : segment.distances) emit_distance(out, distance);
  out << YAML::EndSeq << YAML::EndMap;
}

void emit_header(YAML::Emitter& out, const SubjectModel& model) {
  out << YAML::Key << "subject_model" << YAML::Value << kFormatVersion;
  out << YAML::Key << "subject" << YAML::Value << YAML::DoubleQuoted << model.subject;
  out << YAML::Key << "marker_set" << YAML::Value << YAML::DoubleQuoted << model.marker_set;
  out << YAML::Key << "trial" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "file"
      << YAML::Value << YAML::DoubleQuoted << model.trial_file << YAML::Key << "kind" << YAML::Value
      << (model.options.dynamic ? "labelled" : "static") << YAML::Key << "frames" << YAML::Value
      << model.frames << YAML::Key << "rate_hz" << YAML::Value << model.rate_hz << YAML::EndMap;
  const ModelOptions& o = model.options;
  out << YAML::Key << "options" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "sigmas"
      << YAML::Value << o.sigmas << YAML::Key << "min_tolerance_m" << YAML::Value << metres(o.min_tolerance_m)
      << YAML::Key << "still_m" << YAML::Value << metres(o.still_m) << YAML::EndMap;
}

void emit_lists(YAML::Emitter& out, const SubjectModel& model) {
  out << YAML::Key << "joints" << YAML::Value << YAML::BeginSeq;
  for (const auto& joint : model.joints) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << joint.name << YAML::Key
        << "parent" << YAML::Value << joint.parent << YAML::Key << "child" << YAML::Value << joint.child;
    emit_vector(out, "in_parent_m", joint.in_parent_m);
    emit_vector(out, "in_child_m", joint.in_child_m);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::Key << "sticks" << YAML::Value << YAML::BeginSeq;
  for (const auto& stick : model.sticks)
    out << YAML::Flow << YAML::BeginSeq << stick[0] << stick[1] << YAML::EndSeq;
  out << YAML::EndSeq << YAML::Key << "flags" << YAML::Value << YAML::BeginSeq;
  for (const auto& flag : model.flags)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "kind" << YAML::Value << kind_name(flag.kind)
        << YAML::Key << "marker" << YAML::Value << flag.marker << YAML::Key << "reason" << YAML::Value
        << flag.reason << YAML::EndMap;
  out << YAML::EndSeq << YAML::Key << "ignored_points" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& name : model.ignored_points) out << name;
  out << YAML::EndSeq;
}

Eigen::Vector3d read_vector(const YamlReader& item, const std::string& key) {
  const auto v = item.get_doubles(key, 3);
  return {v[0], v[1], v[2]};
}

// `[a, b]`: two names.
std::array<std::string, 2> pair_of(const YamlReader& list) {
  const YAML::Node& node = list.node();
  if (!node.IsSequence() || node.size() != 2 || !node[0].IsScalar() || !node[1].IsScalar())
    list.fail("", "expected two names [a, b]");
  return {node[0].Scalar(), node[1].Scalar()};
}

MarkerFlag::Kind kind_of(const YamlReader& flag) {
  const std::string kind = flag.get_string("kind");
  for (auto candidate : {MarkerFlag::Kind::kAbsent, MarkerFlag::Kind::kMissingFrames,
                         MarkerFlag::Kind::kMoved, MarkerFlag::Kind::kRepeated}) {
    if (kind == kind_name(candidate)) return candidate;
  }
  flag.fail("kind", "expected absent, missing_frames, moved or repeated, got '" + kind + "'");
}

SegmentLayout read_segment(const YamlReader& item) {
  item.expect_only({"name", "parent", "has_pose", "static_fit_rms_m", "origin_m", "markers", "distances"});
  SegmentLayout segment;
  segment.name = item.get_string("name");
  segment.parent = item.get_string("parent", "");
  segment.has_pose = item.get_bool("has_pose", false);
  segment.static_fit_rms_m = item.get_double("static_fit_rms_m", 0.0);
  if (item.has("origin_m")) segment.origin_m = read_vector(item, "origin_m");
  for (const auto& m : item.sequence("markers")) {
    m.expect_only({"name", "calibration_only", "position_m", "missing_frames", "spread_m"});
    segment.markers.push_back(
        {m.get_string("name"), m.get_bool("calibration_only", false), read_vector(m, "position_m"),
         static_cast<std::size_t>(m.get_int("missing_frames", 0)), m.get_double("spread_m", 0.0)});
  }
  for (const auto& d : item.sequence_or_empty("distances")) {
    d.expect_only({"markers", "mean_m", "sd_m", "min_m", "max_m", "tolerance_m", "frames"});
    segment.distances.push_back({pair_of(d.child("markers")), d.get_double("mean_m"), d.get_double("sd_m"),
                                 d.get_double("min_m"), d.get_double("max_m"), d.get_double("tolerance_m"),
                                 static_cast<std::size_t>(d.get_int("frames", 0))});
  }
  return segment;
}

void read_lists(const YamlReader& reader, SubjectModel& model) {
  for (const auto& j : reader.sequence_or_empty("joints")) {
    j.expect_only({"name", "parent", "child", "in_parent_m", "in_child_m"});
    model.joints.push_back({j.get_string("name"), j.get_string("parent"), j.get_string("child"),
                            read_vector(j, "in_parent_m"), read_vector(j, "in_child_m")});
  }
  for (const auto& stick : reader.sequence_or_empty("sticks")) model.sticks.push_back(pair_of(stick));
  for (const auto& f : reader.sequence_or_empty("flags")) {
    f.expect_only({"kind", "marker", "reason"});
    model.flags.push_back({kind_of(f), f.get_string("marker"), f.get_string("reason")});
  }
  for (const auto& name : reader.sequence_or_empty("ignored_points")) {
    if (!name.node().IsScalar()) name.fail("", "expected a name");
    model.ignored_points.push_back(name.node().Scalar());
  }
}

}  // namespace

std::string subject_model_to_yaml(const SubjectModel& model) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  emit_header(out, model);
  out << YAML::Key << "segments" << YAML::Value << YAML::BeginSeq;
  for (const auto& segment : model.segments) emit_segment(out, segment);
  out << YAML::EndSeq;
  emit_lists(out, model);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void save_subject_model(const SubjectModel& model, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::out | std::ios::trunc);
  if (!out) throw ConfigError(path.string(), "", "cannot open file for writing");
  out << subject_model_to_yaml(model);
  out.flush();
  if (!out) throw ConfigError(path.string(), "", "write failed");
}

SubjectModel load_subject_model(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path.string(), root);
  if (!root.IsMap()) reader.fail("", "expected a subject model (a map)");
  reader.expect_only({"subject_model", "subject", "marker_set", "trial", "options", "segments", "joints",
                      "sticks", "flags", "ignored_points"});
  if (reader.get_int("subject_model") != kFormatVersion)
    reader.fail("subject_model", "expected format version " + std::to_string(kFormatVersion));
  SubjectModel model;
  model.subject = reader.get_string("subject");
  model.marker_set = reader.get_string("marker_set");
  if (reader.has("trial")) {
    const YamlReader trial = reader.child("trial");
    trial.expect_only({"file", "kind", "frames", "rate_hz"});
    model.trial_file = trial.get_string("file", "");
    const std::string kind = trial.get_string("kind", "static");
    if (kind != "static" && kind != "labelled")
      trial.fail("kind", "expected static or labelled, got '" + kind + "'");
    model.options.dynamic = kind == "labelled";
    model.frames = static_cast<std::size_t>(trial.get_int("frames", 0));
    model.rate_hz = trial.get_double("rate_hz", 0.0);
  }
  if (reader.has("options")) {
    const YamlReader options = reader.child("options");
    model.options.sigmas = options.get_double("sigmas", model.options.sigmas);
    model.options.min_tolerance_m = options.get_double("min_tolerance_m", model.options.min_tolerance_m);
    model.options.still_m = options.get_double("still_m", model.options.still_m);
  }
  for (const auto& item : reader.sequence("segments")) model.segments.push_back(read_segment(item));
  read_lists(reader, model);
  if (const auto problem = find_subject_model_problem(model))
    throw ConfigError(path.string(), problem->entry, problem->reason);
  return model;
}

}  // namespace panoptes::labelling
