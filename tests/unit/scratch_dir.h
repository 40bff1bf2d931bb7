// SPDX-License-Identifier: Apache-2.0
// A scratch directory for a whole test process, removed when the process ends (the tests that keep
// files across a process's TESTs; common/temp_dir.h is the per-TEST one).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <system_error>

#include <unistd.h>

namespace panoptes::testing {

// `<temp>/<prefix>_<pid>`, created on first use.
inline std::filesystem::path process_scratch_dir(const std::string& prefix) {
  struct Owned {
    std::map<std::string, std::filesystem::path> dirs{};
    Owned() = default;
    Owned(const Owned&) = delete;
    Owned& operator=(const Owned&) = delete;
    ~Owned() {
      std::error_code ignored;
      for (const auto& entry : dirs) std::filesystem::remove_all(entry.second, ignored);
    }
  };
  static Owned owned;
  auto [it, created] = owned.dirs.try_emplace(prefix);
  if (created) {
    it->second = std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()));
    std::filesystem::create_directories(it->second);
  }
  return it->second;
}

}  // namespace panoptes::testing
