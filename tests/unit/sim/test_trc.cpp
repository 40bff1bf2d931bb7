// SPDX-License-Identifier: Apache-2.0
// TRC motion-capture files: parsing, unit and axis conversion, interpolation, gaps and looping;
// C3D files played back the same way.
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

// A copy of ../shared/data/walk_41markers_100hz.trc (Apache-2.0; tests/data/README.md).
const fs::path kWalk = fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc";

const std::string kCamera = R"(
cameras:
  - id: cam0
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    look_at: {eye: [0, -6, 1], target: [0, 0, 1]}
)";

// Three markers, four frames at 50 Hz, in centimetres; B is missing in frame 3, and C's x is
// blank in frame 2.
const std::string kGappyTrc =
    "PathFileType\t4\t(X/Y/Z)\tgappy.trc\n"
    "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n"
    "50.0\t50.0\t4\t3\tcm\t50.0\t1\t4\n"
    "Frame#\tTime\tA\t\t\tB\t\t\tC\t\t\n"
    "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\tX3\tY3\tZ3\n"
    "\n"
    "1\t0.00\t0\t100\t0\t10\t20\t30\t1\t2\t3\r\n"
    "2\t0.02\t10\t100\t0\t11\t21\t31\t\t2\t3\r\n"
    "3\t0.04\t20\t100\t0\t\t\t\t1\t2\t3\r\n"
    "4\t0.06\t30\t100\t0\t13\t23\t33\t1\t2\t3\r\n";

