// SPDX-License-Identifier: Apache-2.0
// camera_node's log lines on stderr, "<name>: <message>" (integration tests grep them), and the
// counters of what went wrong with frames and commands.
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace panoptes::camera {

// The name starts as "camera_node" and becomes "camera_node[<camera id>]" once the source is open.
class NodeLog {
 public:
  explicit NodeLog(std::string name = "camera_node") : name_(std::move(name)) {}
  void rename(std::string name) { name_ = std::move(name); }
  const std::string& name() const { return name_; }
  // One line on stderr; safe from any thread (one fprintf per line).
  void operator()(const std::string& message) const;

 private:
  std::string name_;
};

// Counts what went wrong with frames and commands, by reason, and remembers the last error.
// The first few of each kind are logged; after that only every 1000th, so a broken camera cannot
// flood the log.
class NodeCounters {
 public:
  explicit NodeCounters(const NodeLog& log) : log_(log) {}
  void count(const std::string& reason, const std::string& message);
  const std::map<std::string, std::uint64_t>& counts() const { return counts_; }
  const std::string& last_error() const { return last_error_; }
  void set_last_error(std::string message) { last_error_ = std::move(message); }

 private:
  const NodeLog& log_;
  std::map<std::string, std::uint64_t> counts_;
  std::string last_error_;
};

}  // namespace panoptes::camera
