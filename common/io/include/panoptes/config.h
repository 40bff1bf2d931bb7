// SPDX-License-Identifier: Apache-2.0
// YAML configuration helpers whose errors name the file and the key.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "panoptes/errors.h"

namespace YAML {
class Node;
}

namespace panoptes {

// Loads a YAML file; throws ConfigError naming the file on a missing file or a syntax error.
YAML::Node load_yaml_file(const std::filesystem::path& path);

// Typed access to a YAML map. `key_path` is the dotted path used in error messages
// (e.g. "cameras[2].K").
class YamlReader {
 public:
  YamlReader(std::string file, const YAML::Node& node, std::string key_path = "");
  ~YamlReader();
  YamlReader(const YamlReader&);
  YamlReader& operator=(const YamlReader&) = delete;

  bool has(const std::string& key) const;
  YamlReader child(const std::string& key) const;                  // throws if missing
  std::vector<YamlReader> sequence(const std::string& key) const;  // throws if missing or not a list
  std::vector<YamlReader> sequence_or_empty(const std::string& key) const;

  double get_double(const std::string& key) const;
  double get_double(const std::string& key, double fallback) const;
  long long get_int(const std::string& key) const;
  long long get_int(const std::string& key, long long fallback) const;
  bool get_bool(const std::string& key, bool fallback) const;
  std::string get_string(const std::string& key) const;
  std::string get_string(const std::string& key, const std::string& fallback) const;
  // A list of numbers; `expected_size` < 0 accepts any length.
  std::vector<double> get_doubles(const std::string& key, int expected_size = -1) const;
  // A list of lists of numbers, each of `inner_size`.
  std::vector<std::vector<double>> get_double_rows(const std::string& key, int inner_size) const;

  // Fails on the first key of this map that is not in `allowed` (typos must not pass silently).
  void expect_only(const std::vector<std::string>& allowed) const;

  const std::string& file() const { return file_; }
  const std::string& key_path() const { return key_path_; }
  std::string key_of(const std::string& key) const;  // full dotted path of a child key
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;
  const YAML::Node& node() const;

 private:
  std::string file_;
  std::string key_path_;
  struct NodeHolder;
  NodeHolder* node_;
};

}  // namespace panoptes
