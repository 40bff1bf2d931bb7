// SPDX-License-Identifier: Apache-2.0
// Paths and scratch files for the labelling tests (docs/marker_sets.md).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "../scratch_dir.h"
#include "../shared_data.h"
#include "panoptes/errors.h"

namespace panoptes::test {

inline std::filesystem::path marker_set_path(const std::string& name) {
  return std::filesystem::path(PANOPTES_SOURCE_DIR) / "deploy" / "markersets" / (name + ".yaml");
}

inline std::filesystem::path gait2392_static() {
  return shared_data("static/gait2392_subject01_static.trc");
}
inline std::filesystem::path gait2392_walk() {
  return shared_data("static/gait2392_subject01_walk1.trc");
}
inline std::filesystem::path rajagopal_static() {
  return shared_data("static/rajagopal_static_walk_1.trc");
}
// The Rajagopal walk is copied into tests/data (Apache-2.0, tests/data/README.md).
inline std::filesystem::path rajagopal_walk() {
  return std::filesystem::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc";
}

// A file in a per-test scratch directory (ctest runs tests in parallel).
inline std::filesystem::path scratch_file(const std::string& name, const std::string& text = "") {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto dir = panoptes::testing::process_scratch_dir("panoptes_labelling_" + std::string(info->name()));
  auto path = dir / name;
  if (!text.empty()) std::ofstream(path) << text;
  return path;
}

// The what() of the error `action` throws, of type Error; a test failure when it throws none.
template <class Error, class Action>
std::string error_of(Action&& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "expected an error";
  return {};
}

}  // namespace panoptes::test
