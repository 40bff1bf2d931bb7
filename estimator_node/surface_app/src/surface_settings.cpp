// SPDX-License-Identifier: Apache-2.0
#include "panoptes/surface_app/surface_settings.h"

#include <cmath>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"

namespace panoptes::surface_app {
namespace {

Eigen::Vector3d read_vector3(const YamlReader& reader, const std::string& key) {
  const auto values = reader.get_doubles(key, 3);
  Eigen::Vector3d v(values[0], values[1], values[2]);
  if (!v.allFinite()) reader.fail(key, "must be finite numbers");
  return v;
}

double positive(const YamlReader& reader, const std::string& key, double fallback) {
  const double value = reader.get_double(key, fallback);
  if (!(value > 0.0) || !std::isfinite(value)) reader.fail(key, "must be a finite number > 0");
  return value;
}

// origin, u_axis, v_axis: the axes are normalised and must be perpendicular.
void read_plane(const YamlReader& reader, surface::SurfacePlane& plane) {
  reader.expect_only({"origin", "u_axis", "v_axis"});
  plane.origin = read_vector3(reader, "origin");
  const Eigen::Vector3d u = read_vector3(reader, "u_axis");
  const Eigen::Vector3d v = read_vector3(reader, "v_axis");
  if (u.norm() < 1e-9) reader.fail("u_axis", "must not be zero");
  if (v.norm() < 1e-9) reader.fail("v_axis", "must not be zero");
  plane.u_axis = u.normalized();
  plane.v_axis = v.normalized();
  if (std::abs(plane.u_axis.dot(plane.v_axis)) > 1e-6)
    reader.fail("v_axis", "must be perpendicular to u_axis (the surface's axes are orthonormal)");
}

// Nine numbers, row-major, or three rows of three.
Eigen::Matrix3d read_homography(const YamlReader& reader) {
  const YAML::Node& node = reader.node()["homography"];
  std::vector<double> values;
  if (node.IsSequence() && node.size() == 3 && node[0].IsSequence()) {
    for (const auto& row : reader.get_double_rows("homography", 3))
      values.insert(values.end(), row.begin(), row.end());
  } else {
    values = reader.get_doubles("homography", 9);
  }
  Eigen::Matrix3d H;
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c)
      H(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = values[3 * r + c];
  return H;
}

void read_tracker(const YamlReader& reader, surface::SurfaceTrackerOptions& o) {
  reader.expect_only({"pixel_sigma", "jerk_noise", "initial_speed_sigma", "initial_accel_sigma", "gate_chi2",
                      "confirm_updates", "end_after_ms", "camera_wait_ms", "duplicate_distance_m"});
  o.pixel_sigma = positive(reader, "pixel_sigma", o.pixel_sigma);
  o.jerk_noise = positive(reader, "jerk_noise", o.jerk_noise);
  o.initial_speed_sigma = positive(reader, "initial_speed_sigma", o.initial_speed_sigma);
  o.initial_accel_sigma = positive(reader, "initial_accel_sigma", o.initial_accel_sigma);
  o.gate_chi2 = positive(reader, "gate_chi2", o.gate_chi2);
  const long long confirm = reader.get_int("confirm_updates", o.confirm_updates);
  if (confirm < 1 || confirm > 1000) reader.fail("confirm_updates", "must be an integer in [1, 1000]");
  o.confirm_updates = static_cast<int>(confirm);
  const double end_after_ms = positive(reader, "end_after_ms", static_cast<double>(o.end_after_ns) * 1e-6);
  if (end_after_ms > 10000.0) reader.fail("end_after_ms", "must be at most 10000");
  o.end_after_ns = static_cast<TimeNs>(std::llround(end_after_ms * 1e6));
  const double camera_wait_ms =
      positive(reader, "camera_wait_ms", static_cast<double>(o.camera_wait_ns) * 1e-6);
  if (camera_wait_ms > 60000.0) reader.fail("camera_wait_ms", "must be at most 60000");
  o.camera_wait_ns = static_cast<TimeNs>(std::llround(camera_wait_ms * 1e6));
  const double duplicate = reader.get_double("duplicate_distance_m", o.duplicate_distance_m);
  if (!(duplicate >= 0.0) || !std::isfinite(duplicate))
    reader.fail("duplicate_distance_m", "must be a finite number >= 0");
  o.duplicate_distance_m = duplicate;
}

}  // namespace

int SurfaceSetup::camera_index(const std::string& id) const {
  for (std::size_t i = 0; i < camera_ids.size(); ++i)
    if (camera_ids[i] == id) return static_cast<int>(i);
  return -1;
}

SurfaceSettings read_surface_settings(const YamlReader& reader) {
  reader.expect_only({"size", "plane", "cameras", "tracker", "latency_window_ms"});
  SurfaceSettings settings;
  settings.file = reader.file();
  const auto size = reader.get_doubles("size", 2);
  if (!(size[0] > 0.0 && size[1] > 0.0 && std::isfinite(size[0]) && std::isfinite(size[1])))
    reader.fail("size", "must be two finite lengths > 0 m (width along u, height along v)");
  settings.plane.size = Eigen::Vector2d(size[0], size[1]);
  if (reader.has("plane")) {
    read_plane(reader.child("plane"), settings.plane);
    settings.has_plane = true;
  }
  for (const YamlReader& camera : reader.sequence_or_empty("cameras")) {
    camera.expect_only({"id", "homography"});
    SurfaceCameraSetting setting;
    setting.id = camera.get_string("id");
    if (setting.id.empty()) camera.fail("id", "must not be empty");
    for (const auto& other : settings.cameras)
      if (other.id == setting.id) camera.fail("id", "duplicate camera '" + setting.id + "'");
    setting.key = camera.key_path();
    if (camera.has("homography")) setting.homography = read_homography(camera);
    if (!setting.homography && !settings.has_plane)
      camera.fail("homography", "missing: without a surface.plane every camera needs its homography");
    settings.cameras.push_back(std::move(setting));
  }
  if (settings.cameras.empty() && !settings.has_plane)
    reader.fail("plane", "missing: give a plane (with --calibration) or a homography per camera");
  if (reader.has("tracker")) read_tracker(reader.child("tracker"), settings.tracker);
  settings.latency_window_ms = reader.get_double("latency_window_ms", settings.latency_window_ms);
  if (!(settings.latency_window_ms >= 0.0 && settings.latency_window_ms <= 10000.0))
    reader.fail("latency_window_ms", "must be a number in [0, 10000]");
  return settings;
}

std::optional<SurfaceSettings> load_surface_settings(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  const YamlReader reader(path.string(), root);
  if (!root.IsMap() || !reader.has("surface")) return std::nullopt;
  return read_surface_settings(reader.child("surface"));
}

SurfaceSetup build_surface(const SurfaceSettings& settings, const SystemCalibration* calibration,
                           const std::string& calibration_file) {
  std::vector<SurfaceCameraSetting> cameras = settings.cameras;
  if (cameras.empty() && calibration != nullptr) {
    for (const auto& camera : calibration->cameras)
      if (camera.T_world_cam) cameras.push_back({camera.id, std::nullopt, "surface.plane"});
  }
  if (cameras.empty())
    throw ConfigError(settings.file, "surface.plane",
                      "no camera to map it: give --calibration with posed cameras, or surface.cameras");
  SurfaceSetup setup;
  std::vector<surface::ImageToSurface> mappings;
  for (const auto& camera : cameras) {
    try {
      if (camera.homography) {
        mappings.push_back(surface::ImageToSurface::from_homography(*camera.homography));
      } else {
        const CameraCalibration* found = calibration != nullptr ? calibration->find(camera.id) : nullptr;
        if (found == nullptr || !found->T_world_cam)
          throw ConfigError(
              settings.file, camera.key,
              "camera '" + camera.id + "' has no homography and no pose in " +
                  (calibration_file.empty() ? "a calibration (give --calibration)" : calibration_file));
        mappings.push_back(surface::ImageToSurface::from_plane(found->model(), settings.plane));
      }
    } catch (const std::invalid_argument& error) {
      const std::string key = camera.homography ? camera.key + ".homography" : "surface.plane";
      const std::string origin = camera.homography ? "" : " (camera pose from " + calibration_file + ")";
      throw ConfigError(settings.file, key, "camera '" + camera.id + "': " + error.what() + origin);
    }
    setup.camera_ids.push_back(camera.id);
  }
  setup.tracker =
      std::make_unique<surface::SurfaceTracker>(settings.plane, std::move(mappings), settings.tracker);
  return setup;
}

}  // namespace panoptes::surface_app
