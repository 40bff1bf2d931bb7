// SPDX-License-Identifier: Apache-2.0
// Wand calibration benchmarks (issue 6), printed as JSON lines:
//  - speed: 16 cameras x 2000 wand frames each, solve time;
//  - the acceptance studio (mocap lenses) with the wand waved through growing volumes;
//  - seed 003 §3.3.2 alternation (virtual calibration object) against the joint bundle adjustment
//    on the 8-camera room, same data;
//  - side by side on two cameras: the wand against OpenCV stereoCalibrate on a simulated
//    chessboard with the same centroid noise.
#include <chrono>
#include <cstdio>
#include <exception>
#include <random>

#include <opencv2/calib3d.hpp>

#include "calib_scenes.h"
#include "panoptes/cli.h"
#include "panoptes/process.h"

using namespace panoptes;
using namespace panoptes::calib;
using namespace panoptes::calib::testing;

namespace {

const WandDefinition kWand{{0.0, 0.18, 0.5}};

void line(const char* name, const Measured& m, double simulate_s) {
  const auto& r = m.result;
  std::printf(
      "{\"case\": \"%s\", \"cameras\": %zu, \"calibrated\": %d, \"solve_s\": %.3f, "
      "\"simulate_and_identify_s\": %.3f, "
      "\"raw_rms_axis_px\": %.4f, \"rms_2d_px\": %.4f, \"position_max_mm\": %.4f, \"rotation_max_deg\": "
      "%.5f, "
      "\"length_mean_mm\": %.4f, \"length_sigma_mm\": %.4f, \"iterations\": %d}\n",
      name, r.cameras.size(), r.calibrated_count(), r.seconds, simulate_s, r.raw_rms_axis_px, r.rms_px,
      m.max_position_error_mm, m.max_rotation_error_deg, r.lengths.mean_error_mm, r.lengths.sigma_mm,
      r.iterations);
  std::fflush(stdout);
}

SceneSpec ring16() {
  return ring(16);
}

// Two cameras 1.2 m apart; OpenCV stereoCalibrate (intrinsics fixed) on a 9x6 board of 60 mm squares
// in 20 poses, with the same centroid noise; extrinsic errors compared with the wand's.
void stereo_side_by_side() {
  SceneSpec spec = room8();
  spec.cameras = {spec.cameras[0], spec.cameras[1]};
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  SolveOptions options;
  options.min_pair_samples = 25;
  const auto t0 = std::chrono::steady_clock::now();
  // Two cameras: align on both centres is under-determined, so compare the relative pose instead.
  std::vector<CameraCalibration> given;
  std::vector<CameraIntrinsics> intrinsics;
  for (const auto& c : scene.cameras()) {
    auto camera = c.calibration;
    camera.T_world_cam.reset();
    given.push_back(camera);
    intrinsics.push_back(camera.intrinsics);
  }
  const auto tracks = simulate_tracks(scene, kWand, intrinsics);
  const SolveResult result = solve_wand_calibration(given, tracks, kWand, options);
  const double simulate_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto relative = [](const RigidTransform& a, const RigidTransform& b) { return a.inverse() * b; };
  const RigidTransform truth =
      relative(*scene.cameras()[0].calibration.T_world_cam, *scene.cameras()[1].calibration.T_world_cam);
  double wand_t_mm = -1, wand_r_deg = -1;
  if (result.calibrated_count() == 2) {
    const RigidTransform est = relative(*result.cameras[0].T_world_cam, *result.cameras[1].T_world_cam);
    wand_t_mm = (est.t - truth.t).norm() * 1e3;
    wand_r_deg = truth.q.angularDistance(est.q) * 180 / M_PI;
  }
  // Chessboard: 20 random poses in front of both cameras, around the point both look at.
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, spec.noise_px);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const CameraModel m0 = scene.cameras()[0].calibration.model(), m1 = scene.cameras()[1].calibration.model();
  std::vector<std::vector<cv::Point3f>> objects;
  std::vector<std::vector<cv::Point2f>> image0, image1;
  const Eigen::Vector3d centre =
      0.5 * (m0.center_world() + m1.center_world()) +
      0.55 * ((spec.cameras[0].target - m0.center_world()) + (spec.cameras[1].target - m1.center_world()));
  int views = 0;
  for (int attempt = 0; attempt < 2000 && views < 20; ++attempt) {
    const Eigen::Vector3d toward = (0.5 * (m0.center_world() + m1.center_world()) - centre).normalized();
    const Eigen::Vector3d tilt(uniform(rng) * 0.5, uniform(rng) * 0.5, uniform(rng) * 0.5);
    RigidTransform T_world_board =
        look_at(centre + Eigen::Vector3d(uniform(rng), uniform(rng), 0.5 * uniform(rng)) * 0.6,
                centre - toward + tilt);
    std::vector<cv::Point3f> object;
    std::vector<cv::Point2f> p0, p1;
    bool ok = true;
    for (int r = 0; r < 6 && ok; ++r)
      for (int c = 0; c < 9 && ok; ++c) {
        const Eigen::Vector3d local((c - 4) * 0.06, (r - 2.5) * 0.06, 0);
        const Eigen::Vector3d X = T_world_board.apply(local);
        const auto a = m0.project(X), b = m1.project(X);
        // Both cameras must see the board's front: camera centres on the board's -z side.
        const Eigen::Vector3d normal = T_world_board.rotation().col(2);
        if (!a || !b || !m0.in_image(*a, 5) || !m1.in_image(*b, 5) || normal.dot(m0.center_world() - X) > 0 ||
            normal.dot(m1.center_world() - X) > 0) {
          ok = false;
          break;
        }
        object.emplace_back(static_cast<float>(local.x()), static_cast<float>(local.y()), 0.f);
        p0.emplace_back(static_cast<float>(a->x() + noise(rng)), static_cast<float>(a->y() + noise(rng)));
        p1.emplace_back(static_cast<float>(b->x() + noise(rng)), static_cast<float>(b->y() + noise(rng)));
      }
    if (!ok) continue;
    objects.push_back(object);
    image0.push_back(p0);
    image1.push_back(p1);
    ++views;
  }
  const auto K = [](const CameraIntrinsics& k) -> cv::Mat {
    cv::Mat m = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
    return m;
  };
  cv::Mat K0 = K(m0.intrinsics()), K1 = K(m1.intrinsics()), D0 = cv::Mat::zeros(1, 5, CV_64F),
          D1 = D0.clone();
  cv::Mat R, T, E, F;
  double cv_t_mm = -1, cv_r_deg = -1, cv_rms = -1;
  if (views >= 5) {
    cv_rms = cv::stereoCalibrate(objects, image0, image1, K0, D0, K1, D1, cv::Size(1280, 1024), R, T, E, F,
                                 cv::CALIB_FIX_INTRINSIC);
    // OpenCV: x1 = R x0 + T, i.e. T_cam1_cam0; truth is T_cam0_cam1.
    Eigen::Matrix3d Re;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Re(i, j) = R.at<double>(i, j);
    RigidTransform T10{Eigen::Quaterniond(Re),
                       Eigen::Vector3d(T.at<double>(0), T.at<double>(1), T.at<double>(2))};
    const RigidTransform est = T10.inverse();
    cv_t_mm = (est.t - truth.t).norm() * 1e3;
    cv_r_deg = truth.q.angularDistance(est.q) * 180 / M_PI;
  }
  std::printf(
      "{\"case\": \"stereo side by side\", \"noise_px\": %.2f, \"baseline_m\": %.3f, \"wand_samples\": %zu, "
      "\"wand_translation_error_mm\": %.4f, \"wand_rotation_error_deg\": %.5f, \"wand_solve_s\": %.3f, "
      "\"chessboard_views\": %d, \"opencv_rms_px\": %.4f, \"opencv_translation_error_mm\": %.4f, "
      "\"opencv_rotation_error_deg\": %.5f, \"simulate_s\": %.2f}\n",
      spec.noise_px, truth.t.norm(), result.samples.size(), wand_t_mm, wand_r_deg, result.seconds, views,
      cv_rms, cv_t_mm, cv_r_deg, simulate_s);
}

