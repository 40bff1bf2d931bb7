// SPDX-License-Identifier: Apache-2.0
// Tests that read ../shared/data beside the checkout (tests/data/README.md): a missing file fails
// the test under CI and skips it elsewhere.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace panoptes::test {

// <source dir>/../shared/data/<relative>.
inline std::filesystem::path shared_data(const std::string& relative) {
  return std::filesystem::path(PANOPTES_SOURCE_DIR) / ".." / "shared" / "data" / relative;
}

}  // namespace panoptes::test

#define PANOPTES_REQUIRE_SHARED(path)                           \
  do {                                                          \
    if (!std::filesystem::exists(path)) {                       \
      if (std::getenv("CI")) FAIL() << (path) << " is missing"; \
      GTEST_SKIP() << (path) << " is missing (../shared/data)"; \
    }                                                           \
  } while (0)
