// SPDX-License-Identifier: Apache-2.0
// Scene files: the shipped scenes, every path and rotation law, camera defaults, and errors that
// name the file and key.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/config.h"
#include "panoptes/simulator.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "scenes";

// A camera block that every test scene reuses; tests append their own keys.
const std::string kOneCamera = R"(
cameras:
  - id: cam0
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    look_at: {eye: [0, -4, 1], target: [0, 0, 1]}
)";

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("panoptes_sim_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
    return path_ / name;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Loads `yaml` from a file and returns the ConfigError it must raise.
ConfigError load_error(const std::string& yaml) {
  const TempDir dir;
  const fs::path path = dir.write("scene.yaml", yaml);
  try {
    Scene::load(path);
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.file(), path.string()) << error.what();
    return error;
  }
  ADD_FAILURE() << "no ConfigError for:\n" << yaml;
  return ConfigError("", "", "");
}

TEST(Scene, DemoSceneHasFourAsynchronousCamerasAroundTheVolume) {
  const Scene scene = Scene::load(kScenes / "demo.yaml");
  EXPECT_EQ(scene.seed(), 42u);
  EXPECT_EQ(scene.duration_ns(), 20 * kNsPerSecond);
  ASSERT_EQ(scene.cameras().size(), 4u);
  std::vector<double> rates;
  for (const SimCameraConfig& camera : scene.cameras()) {
    EXPECT_EQ(camera.calibration.intrinsics.width, 640);
    EXPECT_EQ(camera.calibration.intrinsics.height, 480);
    EXPECT_NEAR(camera.calibration.intrinsics.fx, 600.0, 10.0);
    EXPECT_GE(camera.rate_hz, 60.0);
    EXPECT_DOUBLE_EQ(camera.centroid_noise_px, 0.1);  // from `defaults`
    EXPECT_DOUBLE_EQ(camera.pixel_noise_dn, 1.0);
    ASSERT_TRUE(camera.calibration.T_world_cam.has_value());
    // Every camera looks at the volume centre.
    const auto pixel = camera.calibration.model().project(Eigen::Vector3d(0, 0, 1));
    ASSERT_TRUE(pixel.has_value());
    EXPECT_NEAR(pixel->x(), camera.calibration.intrinsics.cx, 5.0);
    EXPECT_NEAR(pixel->y(), camera.calibration.intrinsics.cy, 5.0);
    for (double rate : rates) EXPECT_NE(rate, camera.rate_hz);
    rates.push_back(camera.rate_hz);
  }
  EXPECT_EQ(scene.marker_names(), (std::vector<std::string>{"m0", "m1", "m2"}));
  EXPECT_EQ(scene.calibration().cameras.size(), 4u);
  EXPECT_NE(scene.find_camera("cam2"), nullptr);
  EXPECT_EQ(scene.find_camera("cam9"), nullptr);
}

TEST(Scene, DemoMarkersStayInsideTheVolumeApartAndInEveryCamera) {
  const Scene scene = Scene::load(kScenes / "demo.yaml");
  double closest = 1e9;
  double distance = 0.0;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (TimeNs t = 0; t <= scene.duration_ns(); t += 10 * kNsPerMillisecond) {
    const auto markers = scene.markers_at(t);
    ASSERT_EQ(markers.size(), 3u);
    for (std::size_t i = 0; i < markers.size(); ++i) {
      ASSERT_TRUE(markers[i].valid);
      EXPECT_LE(markers[i].p.head<2>().cwiseAbs().maxCoeff(), 1.0);
      EXPECT_GE(markers[i].p.z(), 0.0);
      EXPECT_LE(markers[i].p.z(), 2.0);
      for (std::size_t j = i + 1; j < markers.size(); ++j)
        closest = std::min(closest, (markers[i].p - markers[j].p).norm());
    }
    if (t > 0) distance += (markers[0].p - previous).norm();
    previous = markers[0].p;
  }
  EXPECT_GE(closest, 0.3);
  const double mean_speed = distance / ns_to_seconds(scene.duration_ns());
  EXPECT_GT(mean_speed, 0.7);
  EXPECT_LT(mean_speed, 1.5);

  for (const SimCameraConfig& config : scene.cameras()) {
    const CameraSimulator camera(scene, config.calibration.id);
    for (std::int64_t k = 0; camera.frame_time_ns(k) < scene.duration_ns(); k += 7) {
      EXPECT_EQ(camera.features(k).blobs.size(), 3u) << config.calibration.id << " frame " << k;
    }
  }
}

