// SPDX-License-Identifier: Apache-2.0
// Landmarks files (inside-out tracking, docs/inside_out.md): constellations and single fixed
// markers, a save/load round trip, and bad files refused naming the file and the entry.
#include <string>

#include <gtest/gtest.h>

#include "panoptes/landmarks_file.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

std::string error_of(const std::filesystem::path& path) {
  try {
    load_landmarks(path);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

TEST(Landmarks, ReadsConstellationsAndFixedMarkersAndRoundTrips) {
  const testing::TempDir dir;
  const auto path = dir.write("room.yaml",
                              "cameras: []  # other sections (a scene's) are ignored\n"
                              "landmarks:\n"
                              "  - name: ceiling\n"
                              "    markers: [[0, 0, 3], [1, 0, 3], [0, 1.25, 3.01]]\n"
                              "  - name: door\n"
                              "    position: [3, 0.5, 2.1]\n");
  const auto landmarks = load_landmarks(path);
  ASSERT_EQ(landmarks.size(), 2u);
  EXPECT_EQ(landmarks[0].name, "ceiling");
  EXPECT_TRUE(landmarks[0].constellation);
  ASSERT_EQ(landmarks[0].points.size(), 3u);
  EXPECT_DOUBLE_EQ(landmarks[0].points[2].y(), 1.25);
  EXPECT_FALSE(landmarks[1].constellation);
  ASSERT_EQ(landmarks[1].points.size(), 1u);
  EXPECT_DOUBLE_EQ(landmarks[1].points[0].z(), 2.1);

  save_landmarks(landmarks, dir.file("saved.yaml"));
  const auto again = load_landmarks(dir.file("saved.yaml"));
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again[1].name, "door");
  EXPECT_FALSE(again[1].constellation);
  for (std::size_t g = 0; g < 2; ++g)
    for (std::size_t i = 0; i < landmarks[g].points.size(); ++i)
      EXPECT_EQ(again[g].points[i], landmarks[g].points[i]);
}

TEST(Landmarks, BadFilesNameTheFileAndTheEntry) {
  const testing::TempDir dir;
  const auto duplicate = dir.write("dup.yaml",
                                   "landmarks:\n"
                                   "  - {name: a, markers: [[0, 0, 3], [1, 0, 3], [0, 1, 3]]}\n"
                                   "  - {name: a, position: [2, 2, 3]}\n");
  const std::string dup_error = error_of(duplicate);
  EXPECT_NE(dup_error.find("dup.yaml"), std::string::npos) << dup_error;
  EXPECT_NE(dup_error.find("landmarks[1]"), std::string::npos) << dup_error;
  EXPECT_NE(dup_error.find("duplicate landmark id 'a'"), std::string::npos) << dup_error;

  const auto pair = dir.write("pair.yaml", "landmarks:\n  - {name: rail, markers: [[0, 0, 3], [1, 0, 3]]}\n");
  EXPECT_NE(error_of(pair).find("constellation 'rail' needs at least 3 markers"), std::string::npos)
      << error_of(pair);
  const auto both = dir.write("both.yaml", "landmarks:\n  - {name: x, position: [0, 0, 3], markers: []}\n");
  EXPECT_NE(error_of(both).find("give either markers"), std::string::npos) << error_of(both);
  const auto nan = dir.write("nan.yaml", "landmarks:\n  - {name: n, position: [0, .nan, 3]}\n");
  EXPECT_NE(error_of(nan).find("landmarks[0].position"), std::string::npos) << error_of(nan);
  const auto none = dir.write("none.yaml", "bodies: []\n");
  EXPECT_NE(error_of(none).find("landmarks"), std::string::npos) << error_of(none);
  const std::string missing = error_of(dir.file("absent.yaml"));
  EXPECT_NE(missing.find("absent.yaml"), std::string::npos) << missing;
}

}  // namespace
}  // namespace panoptes
