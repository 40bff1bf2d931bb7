// SPDX-License-Identifier: Apache-2.0
// BodyFile: loaded at start; reloaded when it changes; a broken version keeps the previous bodies.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/config.h"
#include "panoptes/session/body_file.h"

namespace panoptes::session {
namespace {

const char* kOneBody =
    "bodies:\n  - name: \"wand\"\n    markers:\n      - [0, 0, 0]\n      - [0.2, 0, 0]\n"
    "      - [0.05, 0.15, 0]\n";
const char* kTwoBodies =
    "bodies:\n  - name: \"wand\"\n    markers:\n      - [0, 0, 0]\n      - [0.2, 0, 0]\n      - [0.05, 0.15, "
    "0]\n"
    "  - name: \"tool\"\n    markers:\n      - [0, 0, 0]\n      - [0.1, 0, 0]\n      - [0, 0.3, 0.05]\n"
    "      - [0.12, 0.2, 0.1]\n";

// Writes `text` and moves the modification time on, so a change is seen whatever the clock's grain.
void write(const std::filesystem::path& path, const std::string& text, int generation) {
  std::ofstream(path) << text;
  std::filesystem::last_write_time(
      path, std::filesystem::file_time_type::clock::now() + std::chrono::seconds(generation));
}

TEST(BodyFile, ReloadsAChangedFileAndKeepsThePreviousBodiesOnABadOne) {
  const auto path = std::filesystem::temp_directory_path() / "panoptes_session_bodies.yaml";
  write(path, kOneBody, 0);
  estimator::Tracker tracker;
  BodyFile file(path.string());
  ASSERT_TRUE(file.enabled());
  file.load(tracker);
  EXPECT_EQ(tracker.body_count(), 1u);

  EXPECT_EQ(file.generation(), 1u);

  file.reload_if_changed(tracker);  // unchanged
  EXPECT_EQ(tracker.body_count(), 1u);
  EXPECT_EQ(file.generation(), 1u) << "an unchanged file is not a new generation";
  write(path, kTwoBodies, 10);
  file.reload_if_changed(tracker);
  EXPECT_EQ(tracker.body_count(), 2u);
  EXPECT_EQ(file.generation(), 2u);
  write(path, "bodies:\n  - name: \"broken\"\n    markers:\n      - [0, 0, 0]\n", 20);
  file.reload_if_changed(tracker);
  EXPECT_EQ(tracker.body_count(), 2u) << "a bad version keeps the previous definitions";
  EXPECT_EQ(file.generation(), 2u) << "the descriptions follow the definitions in use";
  std::filesystem::remove(path);
}

TEST(BodyFile, ABadFileAtStartIsAnErrorNamingTheFile) {
  const auto path = std::filesystem::temp_directory_path() / "panoptes_session_bad_bodies.yaml";
  write(path, "bodies:\n  - name: \"broken\"\n    markers:\n      - [0, 0, 0]\n", 0);
  estimator::Tracker tracker;
  BodyFile file(path.string());
  try {
    file.load(tracker);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("panoptes_session_bad_bodies.yaml"), std::string::npos)
        << error.what();
  }
  std::filesystem::remove(path);
  EXPECT_FALSE(BodyFile("").enabled());
}

}  // namespace
}  // namespace panoptes::session
