// SPDX-License-Identifier: Apache-2.0
// The `surface:` settings of estimator_node's surface mode (docs/surface.md): what they read, and
// the errors that name the file and key (issue 22, "Bad input").
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "panoptes/errors.h"
#include "panoptes/surface_app/surface_mode.h"
#include "panoptes/surface_app/surface_settings.h"

namespace panoptes::surface_app {
namespace {

namespace fs = std::filesystem;

class SurfaceSettingsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("panoptes_surface_settings_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  // The ConfigError loading `yaml` (and building it against `calibration`) raises.
  ConfigError error_of(const std::string& yaml, const SystemCalibration* calibration = nullptr) const {
    const fs::path path = write("surface.yaml", yaml);
    try {
      const auto settings = load_surface_settings(path);
      if (settings) build_surface(*settings, calibration, "cal.yaml");
    } catch (const ConfigError& error) {
      EXPECT_EQ(error.file(), path.string()) << error.what();
      return error;
    }
    ADD_FAILURE() << "no ConfigError for:\n" << yaml;
    return ConfigError("", "", "");
  }

  fs::path dir_;
};

// A camera 2 m in front of the wall y = 0, looking at it (+y), x right, image y down (-z).
SystemCalibration wall_camera() {
  CameraCalibration camera;
  camera.id = "w0";
  camera.intrinsics.width = 1280;
  camera.intrinsics.height = 1024;
  camera.intrinsics.fx = camera.intrinsics.fy = 1829.0;
  camera.intrinsics.cx = 639.5;
  camera.intrinsics.cy = 511.5;
  Eigen::Matrix3d R_world_cam;
  R_world_cam << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // columns: camera x, y, z in the world
  camera.T_world_cam = RigidTransform{Eigen::Quaterniond(R_world_cam), Eigen::Vector3d(0.5, -2.0, 0.5)};
  SystemCalibration calibration;
  calibration.cameras.push_back(camera);
  return calibration;
}

TEST_F(SurfaceSettingsTest, ReadsThePlaneTheHomographiesAndTheTrackerOptions) {
  const auto settings = load_surface_settings(write("s.yaml", R"(
node: {status_period_s: 1}
surface:
  size: [3, 1]
  plane: {origin: [0, 0, 0], u_axis: [2, 0, 0], v_axis: [0, 0, 1]}
  cameras:
    - {id: w0}
    - {id: w1, homography: [[0.001, 0, 0], [0, -0.001, 1], [0, 0, 1]]}
    - {id: w2, homography: [0.001, 0, 2, 0, -0.001, 1, 0, 0, 1]}
  tracker: {pixel_sigma: 0.3, confirm_updates: 3, end_after_ms: 50}
  latency_window_ms: 4
)"));
  ASSERT_TRUE(settings.has_value());
  EXPECT_TRUE(settings->has_plane);
  EXPECT_EQ(settings->plane.u_axis, Eigen::Vector3d::UnitX());  // normalised
  EXPECT_EQ(settings->plane.size, Eigen::Vector2d(3, 1));
  ASSERT_EQ(settings->cameras.size(), 3U);
  EXPECT_FALSE(settings->cameras[0].homography.has_value());
  ASSERT_TRUE(settings->cameras[2].homography.has_value());
  EXPECT_EQ((*settings->cameras[2].homography)(0, 2), 2.0);
  EXPECT_EQ(*settings->cameras[1].homography,
            (Eigen::Matrix3d() << 0.001, 0, 0, 0, -0.001, 1, 0, 0, 1).finished());
  EXPECT_EQ(settings->tracker.confirm_updates, 3);
  EXPECT_EQ(settings->tracker.end_after_ns, 50'000'000);
  EXPECT_EQ(settings->latency_window_ms, 4.0);
  // The plane seen by w0's calibration, the homographies as given: pixel (639.5, 511.5), w0's
  // centre, is the wall's point (0.5, 0.5).
  const SystemCalibration calibration = wall_camera();
  auto setup = build_surface(*settings, &calibration, "cal.yaml");
  EXPECT_EQ(setup.camera_index("w2"), 2);
  EXPECT_EQ(setup.camera_index("other"), -1);
  const std::vector<Eigen::Vector2d> centre = {{639.5, 511.5}};
  setup.tracker->add_frame(0, 1'000'000, centre);
  setup.tracker->add_frame(0, 2'000'000, centre);
  const auto events = setup.tracker->add_frame(0, 3'000'000, centre);  // the third update confirms it
  ASSERT_FALSE(events.empty());
  EXPECT_NEAR(events[0].position.x(), 0.5, 1e-9);
  EXPECT_NEAR(events[0].position.y(), 0.5, 1e-9);
  // No surface section: not surface mode.
  EXPECT_FALSE(load_surface_settings(write("none.yaml", "node: {status_period_s: 1}\n")).has_value());
}

TEST_F(SurfaceSettingsTest, BadSettingsNameTheFileAndKey) {
  EXPECT_EQ(
      error_of("surface: {size: [3, 0], plane: {origin: [0, 0, 0], u_axis: [1, 0, 0], v_axis: [0, 0, 1]}}")
          .key(),
      "surface.size");
  EXPECT_EQ(
      error_of("surface: {size: [3, 1], plane: {origin: [0, 0, 0], u_axis: [1, 0, 0], v_axis: [1, 0, 1]}}")
          .key(),
      "surface.plane.v_axis");
  EXPECT_EQ(error_of("surface: {size: [3, 1], cameras: [{id: w0}]}").key(), "surface.cameras[0].homography");
  EXPECT_EQ(error_of("surface: {size: [3, 1]}").key(), "surface.plane");
  EXPECT_EQ(
      error_of("surface: {size: [3, 1], plane: {origin: [0, 0, 0], u_axis: [1, 0, 0], v_axis: [0, 0, 1]}, "
               "tracker: {jerk: 1}}")
          .key(),
      "surface.tracker.jerk");
  // A degenerate homography (rank 2).
  const ConfigError degenerate =
      error_of("surface: {size: [3, 1], cameras: [{id: w0, homography: [1, 2, 3, 2, 4, 6, 0, 0, 1]}]}");
  EXPECT_EQ(degenerate.key(), "surface.cameras[0].homography") << degenerate.what();
  EXPECT_NE(std::string(degenerate.what()).find("w0"), std::string::npos) << degenerate.what();
  // The wall 3 m behind the camera (which looks along +y from y = -2).
  const SystemCalibration calibration = wall_camera();
  const ConfigError behind =
      error_of("surface: {size: [3, 1], plane: {origin: [0, -3, 0], u_axis: [1, 0, 0], v_axis: [0, 0, 1]}}",
               &calibration);
  EXPECT_EQ(behind.key(), "surface.plane") << behind.what();
  EXPECT_NE(std::string(behind.what()).find("behind"), std::string::npos) << behind.what();
  EXPECT_NE(std::string(behind.what()).find("cal.yaml"), std::string::npos) << behind.what();
  // A listed camera the calibration does not have.
  const ConfigError unknown = error_of(
      "surface: {size: [3, 1], plane: {origin: [0, 0, 0], u_axis: [1, 0, 0], v_axis: [0, 0, 1]}, cameras: "
      "[{id: w9}]}",
      &calibration);
  EXPECT_EQ(unknown.key(), "surface.cameras[0]") << unknown.what();
}

TEST(StrokeJsonLine, CarriesTheEventAndItsCamera) {
  surface::StrokeEvent event;
  event.phase = surface::StrokePhase::kEnd;
  event.stroke_id = 7;
  event.stamp_ns = 1'700'000'000'123'000'000;
  event.position = {1.25, 0.5};
  event.velocity = {-0.5, 0.0};
  event.cameras = 2;
  const auto line = nlohmann::json::parse(stroke_json_line(event, "w1"));
  EXPECT_EQ(line["phase"], "end");
  EXPECT_EQ(line["id"], 7);
  EXPECT_EQ(line["stamp_ns"], 1'700'000'000'123'000'000);
  EXPECT_EQ(line["p"][0], 1.25);
  EXPECT_EQ(line["v"][0], -0.5);
  EXPECT_EQ(line["cameras"], 2);
  EXPECT_EQ(line["camera"], "w1");
}

}  // namespace
}  // namespace panoptes::surface_app