TEST(Scene, WalkSceneSeesTheWholePersonFromSixCameras) {
  const Scene scene = Scene::load(kScenes / "walk.yaml");
  ASSERT_EQ(scene.cameras().size(), 6u);
  ASSERT_EQ(scene.marker_names().size(), 41u);
  EXPECT_EQ(scene.marker_names().front(), "trc/R.Shoulder");
  for (const SimCameraConfig& config : scene.cameras()) {
    EXPECT_GE(config.rate_hz, 100.0);
    const CameraSimulator camera(scene, config.calibration.id);
    for (std::int64_t k = 0; camera.frame_time_ns(k) < scene.duration_ns(); k += 37) {
      EXPECT_EQ(camera.features(k).blobs.size(), 41u) << config.calibration.id << " frame " << k;
    }
  }
  // The person walks along x and stands on the floor (z up).
  double min_x = 1e9, max_x = -1e9, min_z = 1e9, max_z = -1e9;
  for (TimeNs t = 0; t < 3 * kNsPerSecond; t += 10 * kNsPerMillisecond) {
    for (const MarkerTruth& marker : scene.markers_at(t)) {
      min_x = std::min(min_x, marker.p.x());
      max_x = std::max(max_x, marker.p.x());
      min_z = std::min(min_z, marker.p.z());
      max_z = std::max(max_z, marker.p.z());
    }
  }
  EXPECT_GT(max_x - min_x, 3.0);
  EXPECT_GT(min_z, -0.01);
  EXPECT_NEAR(max_z, 1.55, 0.05);
}

TEST(Scene, WandSceneDefinesABodyWithDistinctMarkerDistances) {
  const Scene scene = Scene::load(kScenes / "wand.yaml");
  const auto bodies = scene.body_definitions();
  ASSERT_EQ(bodies.size(), 1u);
  EXPECT_EQ(bodies[0].name, "wand");
  ASSERT_EQ(bodies[0].markers.size(), 4u);
  EXPECT_EQ(scene.marker_names(),
            (std::vector<std::string>{"loose", "wand/0", "wand/1", "wand/2", "wand/3"}));
  std::vector<double> distances;
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = i + 1; j < 4; ++j)
      distances.push_back((bodies[0].markers[i] - bodies[0].markers[j]).norm());
  }
  std::sort(distances.begin(), distances.end());
  for (std::size_t i = 1; i < distances.size(); ++i) EXPECT_GT(distances[i] - distances[i - 1], 0.02);
}