int run(int argc, char** argv) {
  std::string only;
  CLI::App app{"bench_calibration: wand calibration benchmarks, printed as JSON lines", "bench_calibration"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("section", only, "run only this one")
      ->check(CLI::IsMember({"alternation", "stereo", "lens", "studio", "speed"}))
      ->default_str("all");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  if (only.empty() || only == "alternation") {
    const Scene scene = Scene::from_yaml_string(scene_yaml(room8()));
    for (int iterations : {1, 5, 40}) {
      SolveOptions options;
      options.alternation_iterations = iterations;
      const Measured m = solve_and_measure(scene, kWand, options);
      line(("room8 seed-003 alternation x" + std::to_string(iterations)).c_str(), m, 0);
    }
    const Measured m = solve_and_measure(scene, kWand, SolveOptions{});
    line("room8 bundle adjustment", m, 0);
  }
  if (only.empty() || only == "stereo") stereo_side_by_side();
  if (only.empty() || only == "lens") {
    // The 8-camera room with the simulated lens (f = 700 px, 85 deg) against mocap lenses:
    // 1280x1024 at 56 x 46 deg (f = 1200) and 50 x 41 deg (f = 1400), 2048x2048 at 51 deg
    // (f = 2150). Same cameras, aim, wand path and 0.1 px noise: the free-length sigma and how
    // many cameras see each sample.
    struct Lens {
      int width, height;
      double focal;
    };
    for (const Lens lens :
         {Lens{1280, 1024, 700}, Lens{1280, 1024, 1200}, Lens{1280, 1024, 1400}, Lens{2048, 2048, 2150}}) {
      SceneSpec spec = room8();
      spec.width = lens.width;
      spec.height = lens.height;
      spec.focal = lens.focal;
      const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
      const Measured m = solve_and_measure(scene, kWand, SolveOptions{});
      const std::string name = "room8 lens " + std::to_string(lens.width) + "x" +
                               std::to_string(lens.height) + " f " +
                               std::to_string(static_cast<int>(lens.focal));
      line(name.c_str(), m, 0);
      std::printf("  true-camera length sigma %.4f mm;", m.truth_lengths.sigma_mm);
      print_coverage(m, scene);
    }
  }
  if (only.empty() || only == "studio") {
    // The acceptance studio (calib_scenes.h studio8: Prime 41 class lenses, corners and wall
    // centres, aimed into the capture volume) with the wand waved through a growing volume:
    // +-0.8 m (the test's), +-1.0 m and +-1.2 m about the centre (the wand's ends reach 0.25 m
    // further). The true-camera sigma is the floor set by the noise and the optics.
    for (const double amplitude : {0.8, 1.0, 1.2}) {
      StudioLayout layout;
      layout.amplitude = Eigen::Vector3d(amplitude, amplitude, amplitude == 0.8 ? 0.55 : 0.65);
      const Scene scene = Scene::from_yaml_string(scene_yaml(studio8(layout)));
      const Measured m = solve_and_measure(scene, kWand, SolveOptions{});
      char name[64];
      std::snprintf(name, sizeof(name), "studio8 2048x2048 f 2150, wand +-%.1f m", amplitude);
      line(name, m, 0);
      std::printf("  true-camera length sigma %.4f mm;", m.truth_lengths.sigma_mm);
      print_coverage(m, scene);
    }
  }
  if (only.empty() || only == "speed") {
    const auto t0 = std::chrono::steady_clock::now();
    const Scene scene = Scene::from_yaml_string(scene_yaml(ring16()));
    SolveOptions options;
    options.time_offsets = true;
    const Measured m = solve_and_measure(scene, kWand, options);
    const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    line("16 cameras x 2000 frames, time offsets on", m, total - m.result.seconds);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_calibration", [&] { return run(argc, argv); });
}