class TempDir {
 public:
  TempDir() {
    path_ =
        fs::temp_directory_path() /
        ("panoptes_trc_test_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
    return path_ / name;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

TEST(Trc, LoadsTheWalkFileInMetres) {
  const TrcData data = load_trc(kWalk);
  EXPECT_EQ(data.marker_count(), 41u);
  EXPECT_EQ(data.frame_count(), 238u);
  EXPECT_EQ(data.data_rate_hz, 100.0);
  EXPECT_EQ(data.units, "mm");
  EXPECT_EQ(data.marker_names.front(), "R.Shoulder");
  EXPECT_EQ(data.marker_names.back(), "L.Toe");
  EXPECT_DOUBLE_EQ(data.times_s[1], 0.01);
  EXPECT_DOUBLE_EQ(data.times_s.back(), 2.37);
  // Row "1  0.00000  -652.630  1529.542  -94.520 ...".
  EXPECT_TRUE(data.position(0, 0).isApprox(Eigen::Vector3d(-0.652630, 1.529542, -0.094520), 1e-12));
  EXPECT_TRUE(data.is_valid(0, 0));
  for (std::uint8_t valid : data.valid) EXPECT_EQ(valid, 1);  // this recording has no gaps
}

TEST(Trc, SceneConvertsYUpToZUpAndInterpolates) {
  const TempDir dir;
  const fs::path scene_path =
      dir.write("scene.yaml", kCamera + "trc:\n  file: " + fs::absolute(kWalk).string() +
                                  "\n  offset: [1, 2, 3]\n  markers: [L.Toe, R.Shoulder]\n");
  const Scene scene = Scene::load(scene_path);
  EXPECT_EQ(scene.marker_names(), (std::vector<std::string>{"trc/L.Toe", "trc/R.Shoulder"}));
  EXPECT_DOUBLE_EQ(scene.marker_radius(1), 0.007);
  // File (x, y, z) in mm, y up -> world (x, -z, y) in m, plus the offset.
  const Eigen::Vector3d frame0(-0.652630 + 1, 0.094520 + 2, 1.529542 + 3);
  const Eigen::Vector3d frame1(-0.641082 + 1, 0.094682 + 2, 1.531254 + 3);
  const auto at0 = scene.markers_at(0);
  ASSERT_TRUE(at0[1].valid);
  EXPECT_EQ(at0[1].name, "trc/R.Shoulder");
  EXPECT_LT((at0[1].p - frame0).norm(), 1e-12);
  EXPECT_LT((scene.markers_at(10 * kNsPerMillisecond)[1].p - frame1).norm(), 1e-12);
  const auto between = scene.markers_at(7'500'000);
  EXPECT_LT((between[1].p - (0.25 * frame0 + 0.75 * frame1)).norm(), 1e-12);
}

TEST(Trc, RelativePathsResolveAgainstTheSceneFile) {
  const TempDir dir;
  dir.write("gappy.trc", kGappyTrc);
  fs::create_directories(dir.path() / "scenes");
  const fs::path scene_path =
      dir.write("scenes/scene.yaml", kCamera + "trc: {file: ../gappy.trc, up_axis: z}\n");
  const Scene scene = Scene::load(scene_path);
  ASSERT_EQ(scene.marker_names().size(), 3u);
  // Centimetres, z up: no axis change.
  EXPECT_LT((scene.markers_at(0)[1].p - Eigen::Vector3d(0.10, 0.20, 0.30)).norm(), 1e-12);
}

// Issue 32: x-up files exist (some C3D exports); up_axis x turns file (x, y, z) into world
// (y, z, x), a rotation, so the file's up axis becomes our z. Anything else names the key.
TEST(Trc, UpAxisXTurnsTheFilesXIntoWorldZ) {
  const TempDir dir;
  dir.write("gappy.trc", kGappyTrc);
  const Scene scene = Scene::load(dir.write("x_up.yaml", kCamera + "trc: {file: gappy.trc, up_axis: x}\n"));
  // B is at (10, 20, 30) cm in the file.
  EXPECT_LT((scene.markers_at(0)[1].p - Eigen::Vector3d(0.20, 0.30, 0.10)).norm(), 1e-12);
  try {
    Scene::load(dir.write("w_up.yaml", kCamera + "trc: {file: gappy.trc, up_axis: w}\n"));
    ADD_FAILURE() << "up_axis: w was accepted";
  } catch (const std::exception& error) {
    EXPECT_NE(std::string(error.what()).find("up_axis"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("expected x, y or z, got 'w'"), std::string::npos)
        << error.what();
  }
}

// Issue 33 (two subjects): `trc:` as a list plays several recordings at once, each with its own
// prefix, offset and start; a prefix shared by two entries names the duplicate marker.
TEST(Trc, AListOfRecordingsIsSeveralPeople) {
  const TempDir dir;
  const std::string walk = fs::absolute(kWalk).string();
  const Scene scene = Scene::load(
      dir.write("two.yaml", kCamera + "trc:\n  - {file: " + walk +
                                ", prefix: s1/, markers: [L.Toe, R.Shoulder]}\n" + "  - {file: " + walk +
                                ", prefix: s2/, markers: [L.Toe, R.Shoulder], offset: [0, 1.5, 0], " +
                                "start: 0.7}\n"));
  EXPECT_EQ(scene.marker_names(),
            (std::vector<std::string>{"s1/L.Toe", "s1/R.Shoulder", "s2/L.Toe", "s2/R.Shoulder"}));
  // s2 is s1 0.7 s later (pingpong, no turnaround: file time t + start within the recording), 1.5 m
  // along y.
  const auto at_1s = scene.markers_at(1000 * kNsPerMillisecond);
  const auto at_0_3s = scene.markers_at(300 * kNsPerMillisecond);
  for (int m = 0; m < 2; ++m) {
    ASSERT_TRUE(at_1s[m].valid && at_0_3s[2 + m].valid);
    EXPECT_LT((at_0_3s[2 + m].p - (at_1s[m].p + Eigen::Vector3d(0, 1.5, 0))).norm(), 1e-9) << m;
  }
  try {
    Scene::load(dir.write("same.yaml", kCamera + "trc:\n  - {file: " + walk + ", markers: [L.Toe]}\n" +
                                           "  - {file: " + walk + ", markers: [L.Toe]}\n"));
    ADD_FAILURE() << "two recordings with one prefix were accepted";
  } catch (const std::exception& error) {
    EXPECT_NE(std::string(error.what()).find("trc/L.Toe"), std::string::npos) << error.what();
  }
}

TEST(Trc, GapsMakeMarkersInvalidWhereTheyHaveNoData) {
  const TempDir dir;
  const fs::path trc_path = dir.write("gappy.trc", kGappyTrc);
  const TrcData data = load_trc(trc_path);
  ASSERT_EQ(data.frame_count(), 4u);
  EXPECT_EQ(data.units, "cm");
  EXPECT_FALSE(data.is_valid(2, 1));  // B, frame 3
  EXPECT_FALSE(data.is_valid(1, 2));  // C, frame 2: one coordinate blank
  EXPECT_TRUE(data.is_valid(3, 1));
  EXPECT_TRUE(data.position(3, 1).isApprox(Eigen::Vector3d(0.13, 0.23, 0.33)));

  const fs::path scene_path =
      dir.write("scene.yaml", kCamera + "trc: {file: gappy.trc, loop: none, prefix: ''}\n");
  const Scene scene = Scene::load(scene_path);
  EXPECT_EQ(scene.marker_names(), (std::vector<std::string>{"A", "B", "C"}));
  const auto at = [&](double ms) { return scene.markers_at(static_cast<TimeNs>(ms * 1e6)); };
  EXPECT_TRUE(at(10)[1].valid);  // between frames 1 and 2: both present
  EXPECT_NEAR(at(10)[1].p.x(), 0.105, 1e-12);
  EXPECT_FALSE(at(30)[1].valid);  // between frames 2 and 3: B missing in frame 3
  EXPECT_FALSE(at(40)[1].valid);
  EXPECT_FALSE(at(50)[1].valid);
  EXPECT_TRUE(at(60)[1].valid);
  EXPECT_FALSE(at(20)[2].valid);
  EXPECT_TRUE(at(40)[2].valid);
  EXPECT_TRUE(at(50)[0].valid);
  // A is at (0, 100, 0) cm in the file; up_axis defaults to y, so that is 1 m above the floor.
  EXPECT_NEAR(at(0)[0].p.z(), 1.0, 1e-12);
  // loop: none -> nothing outside the recording.
  EXPECT_FALSE(at(61)[0].valid);
  EXPECT_FALSE(at(-1)[0].valid);

  // A missing marker is never rendered or reported.
  const CameraSimulator camera(scene, "cam0");
  EXPECT_EQ(camera.features(0).blobs.size(), 3u);
  EXPECT_FALSE(scene.markers_at(camera.frame_time_ns(2))[2].valid);
  EXPECT_EQ(camera.features(2).blobs.size(), 2u);  // 20 ms at 100 Hz: C has a blank coordinate
}

TEST(Trc, LoopModesPlayPastTheEnd) {
  const TempDir dir;
  dir.write("gappy.trc", kGappyTrc);
  const auto load = [&](const std::string& loop) {
    return Scene::load(
        dir.write("scene_" + loop + ".yaml", kCamera + "trc: {file: gappy.trc, loop: " + loop + "}\n"));
  };
  const auto x_of_a = [](const Scene& scene, double ms) {
    const MarkerTruth a = scene.markers_at(static_cast<TimeNs>(ms * 1e6))[0];
    EXPECT_TRUE(a.valid) << ms << " ms";
    return a.p.x();
  };
  // A moves +0.1 m per 20 ms frame over 0..60 ms.
  const Scene pingpong = load("pingpong");
  EXPECT_NEAR(x_of_a(pingpong, 70), 0.25, 1e-12);   // on its way back
  EXPECT_NEAR(x_of_a(pingpong, 120), 0.0, 1e-12);   // back at the start
  EXPECT_NEAR(x_of_a(pingpong, 130), 0.05, 1e-12);  // and forwards again
  EXPECT_NEAR(x_of_a(load("true"), 70), 0.25, 1e-12);
  const Scene wrap = load("wrap");
  EXPECT_NEAR(x_of_a(wrap, 70), 0.3, 1e-12);  // holds the last frame for one frame interval
  EXPECT_NEAR(x_of_a(wrap, 80), 0.0, 1e-12);  // then starts over
  EXPECT_NEAR(x_of_a(wrap, 90), 0.05, 1e-12);
}

TEST(Trc, PingPongTurnaroundKeepsVelocityContinuous) {
  const TempDir dir;
  dir.write("gappy.trc", kGappyTrc);
  // A moves at +5 m/s along x over the 60 ms recording; sample its velocity every 0.1 ms.
  const auto largest_velocity_jump = [&](const std::string& keys, double* min_x, double* max_x) {
    const Scene scene =
        Scene::load(dir.write("scene.yaml", kCamera + "trc: {file: gappy.trc, up_axis: z" + keys + "}\n"));
    constexpr TimeNs kStep = 100'000;
    double previous_x = scene.markers_at(0)[0].p.x();
    double previous_v = 5.0;
    double jump = 0.0;
    *min_x = *max_x = previous_x;
    for (TimeNs t = kStep; t < 300 * kNsPerMillisecond; t += kStep) {
      const MarkerTruth a = scene.markers_at(t)[0];
      EXPECT_TRUE(a.valid);
      const double v = (a.p.x() - previous_x) / ns_to_seconds(kStep);
      jump = std::max(jump, std::abs(v - previous_v));
      *min_x = std::min(*min_x, a.p.x());
      *max_x = std::max(*max_x, a.p.x());
      previous_x = a.p.x();
      previous_v = v;
    }
    return jump;
  };
  double min_x = 0.0, max_x = 0.0;
  EXPECT_GT(largest_velocity_jump(", start: 0.03", &min_x, &max_x), 9.0);  // instant reversal: -5 -> +5 m/s
  // b = 20 ms: the playback decelerates at 2 / b = 100 s/s^2, A at 500 m/s^2, 0.05 m/s per step.
  EXPECT_LT(largest_velocity_jump(", start: 0.03, turnaround: 0.02", &min_x, &max_x), 0.06);
  EXPECT_NEAR(min_x, 0.0, 1e-4);  // still reaches both ends of the recording
  EXPECT_NEAR(max_x, 0.3, 1e-4);
  const Scene scene = Scene::load(dir.write(
      "start.yaml", kCamera + "trc: {file: gappy.trc, up_axis: z, start: 0.03, turnaround: 0.02}\n"));
  EXPECT_NEAR(scene.markers_at(0)[0].p.x(), 0.15, 1e-12);  // scene time 0 shows `start`, at full speed
  EXPECT_NEAR(scene.markers_at(1'000'000)[0].p.x(), 0.155, 1e-12);
  const Scene from_rest =
      Scene::load(dir.write("rest.yaml", kCamera + "trc: {file: gappy.trc, up_axis: z, turnaround: 0.02}\n"));
  EXPECT_NEAR(from_rest.markers_at(0)[0].p.x(), 0.0, 1e-12);
  EXPECT_NEAR(from_rest.markers_at(1'000'000)[0].p.x(), 5.0 * 0.001 * 0.001 / 0.02,
              1e-12);  // 5 tau, tau = t^2/b

  try {
    Scene::load(dir.write("late.yaml", kCamera + "trc: {file: gappy.trc, start: 0.5}\n"));
    ADD_FAILURE();
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.key(), "trc.start");
  }
  try {
    Scene::load(dir.write("wrap.yaml", kCamera + "trc: {file: gappy.trc, loop: wrap, turnaround: 0.01}\n"));
    ADD_FAILURE();
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.key(), "trc.turnaround");
  }
}

TEST(Trc, MalformedFilesNameTheFileAndLine) {
  const TempDir dir;
  std::string bad = kGappyTrc;
  bad.replace(bad.find("13\t23"), 2, "1x");
  const fs::path path = dir.write("bad.trc", bad);
  try {
    load_trc(path);
    ADD_FAILURE();
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.file(), path.string());
    EXPECT_EQ(error.key(), "line 10");
    EXPECT_NE(std::string(error.what()).find("1x"), std::string::npos);
  }
  std::string inches = kGappyTrc;
  inches.replace(inches.find("\tcm\t"), 4, "\tin\t");
  EXPECT_THROW(load_trc(dir.write("inches.trc", inches)), ConfigError);
  EXPECT_THROW(load_trc(dir.path() / "missing.trc"), ConfigError);

  const fs::path scene_path = dir.write("scene.yaml", kCamera + "trc: {file: bad.trc}\n");
  EXPECT_THROW(Scene::load(scene_path), ConfigError);
  try {
    Scene::load(dir.write("subset.yaml", kCamera + "trc: {file: " + fs::absolute(kWalk).string() +
                                             ", markers: [R.Shoulder, Nose]}\n"));
    ADD_FAILURE();
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.key(), "trc.markers[1]");
  }
}