TEST(Scene, PathsFollowTheirFormulas) {
  const Scene scene = Scene::from_yaml_string(kOneCamera + R"(
markers:
  - name: still
    path: {type: static, position: [1, 2, 3]}
  - name: line
    path: {type: linear, start: [0, 0, 1], velocity: [0.5, -1, 0]}
  - name: ring
    path: {type: circle, center: [0, 0, 1], radius: 0.5, frequency: 0.25}
  - name: tilted
    path: {type: circle, center: [0, 0, 1], radius: 1, frequency: 0.25, axis: [1, 0, 0], phase: 0.5}
  - name: figure
    path: {type: lissajous, center: [0, 0, 1], amplitude: [0.5, 0.4, 0.3], frequency: [0.2, 0.3, 0.1], phase: [0, 1, 2]}
  - name: route
    path: {type: waypoints, points: [[0, 0, 0], [1, 0, 0], [1, 2, 0]], times: [0, 1, 3], loop: true}
)");
  const auto at = [&](double t_s) { return scene.markers_at(seconds_to_ns(t_s)); };
  const auto m = at(1.0);
  ASSERT_EQ(m.size(), 6u);
  EXPECT_TRUE(m[0].p.isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(m[1].p.isApprox(Eigen::Vector3d(0.5, -1, 1)));
  // A quarter turn counter-clockwise about +z from +x.
  EXPECT_LT((m[2].p - Eigen::Vector3d(0, 0.5, 1)).norm(), 1e-12);
  EXPECT_LT((at(0.0)[2].p - Eigen::Vector3d(0.5, 0, 1)).norm(), 1e-12);
  // About +x the circle lies in the y-z plane, radius 1 around the centre.
  EXPECT_NEAR(m[3].p.x(), 0.0, 1e-12);
  EXPECT_NEAR((m[3].p - Eigen::Vector3d(0, 0, 1)).norm(), 1.0, 1e-12);
  const double two_pi = 2.0 * std::numbers::pi;
  EXPECT_NEAR(m[4].p.x(), 0.5 * std::sin(two_pi * 0.2), 1e-12);
  EXPECT_NEAR(m[4].p.y(), 0.4 * std::sin(two_pi * 0.3 + 1), 1e-12);
  EXPECT_NEAR(m[4].p.z(), 1 + 0.3 * std::sin(two_pi * 0.1 + 2), 1e-12);
  EXPECT_TRUE(m[5].p.isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_LT((at(2.0)[5].p - Eigen::Vector3d(1, 1, 0)).norm(), 1e-12);
  EXPECT_LT((at(0.5)[5].p - Eigen::Vector3d(0.5, 0, 0)).norm(), 1e-12);
  EXPECT_LT((at(3.5)[5].p - Eigen::Vector3d(0.5, 0, 0)).norm(), 1e-12);  // looped: period 3 s
  EXPECT_DOUBLE_EQ(scene.marker_radius(0), 0.007);
}

TEST(Scene, BodiesMoveTheirMarkersRigidly) {
  const Scene scene = Scene::from_yaml_string(kOneCamera + R"(
markers:
  - name: lone
    path: {type: static, position: [0, 0, 1]}
bodies:
  - name: spinner
    markers: [[0.1, 0, 0], [0, 0.2, 0], [0, 0, 0.3]]
    marker_radius: 0.005
    path: {type: static, position: [1, 1, 1]}
    rotation: {type: spin, axis: [0, 0, 1], rate: 0.5}
  - name: rocker
    markers: [[0.1, 0, 0]]
    path: {type: linear, start: [0, 0, 1], velocity: [0.1, 0, 0]}
    rotation: {type: oscillate, amplitude: [0, 0, 0.4], frequency: [0, 0, 0.25], initial: [0, 0, 1, 0]}
)");
  EXPECT_EQ(scene.marker_names(),
            (std::vector<std::string>{"lone", "spinner/0", "spinner/1", "spinner/2", "rocker/0"}));
  EXPECT_DOUBLE_EQ(scene.marker_radius(1), 0.005);
  const TimeNs t = seconds_to_ns(1.0);
  const auto bodies = scene.bodies_at(t);
  ASSERT_EQ(bodies.size(), 2u);
  EXPECT_EQ(bodies[0].name, "spinner");
  EXPECT_NEAR(bodies[0].T_world_body.q.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-12);
  // At t = 1 s the oscillation is at its +0.4 rad extreme, on top of the initial half turn.
  const Eigen::Quaterniond rocker_expected =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.4 + std::numbers::pi, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(bodies[1].T_world_body.q.angularDistance(rocker_expected), 0.0, 1e-12);
  EXPECT_TRUE(bodies[1].T_world_body.t.isApprox(Eigen::Vector3d(0.1, 0, 1)));

  const auto markers = scene.markers_at(t);
  const auto definitions = scene.body_definitions();
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LT((markers[1 + i].p - bodies[0].T_world_body.apply(definitions[0].markers[i])).norm(), 1e-12);
  }
  EXPECT_LT((markers[4].p - bodies[1].T_world_body.apply(definitions[1].markers[0])).norm(), 1e-12);
}

TEST(Scene, WaypointRotationsHoldAndSlerpBetweenOrientations) {
  // A wand laid down along x, then turned a quarter turn about z over 2 s and laid down again.
  const Scene scene = Scene::from_yaml_string(kOneCamera + R"(
bodies:
  - name: wand
    markers: [[0.5, 0, 0]]
    path: {type: static, position: [0, 0, 0]}
    rotation: {type: waypoints, q: [[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0.70710678118654752, 0.70710678118654752]], times: [0, 1, 3]}
)");
  const auto q_at = [&](double t_s) { return scene.bodies_at(seconds_to_ns(t_s))[0].T_world_body.q; };
  const auto about_z = [](double angle) {
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
  };
  EXPECT_NEAR(q_at(-1.0).angularDistance(about_z(0)), 0.0, 1e-12);  // first held before times[0]
  EXPECT_NEAR(q_at(0.5).angularDistance(about_z(0)), 0.0, 1e-12);   // at rest between equal orientations
  EXPECT_NEAR(q_at(2.0).angularDistance(about_z(std::numbers::pi / 4)), 0.0, 1e-12);  // halfway: slerp
  EXPECT_NEAR(q_at(9.0).angularDistance(about_z(std::numbers::pi / 2)), 0.0, 1e-12);  // last held
  EXPECT_LT((scene.markers_at(seconds_to_ns(3.0))[0].p - Eigen::Vector3d(0, 0.5, 0)).norm(), 1e-12);

  const ConfigError unordered = load_error(kOneCamera + R"(
bodies:
  - name: b
    markers: [[0, 0, 0]]
    path: {type: static, position: [0, 0, 1]}
    rotation: {type: waypoints, q: [[0, 0, 0, 1], [0, 0, 1, 0]], times: [1, 1]}
)");
  EXPECT_EQ(unordered.key(), "bodies[0].rotation.times");
  EXPECT_EQ(load_error(kOneCamera + R"(
bodies:
  - name: b
    markers: [[0, 0, 0]]
    path: {type: static, position: [0, 0, 1]}
    rotation: {type: waypoints, q: [[0, 0, 0, 0]], times: [0]}
)")
                .key(),
            "bodies[0].rotation.q");
}

TEST(Scene, CameraDefaultsApplyUnlessACameraOverridesThem) {
  const Scene scene = Scene::from_yaml_string(R"(
seed: 5
duration: 2.5
defaults:
  width: 320
  height: 240
  K: [300, 300, 159.5, 119.5]
  rate: 50
  bits: 12
  look_at: {eye: [0, -3, 1], target: [0, 0, 1]}
cameras:
  - id: a
  - id: b
    rate: 25
    width: 100
    phase: 0.004
    clock_offset: -0.25
    exposure: 0.002
    dropout: 0.5
    T_world_cam: {q: [0, 0, 0, 1], t: [1, 2, 3]}
markers:
  - path: {type: static, position: [0, 0, 1]}
)");
  EXPECT_EQ(scene.seed(), 5u);
  EXPECT_EQ(scene.duration_ns(), 2'500'000'000);
  const SimCameraConfig& a = scene.cameras()[0];
  const SimCameraConfig& b = scene.cameras()[1];
  EXPECT_EQ(a.calibration.intrinsics.width, 320);
  EXPECT_EQ(b.calibration.intrinsics.width, 100);
  EXPECT_EQ(b.calibration.intrinsics.height, 240);
  EXPECT_EQ(a.rate_hz, 50.0);
  EXPECT_EQ(b.rate_hz, 25.0);
  EXPECT_EQ(a.bits, 12);
  EXPECT_EQ(b.phase_ns, 4'000'000);
  EXPECT_EQ(b.clock_offset_ns, -250'000'000);
  EXPECT_EQ(b.exposure_ns, 2'000'000);
  EXPECT_EQ(a.exposure_ns, 1'000'000);
  EXPECT_EQ(b.dropout_probability, 0.5);
  EXPECT_TRUE(a.calibration.T_world_cam->t.isApprox(Eigen::Vector3d(0, -3, 1)));
  EXPECT_TRUE(b.calibration.T_world_cam->t.isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_EQ(scene.marker_names(), std::vector<std::string>{"m0"});
}

TEST(Scene, ErrorsNameTheFileAndTheKey) {
  const std::string camera_without_K = R"(
cameras:
  - id: cam0
    width: 640
    height: 480
    look_at: {eye: [0, -4, 1], target: [0, 0, 1]}
markers:
  - path: {type: static, position: [0, 0, 1]}
)";
  EXPECT_EQ(load_error(camera_without_K).key(), "cameras[0].K");

  const ConfigError path_type = load_error(kOneCamera + R"(
markers:
  - name: a
    path: {type: static, position: [0, 0, 1]}
  - name: b
    path: {type: spiral, center: [0, 0, 1]}
)");
  EXPECT_EQ(path_type.key(), "markers[1].path.type");
  EXPECT_NE(std::string(path_type.what()).find("spiral"), std::string::npos);

  const ConfigError trc = load_error(kOneCamera + R"(
trc:
  file: no_such_walk.trc
)");
  EXPECT_EQ(trc.key(), "trc.file");
  EXPECT_NE(std::string(trc.what()).find("no_such_walk.trc"), std::string::npos);

  EXPECT_EQ(load_error(kOneCamera + R"(
markers:
  - path: {type: static, position: [0, 0, 1]}
    radus: 0.01
)")
                .key(),
            "markers[0].radus");
  EXPECT_EQ(load_error(kOneCamera + R"(
markers:
  - path: {type: lissajous, center: [0, 0, 1], amplitude: [1, 1], frequency: [1, 1, 1]}
)")
                .key(),
            "markers[0].path.amplitude");
  EXPECT_EQ(
      load_error(kOneCamera + "    bits: 9\nmarkers:\n  - path: {type: static, position: [0, 0, 1]}\n").key(),
      "cameras[0].bits");
  const std::string second_cam0 = kOneCamera.substr(kOneCamera.find("  - id"));
  EXPECT_EQ(load_error(kOneCamera + second_cam0).key(), "cameras[1].id");
  EXPECT_EQ(load_error(kOneCamera).key(), "markers");  // nothing to see
  EXPECT_EQ(load_error("defaults: {rate: 0}\n" + kOneCamera +
                       "markers:\n  - path: {type: static, position: [0, 0, 1]}\n")
                .key(),
            "defaults.rate");
  EXPECT_EQ(load_error(kOneCamera + R"(
bodies:
  - name: b
    markers: [[0, 0, 0]]
    path: {type: static, position: [0, 0, 1]}
    rotation: {type: spin, axis: [0, 0, 0], rate: 1}
)")
                .key(),
            "bodies[0].rotation.axis");
}

TEST(Scene, MissingOrMalformedFilesAreConfigErrors) {
  EXPECT_THROW(Scene::load("/nonexistent/scene.yaml"), ConfigError);
  EXPECT_THROW(Scene::from_yaml_string("cameras: [", ".", "inline"), ConfigError);
  try {
    Scene::from_yaml_string("cameras: []\n", ".", "inline.yaml");
    ADD_FAILURE();
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.file(), "inline.yaml");
    EXPECT_EQ(error.key(), "cameras");
  }
}

}  // namespace
}  // namespace panoptes

