// SPDX-License-Identifier: Apache-2.0
#include "panoptes/plan_io/room_file.h"

#include <cmath>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"
#include "panoptes/planner/optimizer.h"

namespace panoptes::planner {

namespace {

Eigen::Vector3d vector3(const YamlReader& reader, const std::string& key) {
  const std::vector<double> v = reader.get_doubles(key, 3);
  for (const double x : v)
    if (!std::isfinite(x)) reader.fail(key, "must be finite numbers");
  return {v[0], v[1], v[2]};
}

// A box; only regions carry a weight (issue 32: a weight on the volume or an obstacle was accepted
// and ignored).
Box read_box(const YamlReader& reader, bool weighted = false) {
  if (weighted) {
    reader.expect_only({"min", "max", "weight"});
  } else {
    reader.expect_only({"min", "max"});
  }
  Box box{vector3(reader, "min"), vector3(reader, "max")};
  if ((box.max.array() <= box.min.array()).any())
    reader.fail("max", "must be greater than min on every axis (an inverted or empty box)");
  return box;
}

double positive(const YamlReader& reader, const std::string& key, double fallback) {
  const double value = reader.get_double(key, fallback);
  if (!(value > 0.0) || !std::isfinite(value)) reader.fail(key, "must be a finite number > 0");
  return value;
}

Lens read_lens(const YamlReader& reader) {
  reader.expect_only(
      {"name", "width", "height", "focal_px", "focal_mm", "pixel_um", "min_depth_m", "max_depth_m"});
  Lens lens;
  lens.name = reader.get_string("name");
  const long long width = reader.get_int("width"), height = reader.get_int("height");
  if (width < 16 || height < 16 || width > 100000 || height > 100000)
    reader.fail("width", "image size must be 16..100000 pixels");
  double focal = 0.0;
  if (reader.has("focal_px")) {
    focal = positive(reader, "focal_px", 1.0);
  } else if (reader.has("focal_mm")) {
    focal = positive(reader, "focal_mm", 1.0) * 1000.0 / positive(reader, "pixel_um", 1.0);
  } else {
    reader.fail("focal_px", "missing: give focal_px, or focal_mm with pixel_um");
  }
  lens.intrinsics.width = static_cast<int>(width);
  lens.intrinsics.height = static_cast<int>(height);
  lens.intrinsics.fx = lens.intrinsics.fy = focal;
  lens.intrinsics.cx = 0.5 * static_cast<double>(width) - 0.5;
  lens.intrinsics.cy = 0.5 * static_cast<double>(height) - 0.5;
  lens.min_depth_m = reader.get_double("min_depth_m", 0.3);
  lens.max_depth_m = positive(reader, "max_depth_m", 12.0);
  if (!(lens.min_depth_m >= 0.0) || lens.min_depth_m >= lens.max_depth_m)
    reader.fail("min_depth_m", "must be >= 0 and below max_depth_m");
  return lens;
}

MountSurface read_mount(const YamlReader& reader) {
  reader.expect_only({"name", "corner", "u", "v"});
  MountSurface mount;
  mount.name = reader.get_string("name");
  mount.corner = vector3(reader, "corner");
  mount.edge_u = vector3(reader, "u");
  if (reader.has("v")) mount.edge_v = vector3(reader, "v");
  if (mount.edge_u.norm() <= 0.0) reader.fail("u", "must not be zero (a mount is a rectangle or a line)");
  return mount;
}

Norm read_norm(const YamlReader& reader, const std::string& key) {
  const std::string name = reader.get_string(key, "rms");
  if (name == "max") return Norm::kMax;
  if (name == "mean") return Norm::kMean;
  if (name == "rms") return Norm::kRms;
  reader.fail(key, "must be max, mean or rms (got '" + name + "')");
}

void read_metric(const YamlReader& reader, MetricOptions& metric) {
  reader.expect_only({"resolution", "over_directions", "over_planes", "over_points", "pixel_sigma",
                      "unseen_m", "k_cameras", "min_triangulation_deg"});
  const std::string model = reader.get_string("resolution", "covariance");
  if (model == "covariance") {
    metric.resolution = ResolutionModel::kCovariance;
  } else if (model == "pyramid") {
    metric.resolution = ResolutionModel::kPyramid;
  } else {
    reader.fail("resolution", "must be covariance or pyramid (got '" + model + "')");
  }
  metric.over_directions = read_norm(reader, "over_directions");
  metric.over_planes = read_norm(reader, "over_planes");
  metric.over_points = read_norm(reader, "over_points");
  metric.pixel_sigma = positive(reader, "pixel_sigma", metric.pixel_sigma);
  metric.unseen_m = positive(reader, "unseen_m", metric.unseen_m);
  const long long k = reader.get_int("k_cameras", metric.k_cameras);
  if (k < 1 || k > 64) reader.fail("k_cameras", "must be 1..64");
  metric.k_cameras = static_cast<int>(k);
  metric.min_triangulation_deg = reader.get_double("min_triangulation_deg", metric.min_triangulation_deg);
  if (!(metric.min_triangulation_deg >= 0.0 && metric.min_triangulation_deg < 90.0))
    reader.fail("min_triangulation_deg", "must be in [0, 90)");
}

void read_occlusion(const YamlReader& reader, OccluderModel& occluders) {
  reader.expect_only({"planes", "axis", "min_angle_deg", "max_angle_deg", "facing_angle_deg"});
  const long long planes = reader.get_int("planes", occluders.planes);
  if (planes < 0 || planes > 4096) reader.fail("planes", "must be 0..4096 (0: no dynamic occlusion)");
  occluders.planes = static_cast<int>(planes);
  if (reader.has("axis")) occluders.axis = vector3(reader, "axis");
  if (occluders.axis.norm() <= 0.0) reader.fail("axis", "must not be zero");
  occluders.max_angle_deg = reader.get_double("max_angle_deg", occluders.max_angle_deg);
  if (!(occluders.max_angle_deg > 0.0 && occluders.max_angle_deg <= 180.0))
    reader.fail("max_angle_deg", "must be in (0, 180]");
  occluders.min_angle_deg = reader.get_double("min_angle_deg", occluders.min_angle_deg);
  if (!(occluders.min_angle_deg >= 0.0 && occluders.min_angle_deg < occluders.max_angle_deg))
    reader.fail("min_angle_deg", "must be in [0, max_angle_deg)");
  occluders.facing_angle_deg = reader.get_double("facing_angle_deg", occluders.facing_angle_deg);
  if (!(occluders.facing_angle_deg > 0.0 && occluders.facing_angle_deg < 180.0))
    reader.fail("facing_angle_deg", "must be in (0, 180)");
}

// subject: {markers, size: [x, y, z], one_view_episode_s} and
// tracker: {publish_max_sigma_m, process_noise, epipolar_px}.
void read_tracker_model(const YamlReader& reader, TrackerModel& tracker) {
  if (reader.has("subject")) {
    const YamlReader subject = reader.child("subject");
    subject.expect_only({"markers", "size", "one_view_episode_s"});
    const long long markers = subject.get_int("markers", tracker.subject_markers);
    if (markers < 0 || markers > 100000) subject.fail("markers", "must be 0..100000");
    tracker.subject_markers = static_cast<int>(markers);
    if (subject.has("size")) tracker.subject_size = vector3(subject, "size");
    if (!(tracker.subject_size.minCoeff() > 0.0)) subject.fail("size", "must be positive in x, y and z");
    tracker.one_view_episode_s = positive(subject, "one_view_episode_s", tracker.one_view_episode_s);
  }
  if (reader.has("tracker")) {
    const YamlReader model = reader.child("tracker");
    model.expect_only({"publish_max_sigma_m", "process_noise", "epipolar_px"});
    tracker.publish_max_sigma_m = positive(model, "publish_max_sigma_m", tracker.publish_max_sigma_m);
    tracker.process_noise = positive(model, "process_noise", tracker.process_noise);
    tracker.epipolar_px = positive(model, "epipolar_px", tracker.epipolar_px);
  }
}

}  // namespace

RoomFile load_room(const std::filesystem::path& path) {
  const YAML::Node node = load_yaml_file(path);
  const YamlReader reader(path.string(), node);
  reader.expect_only({"volume", "regions", "obstacles", "mounts", "lenses", "occlusion", "metric", "samples",
                      "subject", "tracker", "objective"});
  RoomFile file;
  file.room.volume = read_box(reader.child("volume"));
  for (const YamlReader& region : reader.sequence_or_empty("regions")) {
    const Box box = read_box(region, true);
    const double weight = region.get_double("weight", 1.0);
    if (!(weight >= 0.0) || !std::isfinite(weight)) region.fail("weight", "must be a finite number >= 0");
    file.room.regions.push_back({box, weight});
  }
  for (const YamlReader& obstacle : reader.sequence_or_empty("obstacles"))
    file.room.obstacles.push_back(read_box(obstacle));
  for (const YamlReader& mount : reader.sequence_or_empty("mounts"))
    file.room.mounts.push_back(read_mount(mount));
  if (file.room.mounts.empty())
    reader.fail("mounts", "the room has no mounting surface: list walls, ceiling or trusses");
  for (const YamlReader& lens : reader.sequence("lenses")) file.room.lenses.push_back(read_lens(lens));
  if (file.room.lenses.empty()) reader.fail("lenses", "list at least one lens");
  if (reader.has("occlusion")) read_occlusion(reader.child("occlusion"), file.occluders);
  if (reader.has("metric")) read_metric(reader.child("metric"), file.metric);
  read_tracker_model(reader, file.tracker);
  if (reader.has("objective")) {
    const auto objective = objective_from_name(reader.get_string("objective"));
    if (!objective) reader.fail("objective", "must be q or tracker_rmse");
    file.objective = *objective;
  }
  if (reader.has("samples")) {
    const YamlReader samples = reader.child("samples");
    samples.expect_only({"points", "directions", "seed"});
    const long long points = samples.get_int("points", file.sample_points);
    const long long directions = samples.get_int("directions", file.sample_directions);
    if (points < 1 || points > 1000000) samples.fail("points", "must be 1..1000000");
    if (directions < 1 || directions > 4096) samples.fail("directions", "must be 1..4096");
    file.sample_points = static_cast<int>(points);
    file.sample_directions = static_cast<int>(directions);
    file.sample_seed = static_cast<std::uint64_t>(samples.get_int("seed", 1));
  }
  return file;
}

}  // namespace panoptes::planner
