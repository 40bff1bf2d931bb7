// SPDX-License-Identifier: Apache-2.0
#include "panoptes/glob.h"

#include <glob.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace panoptes {
namespace {

// Owns a glob_t so that globfree runs on every path out.
class GlobMatches {
 public:
  GlobMatches() = default;
  ~GlobMatches() { ::globfree(&matches_); }
  GlobMatches(const GlobMatches&) = delete;
  GlobMatches& operator=(const GlobMatches&) = delete;
  glob_t* get() { return &matches_; }

 private:
  glob_t matches_{};
};

}  // namespace

std::vector<std::filesystem::path> glob_files(const std::string& pattern) {
  GlobMatches matches;
  // GLOB_MARK appends '/' to directories, so they are told apart without a stat per match.
  const int status = ::glob(pattern.c_str(), GLOB_MARK, nullptr, matches.get());
  if (status == GLOB_NOMATCH) return {};
  // Without GLOB_ERR an unreadable directory is skipped, so only running out of memory lands here.
  if (status != 0)
    throw std::runtime_error("'" + pattern + "': glob(3) failed with code " + std::to_string(status));
  std::vector<std::filesystem::path> paths;
  paths.reserve(matches.get()->gl_pathc);
  for (std::size_t i = 0; i < matches.get()->gl_pathc; ++i) {
    const std::string match = matches.get()->gl_pathv[i];
    if (!match.empty() && match.back() != '/') paths.emplace_back(match);
  }
  // glob(3) sorts with strcoll, which depends on the locale; frame order must not.
  std::sort(paths.begin(), paths.end(), [](const std::filesystem::path& a, const std::filesystem::path& b) {
    return a.native() < b.native();
  });
  return paths;
}

}  // namespace panoptes
