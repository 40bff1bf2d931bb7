// SPDX-License-Identifier: Apache-2.0
#include "panoptes/surface_app/calibrate_surface.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/process.h"
#include "panoptes/surface/image_to_surface.h"

namespace panoptes::surface_app {
namespace {

Eigen::Vector2d read_pair(const YamlReader& reader, const std::string& key) {
  const auto values = reader.get_doubles(key, 2);
  Eigen::Vector2d v(values[0], values[1]);
  if (!v.allFinite()) reader.fail(key, "must be two finite numbers");
  return v;
}

SurfaceCorrespondences read_camera(const YamlReader& camera, const Eigen::Vector2d& size) {
  camera.expect_only({"id", "points", "corners"});
  SurfaceCorrespondences out;
  out.camera_id = camera.get_string("id");
  if (out.camera_id.empty()) camera.fail("id", "must not be empty");
  if (camera.has("corners")) {
    out.key = camera.key_of("corners");
    const auto corners = camera.get_double_rows("corners", 2);
    if (corners.size() != 4)
      camera.fail("corners", "needs the pixels of the 4 corners (0, 0), (W, 0), (W, H), (0, H)");
    const Eigen::Vector2d surface_corners[4] = {{0, 0}, {size.x(), 0}, {size.x(), size.y()}, {0, size.y()}};
    for (std::size_t i = 0; i < 4; ++i) {
      out.pixels.emplace_back(corners[i][0], corners[i][1]);
      out.surface.push_back(surface_corners[i]);
    }
  } else {
    out.key = camera.key_of("points");
    for (const YamlReader& point : camera.sequence("points")) {
      point.expect_only({"surface", "pixel"});
      out.surface.push_back(read_pair(point, "surface"));
      out.pixels.push_back(read_pair(point, "pixel"));
    }
  }
  return out;
}

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

}  // namespace

std::vector<SurfaceCorrespondences> load_surface_points(const std::string& path, Eigen::Vector2d& size) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path, root);
  reader.expect_only({"size", "cameras"});
  size = read_pair(reader, "size");
  if (!(size.x() > 0 && size.y() > 0)) reader.fail("size", "must be two lengths > 0 m");
  std::vector<SurfaceCorrespondences> cameras;
  for (const YamlReader& camera : reader.sequence("cameras")) cameras.push_back(read_camera(camera, size));
  if (cameras.empty()) reader.fail("cameras", "must list at least one camera");
  return cameras;
}

int run_calibrate_surface(int argc, char** argv) {
  std::string points_file, out_file;
  CLI::App app{
      "calibrate surface: a homography per camera from pixel <-> surface points (four clicked corners or a "
      "shown pattern), written as estimator_node --surface settings (docs/surface.md)",
      "estimator_node calibrate surface"};
  app.add_option("--points", points_file, "points YAML: size [W, H] and per camera corners or points")
      ->required();
  app.add_option("--out", out_file, "the surface settings YAML to write")->required();
  if (const auto code = parse_command_line(app, argc, argv, [] {})) return *code;
  Eigen::Vector2d size;
  std::ostringstream yaml;
  try {
    const auto cameras = load_surface_points(points_file, size);
    yaml << "# estimator_node calibrate surface --points " << points_file << "\nsurface:\n  size: ["
         << format_number(size.x()) << ", " << format_number(size.y()) << "]\n  cameras:\n";
    for (const auto& camera : cameras) {
      Eigen::Matrix3d H;
      try {
        H = surface::fit_homography(camera.pixels, camera.surface);
        H /= H(2, 2);
      } catch (const std::invalid_argument& error) {
        throw ConfigError(points_file, camera.key, "camera '" + camera.camera_id + "': " + error.what());
      }
      const auto mapping = surface::ImageToSurface::from_homography(H);
      double sum2 = 0, worst = 0;
      for (std::size_t i = 0; i < camera.pixels.size(); ++i) {
        const auto st = mapping.map(camera.pixels[i]);
        const double e = st ? (*st - camera.surface[i]).norm() : INFINITY;
        sum2 += e * e;
        worst = std::max(worst, e);
      }
      std::fprintf(stderr, "calibrate surface: camera %s: %zu points, residual RMS %.3f mm, max %.3f mm\n",
                   camera.camera_id.c_str(), camera.pixels.size(),
                   1e3 * std::sqrt(sum2 / static_cast<double>(camera.pixels.size())), 1e3 * worst);
      yaml << "    - id: " << camera.camera_id << "\n      homography: [";
      for (int r = 0; r < 3; ++r) {
        yaml << (r ? ", [" : "[");
        for (int c = 0; c < 3; ++c) yaml << (c ? ", " : "") << format_number(H(r, c));
        yaml << "]";
      }
      yaml << "]\n";
    }
  } catch (const ConfigError& error) {
    std::fprintf(stderr, "estimator_node calibrate surface: %s\n", error.what());
    return kExitBadInput;
  }
  std::ofstream out(out_file, std::ios::trunc);
  out << yaml.str();
  if (!out) {
    std::fprintf(stderr, "estimator_node calibrate surface: %s: cannot write\n", out_file.c_str());
    return kExitFailure;
  }
  std::fprintf(stderr, "calibrate surface: wrote %s\n", out_file.c_str());
  return kExitOk;
}

}  // namespace panoptes::surface_app
