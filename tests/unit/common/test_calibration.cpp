// SPDX-License-Identifier: Apache-2.0
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/config.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

// Values that need all 17 significant digits, so any loss of precision shows.
SystemCalibration awkward_calibration() {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  SystemCalibration calibration;
  for (int i = 0; i < 3; ++i) {
    CameraCalibration camera;
    camera.id = "cam" + std::to_string(i);
    camera.intrinsics.width = 1280 + i;
    camera.intrinsics.height = 1024 - i;
    camera.intrinsics.fx = 800.0 + unit(rng) / 3.0;
    camera.intrinsics.fy = 801.0 + unit(rng) / 7.0;
    camera.intrinsics.cx = 640.0 + unit(rng);
    camera.intrinsics.cy = 512.0 + unit(rng);
    camera.intrinsics.distortion = {unit(rng) * 0.3, unit(rng) * 0.1, unit(rng) * 1e-3, 1e-19 * unit(rng),
                                    0.1};
    if (i != 1) {  // camera 1 holds intrinsics only
      RigidTransform T;
      T.q = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
      T.t = Eigen::Vector3d(unit(rng) * 5, unit(rng) * 5, 1.0 / 3.0);
      camera.T_world_cam = T;
    }
    calibration.cameras.push_back(camera);
  }
  return calibration;
}

const char* kValidCamera =
    "  - id: cam0\n"
    "    width: 1280\n"
    "    height: 1024\n"
    "    K: [800, 801, 640, 512]\n";

TEST(Calibration, SaveLoadRoundTripIsExact) {
  testing::TempDir dir;
  const SystemCalibration original = awkward_calibration();
  const auto path = dir.file("cal.yaml");
  save_calibration(original, path);
  const SystemCalibration loaded = load_calibration(path);
  ASSERT_EQ(loaded.cameras.size(), original.cameras.size());
  for (std::size_t i = 0; i < original.cameras.size(); ++i) {
    const CameraCalibration& a = original.cameras[i];
    const CameraCalibration& b = loaded.cameras[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.intrinsics.width, b.intrinsics.width);
    EXPECT_EQ(a.intrinsics.height, b.intrinsics.height);
    EXPECT_EQ(a.intrinsics.fx, b.intrinsics.fx);
    EXPECT_EQ(a.intrinsics.fy, b.intrinsics.fy);
    EXPECT_EQ(a.intrinsics.cx, b.intrinsics.cx);
    EXPECT_EQ(a.intrinsics.cy, b.intrinsics.cy);
    EXPECT_EQ(a.intrinsics.distortion, b.intrinsics.distortion);
    ASSERT_EQ(a.T_world_cam.has_value(), b.T_world_cam.has_value());
    if (a.T_world_cam) {
      EXPECT_EQ(a.T_world_cam->q.coeffs(), b.T_world_cam->q.coeffs());
      EXPECT_EQ(a.T_world_cam->t, b.T_world_cam->t);
    }
  }
  // Saving what was loaded gives the same text: nothing drifts over repeated tool runs.
  EXPECT_EQ(calibration_to_yaml(loaded), calibration_to_yaml(original));
}