// The walk played from a C3D file (docs/simulator.md, "TRC and C3D playback").
const std::string kC3dScene = kCamera + R"(trc:
  offset: [0.5, 0, 0]
  loop: wrap
  file: )";

TEST(C3dPlayback, WalkFromC3dMovesLikeWalkFromTrc) {
  const TempDir temp;
  const fs::path& dir = temp.path();
  MarkerTrajectories walk = load_trc(kWalk);
  // A gap, to see that C3D's invalid points stay invalid in the scene.
  walk.valid[10 * walk.marker_count() + 3] = 0;
  write_c3d(dir / "walk.c3d", walk);
  write_trc(dir / "walk.trc", walk);
  const Scene from_c3d = Scene::from_yaml_string(kC3dScene + (dir / "walk.c3d").string(), dir, "c3d.yaml");
  const Scene from_trc = Scene::from_yaml_string(kC3dScene + (dir / "walk.trc").string(), dir, "trc.yaml");
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
}

TEST(C3dPlayback, ABadC3dFileIsAConfigErrorNamingIt) {
  const TempDir temp;
  const fs::path& dir = temp.path();
  temp.write("bad.c3d", "not a c3d file");
  try {
    Scene::from_yaml_string(kC3dScene + (dir / "bad.c3d").string(), dir, "bad.yaml");
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("bad.c3d: offset 0"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace panoptes
