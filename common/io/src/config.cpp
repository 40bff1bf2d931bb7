// SPDX-License-Identifier: Apache-2.0
#include "panoptes/config.h"

#include <algorithm>
#include <fstream>
#include <limits>
#include <string_view>
#include <utility>

#include <yaml-cpp/yaml.h>

namespace panoptes {

namespace {

std::string list_description(int expected_size) {
  if (expected_size < 0) return "expected a list of numbers";
  return "expected a list of " + std::to_string(expected_size) +
         (expected_size == 1 ? " number" : " numbers");
}

std::string indexed(const std::string& key_path, std::size_t index) {
  return key_path + "[" + std::to_string(index) + "]";
}

double scalar_as_double(const YamlReader& reader, const YAML::Node& node, const std::string& key_path) {
  if (!node.IsScalar()) throw ConfigError(reader.file(), key_path, "expected a number");
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    throw ConfigError(reader.file(), key_path, "expected a number, got '" + node.Scalar() + "'");
  }
}

std::vector<double> sequence_as_doubles(const YamlReader& reader, const YAML::Node& node,
                                        const std::string& key_path, int expected_size) {
  if (!node.IsSequence()) throw ConfigError(reader.file(), key_path, list_description(expected_size));
  if (expected_size >= 0 && node.size() != static_cast<std::size_t>(expected_size)) {
    throw ConfigError(reader.file(), key_path,
                      list_description(expected_size) + ", got " + std::to_string(node.size()));
  }
  std::vector<double> values;
  values.reserve(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) {
    values.push_back(scalar_as_double(reader, node[i], indexed(key_path, i)));
  }
  return values;
}

}  // namespace

YAML::Node load_yaml_file(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored))
    throw ConfigError(file, "", "cannot open file: is a directory");
  std::ifstream in(path);
  if (!in) throw ConfigError(file, "", "cannot open file");
  try {
    return YAML::Load(in);
  } catch (const YAML::ParserException& error) {
    // yaml-cpp counts lines and columns from 0; editors count from 1.
    throw ConfigError(file, "",
                      "YAML syntax error at line " + std::to_string(error.mark.line + 1) + ", column " +
                          std::to_string(error.mark.column + 1) + ": " + error.msg);
  } catch (const YAML::Exception& error) {
    throw ConfigError(file, "", std::string("cannot parse YAML: ") + error.what());
  }
}

struct YamlReader::NodeHolder {
  YAML::Node node;
};

YamlReader::YamlReader(std::string file, const YAML::Node& node, std::string key_path)
    : file_(std::move(file)), key_path_(std::move(key_path)), node_(new NodeHolder{node}) {}

YamlReader::~YamlReader() {
  delete node_;
}

YamlReader::YamlReader(const YamlReader& other)
    : file_(other.file_), key_path_(other.key_path_), node_(new NodeHolder{other.node_->node}) {}

const YAML::Node& YamlReader::node() const {
  return node_->node;
}

std::string YamlReader::key_of(const std::string& key) const {
  if (key.empty()) return key_path_;
  if (key_path_.empty()) return key;
  return key_path_ + "." + key;
}

void YamlReader::expect_only(const std::vector<std::string>& allowed) const {
  const YAML::Node& self = node();
  if (!self.IsMap()) return;
  for (const auto& entry : self) {
    const std::string key = entry.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string known;
    for (const std::string& name : allowed) known += (known.empty() ? "" : ", ") + name;
    fail(key, "unknown key (expected one of: " + known + ")");
  }
}

void YamlReader::fail(const std::string& key, const std::string& reason) const {
  throw ConfigError(file_, key_of(key), reason);
}

bool YamlReader::has(const std::string& key) const {
  const YAML::Node& self = node();
  if (!self.IsMap()) return false;
  const YAML::Node value = self[key];
  // "key:" with nothing after it is YAML null; treating it as absent lets optional keys be blanked.
  return value.IsDefined() && !value.IsNull();
}

namespace {

YAML::Node required_value(const YamlReader& reader, const std::string& key) {
  const YAML::Node& self = reader.node();
  if (!self.IsMap() && !self.IsNull()) reader.fail("", "expected a map");
  if (!self.IsMap()) reader.fail(key, "missing key");
  const YAML::Node value = self[key];
  if (!value.IsDefined()) reader.fail(key, "missing key");
  return value;
}

}  // namespace

YamlReader YamlReader::child(const std::string& key) const {
  return YamlReader(file_, required_value(*this, key), key_of(key));
}

std::vector<YamlReader> YamlReader::sequence(const std::string& key) const {
  const YAML::Node value = required_value(*this, key);
  if (!value.IsSequence()) fail(key, "expected a list");
  std::vector<YamlReader> items;
  items.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    items.emplace_back(file_, value[i], indexed(key_of(key), i));
  }
  return items;
}

std::vector<YamlReader> YamlReader::sequence_or_empty(const std::string& key) const {
  if (!has(key)) return {};
  return sequence(key);
}

double YamlReader::get_double(const std::string& key) const {
  return scalar_as_double(*this, required_value(*this, key), key_of(key));
}

double YamlReader::get_double(const std::string& key, double fallback) const {
  return has(key) ? get_double(key) : fallback;
}

long long YamlReader::get_int(const std::string& key) const {
  const YAML::Node value = required_value(*this, key);
  if (!value.IsScalar()) fail(key, "expected an integer");
  try {
    return value.as<long long>();
  } catch (const YAML::Exception&) {
    fail(key, "expected an integer, got '" + value.Scalar() + "'");
  }
}

long long YamlReader::get_int(const std::string& key, long long fallback) const {
  return has(key) ? get_int(key) : fallback;
}

bool YamlReader::get_bool(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node value = node()[key];
  if (!value.IsScalar()) fail(key, "expected true or false");
  try {
    return value.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "expected true or false, got '" + value.Scalar() + "'");
  }
}

std::string YamlReader::get_string(const std::string& key) const {
  const YAML::Node value = required_value(*this, key);
  if (!value.IsScalar()) fail(key, "expected a string");
  return value.Scalar();
}

std::string YamlReader::get_string(const std::string& key, const std::string& fallback) const {
  return has(key) ? get_string(key) : fallback;
}

std::vector<double> YamlReader::get_doubles(const std::string& key, int expected_size) const {
  return sequence_as_doubles(*this, required_value(*this, key), key_of(key), expected_size);
}

std::vector<std::vector<double>> YamlReader::get_double_rows(const std::string& key, int inner_size) const {
  const YAML::Node value = required_value(*this, key);
  if (!value.IsSequence())
    fail(key, "expected a list of lists of " + std::to_string(inner_size) + " numbers");
  std::vector<std::vector<double>> rows;
  rows.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    rows.push_back(sequence_as_doubles(*this, value[i], indexed(key_of(key), i), inner_size));
  }
  return rows;
}

}  // namespace panoptes
