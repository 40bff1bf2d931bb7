// SPDX-License-Identifier: Apache-2.0
// File-name patterns, one way for every program: POSIX glob(3), so `*`, `?`, bracket expressions
// (`left[0-9]*.jpg`, `cam[!2].pgm`) and backslash escapes work everywhere. cv::glob, used before,
// understands only `*` and `?`.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace panoptes {

// The paths that match `pattern`, directories left out, sorted by their bytes (locale-independent
// name order: pad frame numbers with zeros so that "9" does not sort after "10"). A pattern without
// wildcards matches the path itself if it exists. Empty when nothing matches: whether that is an
// error, and how to word it, is the caller's choice. Unreadable directories are skipped. Throws
// std::runtime_error naming the pattern only if glob(3) itself fails (out of memory).
std::vector<std::filesystem::path> glob_files(const std::string& pattern);

}  // namespace panoptes