TEST(Calibration, LoadsContractExample) {
  testing::TempDir dir;
  const auto path = dir.write("cal.yaml",
                              "cameras:\n"
                              "  - id: cam0\n"
                              "    width: 1280\n"
                              "    height: 1024\n"
                              "    K: [900.5, 901.25, 640.5, 511.75]   # pixels\n"
                              "    distortion: [-0.1, 0.02, 0.001, -0.002, 0.003]\n"
                              "    T_world_cam:\n"
                              "      q: [0, 0, 0, 2]\n"
                              "      t: [1, 2, 3]\n"
                              "  - id: cam1\n"
                              "    width: 640\n"
                              "    height: 480\n"
                              "    K: [500, 500, 320, 240]\n");
  const SystemCalibration calibration = load_calibration(path);
  ASSERT_EQ(calibration.cameras.size(), 2u);
  const CameraCalibration* cam0 = calibration.find("cam0");
  ASSERT_NE(cam0, nullptr);
  EXPECT_EQ(cam0->intrinsics.fx, 900.5);
  EXPECT_EQ(cam0->intrinsics.fy, 901.25);
  EXPECT_EQ(cam0->intrinsics.cx, 640.5);
  EXPECT_EQ(cam0->intrinsics.cy, 511.75);
  EXPECT_EQ(cam0->intrinsics.distortion, (std::array<double, 5>{-0.1, 0.02, 0.001, -0.002, 0.003}));
  ASSERT_TRUE(cam0->T_world_cam.has_value());
  // [x, y, z, w] order, normalised on load.
  EXPECT_DOUBLE_EQ(cam0->T_world_cam->q.w(), 1.0);
  EXPECT_DOUBLE_EQ(cam0->T_world_cam->q.norm(), 1.0);
  EXPECT_EQ(cam0->T_world_cam->t, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(cam0->model().center_world(), Eigen::Vector3d(1, 2, 3));

  const CameraCalibration* cam1 = calibration.find("cam1");
  ASSERT_NE(cam1, nullptr);
  EXPECT_EQ(cam1->intrinsics.distortion, (std::array<double, 5>{}));
  EXPECT_FALSE(cam1->T_world_cam.has_value());
  EXPECT_THROW(cam1->model(), std::logic_error);
  EXPECT_EQ(calibration.find("cam2"), nullptr);
}

TEST(Calibration, QuaternionOrderIsXyzw) {
  testing::TempDir dir;
  // 90 degrees about z: [0, 0, sin45, cos45].
  const auto path =
      dir.write("cal.yaml", std::string("cameras:\n") + kValidCamera +
                                "    T_world_cam: {q: [0, 0, 0.7071067811865476, 0.7071067811865476], "
                                "t: [0, 0, 0]}\n");
  const SystemCalibration calibration = load_calibration(path);
  const Eigen::Vector3d x_in_world = calibration.cameras[0].T_world_cam->apply(Eigen::Vector3d::UnitX());
  EXPECT_LT((x_in_world - Eigen::Vector3d::UnitY()).norm(), 1e-12);
}

struct BadFile {
  const char* name;
  std::string text;
  std::string expected_message;  // after "<path>: "
};

TEST(Calibration, BadFilesNameFileAndKey) {
  const std::vector<BadFile> cases = {
      {"missing K",
       std::string("cameras:\n") + kValidCamera + "  - id: cam1\n    width: 1280\n    height: 1024\n",
       "cameras[1].K: missing key"},
      {"short K",
       std::string("cameras:\n") + kValidCamera + "  - {id: cam1, width: 64, height: 48, K: [1, 2, 3]}\n",
       "cameras[1].K: expected a list of 4 numbers, got 3"},
      {"K not a list",
       std::string("cameras:\n") + kValidCamera + "  - {id: cam1, width: 64, height: 48, K: 5}\n",
       "cameras[1].K: expected a list of 4 numbers"},
      {"K element",
       std::string("cameras:\n") + kValidCamera + "  - {id: cam1, width: 64, height: 48, K: [1, b, 3, 4]}\n",
       "cameras[1].K[1]: expected a number, got 'b'"},
      {"long distortion", std::string("cameras:\n") + kValidCamera + "    distortion: [0, 0, 0, 0, 0, 0]\n",
       "cameras[0].distortion: expected a list of 5 numbers, got 6"},
      {"zero width", "cameras:\n  - {id: cam0, width: 0, height: 48, K: [1, 1, 3, 4]}\n",
       "cameras[0].width: expected a positive integer, got 0"},
      {"fractional height", "cameras:\n  - {id: cam0, width: 64, height: 4.5, K: [1, 1, 3, 4]}\n",
       "cameras[0].height: expected an integer, got '4.5'"},
      {"negative fy", "cameras:\n  - {id: cam0, width: 64, height: 48, K: [1, -1, 3, 4]}\n",
       "cameras[0].K: fx and fy must be positive"},
      {"duplicate id", std::string("cameras:\n") + kValidCamera + kValidCamera,
       "cameras[1].id: duplicate camera id 'cam0'"},
      {"zero quaternion",
       std::string("cameras:\n") + kValidCamera + "    T_world_cam: {q: [0, 0, 0, 0], t: [0, 0, 0]}\n",
       "cameras[0].T_world_cam.q: quaternion has near-zero norm"},
      {"missing t", std::string("cameras:\n") + kValidCamera + "    T_world_cam: {q: [0, 0, 0, 1]}\n",
       "cameras[0].T_world_cam.t: missing key"},
      {"no cameras key", "camera: []\n", "cameras: missing key"},
      {"cameras not a list", "cameras: {id: cam0}\n", "cameras: expected a list"},
      {"empty cameras", "cameras: []\n", "cameras: expected at least one camera"},
      {"empty file", "", "cameras: missing key"},
  };
  testing::TempDir dir;
  for (const BadFile& bad : cases) {
    const auto path = dir.write("cal.yaml", bad.text);
    EXPECT_EQ(config_error_of([&] { load_calibration(path); }), path.string() + ": " + bad.expected_message)
        << bad.name;
  }
}

TEST(Calibration, MissingFileAndSyntaxErrorNameTheFile) {
  testing::TempDir dir;
  const auto missing = dir.file("absent_cal.yaml");
  EXPECT_EQ(config_error_of([&] { load_calibration(missing); }), missing.string() + ": cannot open file");

  const auto broken =
      dir.write("broken_cal.yaml", std::string("cameras:\n") + kValidCamera + "    K: [1, 2\n");
  const std::string message = config_error_of([&] { load_calibration(broken); });
  EXPECT_EQ(message.rfind(broken.string() + ": ", 0), 0u) << message;
  EXPECT_NE(message.find("line "), std::string::npos) << message;
}

TEST(Calibration, SaveToUnwritablePathThrowsConfigError) {
  const std::string message =
      config_error_of([] { save_calibration(awkward_calibration(), "/nonexistent/dir/cal.yaml"); });
  EXPECT_NE(message.find("/nonexistent/dir/cal.yaml"), std::string::npos) << message;
}

TEST(Bodies, SaveLoadRoundTripIsExact) {
  testing::TempDir dir;
  std::vector<BodyDefinition> bodies = {
      {"wand", {{0, 0, 0}, {0.1, 0, 0}, {0.25, 1.0 / 3.0, -0.0123456789012345}}},
      {"single", {{1e-3, -2e-3, 3.14159265358979}}},
  };
  const auto path = dir.file("bodies.yaml");
  save_bodies(bodies, path);
  const std::vector<BodyDefinition> loaded = load_bodies(path);
  ASSERT_EQ(loaded.size(), bodies.size());
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    EXPECT_EQ(loaded[i].name, bodies[i].name);
    EXPECT_EQ(loaded[i].markers, bodies[i].markers);
  }
}

TEST(Bodies, BadFilesNameFileAndKey) {
  const std::vector<BadFile> cases = {
      {"short marker", "bodies:\n  - name: wand\n    markers: [[0, 0, 0], [1, 2]]\n",
       "bodies[0].markers[1]: expected a list of 3 numbers, got 2"},
      {"no markers", "bodies:\n  - name: wand\n    markers: []\n",
       "bodies[0].markers: expected at least one marker"},
      {"missing name", "bodies:\n  - markers: [[0, 0, 0]]\n", "bodies[0].name: missing key"},
      {"duplicate name",
       "bodies:\n  - {name: a, markers: [[0, 0, 0]]}\n  - {name: a, markers: [[1, 0, 0]]}\n",
       "bodies[1].name: duplicate body name 'a'"},
      {"missing bodies", "other: 1\n", "bodies: missing key"},
  };
  testing::TempDir dir;
  for (const BadFile& bad : cases) {
    const auto path = dir.write("bodies.yaml", bad.text);
    EXPECT_EQ(config_error_of([&] { load_bodies(path); }), path.string() + ": " + bad.expected_message)
        << bad.name;
  }
}

}  // namespace
}  // namespace panoptes