namespace panoptes {
namespace {

// Issue 22: laser spots on the wall exist only while the pen is down.
TEST(Scene, PenDownIntervalsSwitchAMarkerOnAndOff) {
  const Scene scene = Scene::load(kScenes / "surface_wall.yaml");
  ASSERT_EQ(scene.marker_names().at(4), "line_high");  // pen down in [0.2, 4.9) s
  const auto valid_at = [&](double t_s) { return scene.markers_at(seconds_to_ns(t_s)).at(4).valid; };
  EXPECT_FALSE(valid_at(0.19));
  EXPECT_TRUE(valid_at(0.2));
  EXPECT_TRUE(valid_at(4.89));
  EXPECT_FALSE(valid_at(4.9));
  // The spots lie on the wall (y = 0) whether on or off.
  for (const auto& marker : scene.markers_at(seconds_to_ns(1.0))) EXPECT_NEAR(marker.p.y(), 0.0, 1e-12);
  const ConfigError reversed = load_error(kOneCamera +
                                          "markers: [{name: a, path: {type: static, position: [0, 0, 0]}, "
                                          "pen_down: [[1.0, 2.0], [1.5, 3.0]]}]\n");
  EXPECT_EQ(reversed.key(), "markers[0].pen_down") << reversed.what();
}

}  // namespace
}  // namespace panoptes
