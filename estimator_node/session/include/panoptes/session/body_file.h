// SPDX-License-Identifier: Apache-2.0
// The bodies file (docs/bodies.md): loaded at start (an error is fatal) and, live, reloaded when
// it changes (an error keeps the previous definitions). Warns about bodies that identification
// cannot tell apart.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "panoptes/estimator/tracker.h"

namespace panoptes::session {

class BodyFile {
 public:
  explicit BodyFile(std::string path) : path_(std::move(path)) {}
  bool enabled() const { return !path_.empty(); }

  // Throws ConfigError naming the file and body.
  void load(estimator::Tracker& tracker);

  // Reloads if the file changed since the last load; a bad file is reported once and ignored.
  void reload_if_changed(estimator::Tracker& tracker);

  // Counts the successful loads: it changes whenever the tracker's body definitions do.
  std::uint64_t generation() const { return generation_; }
  const std::string& path() const { return path_; }

 private:
  std::optional<std::filesystem::file_time_type> modified() const;

  std::string path_;
  std::optional<std::filesystem::file_time_type> stamp_;
  std::uint64_t generation_ = 0;
};

}  // namespace panoptes::session
