// SPDX-License-Identifier: Apache-2.0
// The simulator plays C3D marker files exactly as it plays TRC (docs/simulator.md, "Marker files").
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/config.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/simulator.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;

const fs::path kWalk = fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc";

const std::string kScene = R"(
cameras:
  - id: cam0
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    look_at: {eye: [0, -6, 1], target: [0, 0, 1]}
trc:
  offset: [0.5, 0, 0]
  loop: wrap
  file: )";

TEST(C3dPlayback, WalkFromC3dMovesLikeWalkFromTrc) {
  const fs::path dir = fs::temp_directory_path() / "panoptes_c3d_playback";
  fs::create_directories(dir);
  MarkerTrajectories walk = load_trc(kWalk);
  // A gap, to see that C3D's invalid points stay invalid in the scene.
  walk.valid[10 * walk.marker_count() + 3] = 0;
  write_c3d(dir / "walk.c3d", walk);
  write_trc(dir / "walk.trc", walk);
  const Scene from_c3d = Scene::from_yaml_string(kScene + (dir / "walk.c3d").string(), dir, "c3d.yaml");
  const Scene from_trc = Scene::from_yaml_string(kScene + (dir / "walk.trc").string(), dir, "trc.yaml");
  ASSERT_EQ(from_c3d.marker_names(), from_trc.marker_names());
  ASSERT_EQ(from_c3d.marker_names().size(), 41U);
  double worst = 0.0;
  int compared = 0;
  for (TimeNs t = 0; t < 5 * kNsPerSecond; t += 3'333'333) {  // off the file's grid: interpolated
    const auto a = from_c3d.markers_at(t);
    const auto b = from_trc.markers_at(t);
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].valid, b[i].valid) << i << " at " << t;
      if (!a[i].valid) continue;
      worst = std::max(worst, (a[i].p - b[i].p).norm());
      ++compared;
    }
  }
  EXPECT_GT(compared, 30000);
  EXPECT_LT(worst, 1e-6);
  EXPECT_FALSE(from_c3d.markers_at(100 * kNsPerMillisecond)[3].valid);  // the gap, frame 10
  fs::remove_all(dir);
}

TEST(C3dPlayback, ABadC3dFileIsAConfigErrorNamingIt) {
  const fs::path dir = fs::temp_directory_path() / "panoptes_c3d_playback_bad";
  fs::create_directories(dir);
  { std::ofstream(dir / "bad.c3d") << "not a c3d file"; }
  try {
    Scene::from_yaml_string(kScene + (dir / "bad.c3d").string(), dir, "bad.yaml");
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("bad.c3d: offset 0"), std::string::npos) << error.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace panoptes
