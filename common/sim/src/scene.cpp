// SPDX-License-Identifier: Apache-2.0
// Scene files (docs/simulator.md): cameras, analytic markers, TRC playback and rigid bodies.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "chain_motion.h"
#include "motion.h"
#include "panoptes/calibration_file.h"
#include "panoptes/config.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/geometry.h"
#include "panoptes/landmarks_file.h"
#include "panoptes/simulator.h"
#include "random.h"

namespace panoptes {

namespace {

using sim::read_vector3;
using sim::reject_unknown_keys;

constexpr double kDefaultMarkerRadius = 0.007;  // 14 mm spheres, the common passive marker size
constexpr double kDefaultDurationS = 10.0;

enum class TrcLoop { kNone, kWrap, kPingPong };

struct TrcSource {
  TrcData data;
  std::vector<std::size_t> columns;  // file marker indices, in scene order
  Eigen::Matrix3d R_world_file = Eigen::Matrix3d::Identity();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  TrcLoop loop = TrcLoop::kPingPong;
  double start_s = 0.0;
  double turnaround_s = 0.0;
  double radius = kDefaultMarkerRadius;
  // Self-occlusion by the body (trc.occlusion); 0: off.
  double facing_angle_rad = 0.0;
  // trc.hide: a marker hidden from every camera over [from_s, to_s) of scene time (a hand over
  // it, a subject turned away for a while); `marker` indexes `columns`.
  struct Hidden {
    std::size_t marker = 0;
    double from_s = 0.0;
    double to_s = 0.0;
  };
  std::vector<Hidden> hidden;
};

struct MarkerSpec {
  std::string name;
  double radius = kDefaultMarkerRadius;
  sim::Path path;
  // `pen_down`: [start, end] intervals (s) in which the marker exists (a laser spot that is on);
  // empty: always.
  std::vector<std::pair<double, double>> pen_down;

  bool exists_at(double t_s) const {
    if (pen_down.empty()) return true;
    return std::any_of(pen_down.begin(), pen_down.end(),
                       [&](const auto& interval) { return t_s >= interval.first && t_s < interval.second; });
  }
};

struct BodySpec {
  std::string name;
  std::vector<Eigen::Vector3d> markers;
  double marker_radius = kDefaultMarkerRadius;
  sim::Path path;
  sim::Rotation rotation;
  BodyKind kind = BodyKind::kPassive;
  // occlusion: a marker is hidden from cameras more than facing_angle away from its normal: the
  // body-frame `normal` if given, else outward from the markers' centroid. 0: never hidden.
  double facing_angle_rad = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

// A moving camera's rig (inside-out tracking, docs/inside_out.md): the camera's pose keys give its
// mount on the rig, and the rig moves along `path` turning by `rotation`.
struct RigSpec {
  std::string name;
  sim::Path path;
  sim::Rotation rotation;
  std::vector<Eigen::Vector3d> markers;  // carried by the rig (rig frame): what fixed cameras see of it
};

RigSpec read_rig(const YamlReader& camera, const std::string& camera_id) {
  const YamlReader rig_reader = camera.child("rig");
  reject_unknown_keys(rig_reader, {"name", "path", "rotation", "markers"});
  RigSpec rig{rig_reader.get_string("name", camera_id),
              sim::read_path(rig_reader.child("path")),
              rig_reader.has("rotation") ? sim::read_rotation(rig_reader.child("rotation")) : sim::Rotation{},
              {}};
  if (rig.name.empty()) rig_reader.fail("name", "must not be empty");
  if (rig_reader.has("markers")) {
    for (const auto& row : rig_reader.get_double_rows("markers", 3)) {
      if (!std::isfinite(row[0]) || !std::isfinite(row[1]) || !std::isfinite(row[2]))
        rig_reader.fail("markers", "expected finite numbers");
      rig.markers.emplace_back(row[0], row[1], row[2]);
    }
  }
  return rig;
}

// Reads a camera key from the camera's own map, falling back to the scene's `defaults`, so that
// error messages name whichever map the value actually came from.
class CameraKeys {
 public:
  CameraKeys(const YamlReader& camera, const std::optional<YamlReader>& defaults)
      : camera_(camera), defaults_(defaults) {}

  const YamlReader& source(const std::string& key) const {
    if (camera_.has(key) || !defaults_ || !defaults_->has(key)) return camera_;
    return *defaults_;
  }
  bool has(const std::string& key) const { return source(key).has(key); }
  double number(const std::string& key, double fallback) const {
    const double value = source(key).get_double(key, fallback);
    if (!std::isfinite(value)) source(key).fail(key, "expected a finite number");
    return value;
  }
  double non_negative(const std::string& key, double fallback) const {
    const double value = number(key, fallback);
    if (value < 0.0) source(key).fail(key, "must be >= 0");
    return value;
  }
  int positive_int(const std::string& key) const {
    const YamlReader& reader = source(key);
    const long long value = reader.get_int(key);
    if (value <= 0 || value > 1'000'000) reader.fail(key, "expected a positive integer");
    return static_cast<int>(value);
  }

 private:
  const YamlReader& camera_;
  const std::optional<YamlReader>& defaults_;
};

#define PANOPTES_SIM_CAMERA_KEYS                                                                           \
  "width", "height", "K", "distortion", "T_world_cam", "look_at", "rate", "phase", "clock_offset",         \
      "exposure", "pixel_noise", "centroid_noise", "background", "blob_peak", "blob_min_sigma", "dropout", \
      "bits", "false_blobs", "merge_distance", "latency", "latency_jitter", "late_fraction", "late_delay"

RigidTransform read_pose(const YamlReader& camera, const std::optional<YamlReader>& defaults) {
  // The pose keys are one group: a camera's own pose replaces the defaults' whichever form it takes.
  const bool own = camera.has("T_world_cam") || camera.has("look_at");
  const YamlReader& reader = own || !defaults ? camera : *defaults;
  if (reader.has("T_world_cam") && reader.has("look_at")) {
    reader.fail("look_at", "give either T_world_cam or look_at, not both");
  }
  if (reader.has("look_at")) {
    const YamlReader look = reader.child("look_at");
    reject_unknown_keys(look, {"eye", "target", "up"});
    const Eigen::Vector3d eye = read_vector3(look, "eye");
    const Eigen::Vector3d target = read_vector3(look, "target");
    const Eigen::Vector3d up = read_vector3(look, "up", Eigen::Vector3d::UnitZ());
    if ((target - eye).norm() < 1e-9) look.fail("target", "must differ from eye");
    return look_at(eye, target, up);
  }
  if (!reader.has("T_world_cam")) camera.fail("T_world_cam", "missing key (or give look_at)");
  const YamlReader pose = reader.child("T_world_cam");
  reject_unknown_keys(pose, {"q", "t"});
  return RigidTransform{sim::read_quaternion(pose, "q"), read_vector3(pose, "t")};
}

// `bump: {at: s, rotation: [rx, ry, rz] (rad, a rotation vector), translation: [x, y, z] (m)}`,
// both in the camera's frame.
void read_bump(const YamlReader& bump, SimCameraConfig& config) {
  reject_unknown_keys(bump, {"at", "rotation", "translation"});
  const double at_s = bump.get_double("at");
  if (!(at_s >= 0.0) || !std::isfinite(at_s)) bump.fail("at", "must be a finite time >= 0 s");
  const Eigen::Vector3d rotation = read_vector3(bump, "rotation", Eigen::Vector3d::Zero());
  const Eigen::Vector3d translation = read_vector3(bump, "translation", Eigen::Vector3d::Zero());
  config.bumped = true;
  config.bump_at_ns = seconds_to_ns(at_s);
  const double angle = rotation.norm();
  config.bump.q = angle > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation / angle))
                              : Eigen::Quaterniond::Identity();
  config.bump.t = translation;
}

// A unit vector drawn from (scene seed, camera index): the direction of a drift whose axis is not
// given (`drift` in `defaults` gives every camera its own).
Eigen::Vector3d random_axis(std::uint64_t seed, std::size_t camera_index) {
  sim::Rng random(sim::hash_key(seed, 0xD71F7ULL, camera_index));
  const Eigen::Vector3d v(random.normal(), random.normal(), random.normal());
  return v.norm() > 1e-9 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX();
}

// `drift: {rate: deg/min, axis: [x, y, z] (camera frame; absent: drawn per camera), translation:
// [x, y, z] (mm/min, camera frame), from: s}`. The axis is left zero when absent (drawn later,
// when the seed and the camera's index are known).
void set_drift(SimCameraConfig& config, TimeNs from_ns, double degrees_per_minute,
               const Eigen::Vector3d& axis, const Eigen::Vector3d& millimetres_per_minute) {
  config.drifting = true;
  config.drift_from_ns = from_ns;
  config.drift_axis = axis.norm() > 0.0 ? Eigen::Vector3d(axis.normalized()) : Eigen::Vector3d::Zero();
  config.drift_rate_rad_s = degrees_per_minute * std::numbers::pi / 180.0 / 60.0;
  config.drift_velocity_m_s = millimetres_per_minute * 1e-3 / 60.0;
}

void read_drift(const YamlReader& drift, SimCameraConfig& config) {
  reject_unknown_keys(drift, {"rate", "axis", "translation", "from"});
  const double rate = drift.get_double("rate");
  if (!(rate >= 0.0) || !std::isfinite(rate)) drift.fail("rate", "must be a finite rate >= 0 deg/min");
  const double from_s = drift.get_double("from", 0.0);
  if (!(from_s >= 0.0) || !std::isfinite(from_s)) drift.fail("from", "must be a finite time >= 0 s");
  const Eigen::Vector3d axis = read_vector3(drift, "axis", Eigen::Vector3d::Zero());
  if (drift.has("axis") && !(axis.norm() > 0.0)) drift.fail("axis", "must not be zero");
  set_drift(config, seconds_to_ns(from_s), rate, axis,
            read_vector3(drift, "translation", Eigen::Vector3d::Zero()));
}

SimCameraConfig read_camera(const YamlReader& camera, const std::optional<YamlReader>& defaults) {
  reject_unknown_keys(camera, {"id", "rig", "bump", "drift", PANOPTES_SIM_CAMERA_KEYS});
  const CameraKeys keys(camera, defaults);
  SimCameraConfig config;
  CameraCalibration& calibration = config.calibration;
  calibration.id = camera.get_string("id");
  if (calibration.id.empty()) camera.fail("id", "must not be empty");
  CameraIntrinsics& intrinsics = calibration.intrinsics;
  intrinsics.width = keys.positive_int("width");
  intrinsics.height = keys.positive_int("height");
  {
    const YamlReader& reader = keys.source("K");
    const std::vector<double> K = reader.get_doubles("K", 4);
    if (!(K[0] > 0.0 && K[1] > 0.0) || !std::isfinite(K[2]) || !std::isfinite(K[3])) {
      reader.fail("K", "expected [fx, fy, cx, cy] with positive focal lengths");
    }
    intrinsics.fx = K[0];
    intrinsics.fy = K[1];
    intrinsics.cx = K[2];
    intrinsics.cy = K[3];
  }
  if (keys.has("distortion")) {
    const YamlReader& reader = keys.source("distortion");
    const std::vector<double> distortion = reader.get_doubles("distortion", 5);
    for (std::size_t i = 0; i < 5; ++i) {
      if (!std::isfinite(distortion[i])) reader.fail("distortion", "expected finite numbers");
      intrinsics.distortion[i] = distortion[i];
    }
  }
  // A camera on a rig is mounted as its own pose keys say (none: at the rig's origin, looking
  // along the rig's z); the defaults' pose is a fixed camera's, not a mount.
  const bool on_rig = camera.has("rig");
  calibration.T_world_cam = on_rig && !camera.has("T_world_cam") && !camera.has("look_at")
                                ? RigidTransform{}
                                : read_pose(camera, on_rig ? std::nullopt : defaults);
  calibration.moving = on_rig;
  if (camera.has("bump")) read_bump(camera.child("bump"), config);
  if (camera.has("drift")) {
    read_drift(camera.child("drift"), config);
  } else if (defaults && defaults->has("drift")) {
    read_drift(defaults->child("drift"), config);
  }

  config.rate_hz = keys.number("rate", config.rate_hz);
  if (!(config.rate_hz > 0.0)) keys.source("rate").fail("rate", "must be > 0 Hz");
  config.phase_ns = seconds_to_ns(keys.number("phase", 0.0));
  config.clock_offset_ns = seconds_to_ns(keys.number("clock_offset", 0.0));
  config.exposure_ns = seconds_to_ns(keys.non_negative("exposure", ns_to_seconds(config.exposure_ns)));
  config.pixel_noise_dn = keys.non_negative("pixel_noise", config.pixel_noise_dn);
  config.centroid_noise_px = keys.non_negative("centroid_noise", config.centroid_noise_px);
  config.background_dn = keys.non_negative("background", config.background_dn);
  config.blob_peak_dn = keys.non_negative("blob_peak", config.blob_peak_dn);
  config.blob_min_sigma_px = keys.number("blob_min_sigma", config.blob_min_sigma_px);
  if (!(config.blob_min_sigma_px > 0.0))
    keys.source("blob_min_sigma").fail("blob_min_sigma", "must be > 0 px");
  config.dropout_probability = keys.non_negative("dropout", config.dropout_probability);
  if (config.dropout_probability > 1.0)
    keys.source("dropout").fail("dropout", "must be a probability in [0, 1]");
  if (keys.has("bits")) {
    const YamlReader& reader = keys.source("bits");
    const long long bits = reader.get_int("bits");
    if (bits != 8 && bits != 10 && bits != 12 && bits != 16) reader.fail("bits", "expected 8, 10, 12 or 16");
    config.bits = static_cast<int>(bits);
  }
  // Poisson counts are drawn by summing exponential gaps, whose cost grows with the mean.
  constexpr double kMaxFalseBlobs = 10'000.0;
  config.false_blobs = keys.non_negative("false_blobs", config.false_blobs);
  if (config.false_blobs > kMaxFalseBlobs)
    keys.source("false_blobs").fail("false_blobs", "must be at most 10000 per frame");
  config.merge_distance_px = keys.non_negative("merge_distance", config.merge_distance_px);
  config.latency_ns = seconds_to_ns(keys.non_negative("latency", ns_to_seconds(config.latency_ns)));
  config.latency_jitter_ns =
      seconds_to_ns(keys.non_negative("latency_jitter", ns_to_seconds(config.latency_jitter_ns)));
  config.late_fraction = keys.non_negative("late_fraction", config.late_fraction);
  if (config.late_fraction > 1.0)
    keys.source("late_fraction").fail("late_fraction", "must be a probability in [0, 1]");
  if (keys.has("late_delay")) {
    const YamlReader& reader = keys.source("late_delay");
    const std::vector<double> delay = reader.get_doubles("late_delay", 2);
    if (!(std::isfinite(delay[0]) && std::isfinite(delay[1]) && delay[0] >= 0.0 && delay[1] >= delay[0])) {
      reader.fail("late_delay", "expected [min, max] seconds with 0 <= min <= max");
    }
    config.late_delay_min_ns = seconds_to_ns(delay[0]);
    config.late_delay_max_ns = seconds_to_ns(delay[1]);
  }
  return config;
}

double read_marker_radius(const YamlReader& reader, const std::string& key) {
  const double radius = reader.get_double(key, kDefaultMarkerRadius);
  if (!(radius > 0.0) || !std::isfinite(radius)) reader.fail(key, "must be > 0 m");
  return radius;
}

// "${NAME}" is replaced by the environment variable NAME, so scenes can point at data kept outside
// the repository without hard-coding a machine's layout.
std::string expand_environment(const YamlReader& reader, const std::string& key, const std::string& text) {
  std::string result;
  std::size_t position = 0;
  while (true) {
    const std::size_t open = text.find("${", position);
    if (open == std::string::npos) break;
    const std::size_t close = text.find('}', open);
    if (close == std::string::npos) reader.fail(key, "unterminated '${' in '" + text + "'");
    const std::string name = text.substr(open + 2, close - open - 2);
    const char* value = std::getenv(name.c_str());
    if (value == nullptr) reader.fail(key, "environment variable '" + name + "' is not set");
    result += text.substr(position, open - position);
    result += value;
    position = close + 1;
  }
  return result + text.substr(position);
}

TrcLoop read_trc_loop(const YamlReader& reader) {
  if (!reader.has("loop")) return TrcLoop::kPingPong;
  const std::string text = reader.get_string("loop");
  if (text == "pingpong" || text == "true" || text == "yes" || text == "on") return TrcLoop::kPingPong;
  if (text == "wrap") return TrcLoop::kWrap;
  if (text == "none" || text == "false" || text == "no" || text == "off") return TrcLoop::kNone;
  reader.fail("loop", "expected pingpong (or true), wrap, or none (or false); got '" + text + "'");
}

// `hide: [{marker: NAME, from: S, to: S}, ...]`: NAME one of the markers the source plays.
void read_trc_hide(const YamlReader& reader, const std::filesystem::path& file, TrcSource& source) {
  for (const YamlReader& entry : reader.sequence_or_empty("hide")) {
    reject_unknown_keys(entry, {"marker", "from", "to"});
    const std::string name = entry.get_string("marker");
    const auto played = std::find_if(source.columns.begin(), source.columns.end(), [&](std::size_t column) {
      return source.data.marker_names[column] == name;
    });
    if (played == source.columns.end()) {
      entry.fail("marker", "no marker '" + name + "' played from " + file.string());
    }
    TrcSource::Hidden hidden{static_cast<std::size_t>(played - source.columns.begin()),
                             entry.get_double("from"), entry.get_double("to")};
    if (!(hidden.from_s >= 0.0)) entry.fail("from", "must be a scene time >= 0 s");
    if (!(hidden.to_s > hidden.from_s)) entry.fail("to", "must be after 'from'");
    source.hidden.push_back(hidden);
  }
}

TrcSource read_trc(const YamlReader& reader, const std::filesystem::path& base_dir,
                   std::vector<std::string>& names) {
  reject_unknown_keys(reader, {"file", "offset", "up_axis", "loop", "turnaround", "markers", "radius",
                               "start", "prefix", "occlusion", "hide"});
  TrcSource source;
  std::filesystem::path file = expand_environment(reader, "file", reader.get_string("file"));
  if (file.is_relative()) file = base_dir / file;
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) {
    reader.fail("file", "marker file '" + file.lexically_normal().string() + "' not found");
  }
  // The same playback for C3D files (docs/simulator.md, "Marker files"); units follow POINT:UNITS.
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  source.data = extension == ".c3d" ? load_c3d(file) : load_trc(file);
  source.offset = read_vector3(reader, "offset", Eigen::Vector3d::Zero());
  const std::string up_axis = reader.get_string("up_axis", "y");
  if (up_axis == "y") {
    // A +90 degree turn about x: file (x, y, z) -> world (x, -z, y). Keeps the frame right-handed
    // and the file's x (usually the walking direction) as world x.
    source.R_world_file << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  } else if (up_axis == "x") {
    // A cyclic turn: file (x, y, z) -> world (y, z, x), so that the file's up axis is our z.
    source.R_world_file << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  } else if (up_axis != "z") {
    reader.fail("up_axis", "expected x, y or z, got '" + up_axis + "'");
  }
  source.loop = read_trc_loop(reader);
  const double length = source.data.times_s.back() - source.data.times_s.front();
  source.start_s = reader.get_double("start", 0.0);
  if (!(source.start_s >= 0.0 && source.start_s <= length)) {
    reader.fail("start", "must lie within the recording, [0, " + std::to_string(length) + "] s");
  }
  source.turnaround_s = reader.get_double("turnaround", 0.0);
  if (!(source.turnaround_s >= 0.0 && source.turnaround_s <= 2.0 * length)) {
    reader.fail("turnaround", "must be in [0, twice the recording's length] s");
  }
  if (source.turnaround_s > 0.0 && source.loop != TrcLoop::kPingPong) {
    reader.fail("turnaround", "applies only to loop: pingpong");
  }
  source.radius = read_marker_radius(reader, "radius");
  if (reader.has("occlusion")) {
    const YamlReader occlusion = reader.child("occlusion");
    reject_unknown_keys(occlusion, {"facing_angle"});
    const double degrees = occlusion.get_double("facing_angle");
    if (!(degrees > 0.0 && degrees <= 180.0)) occlusion.fail("facing_angle", "must be in (0, 180] degrees");
    source.facing_angle_rad = degrees * std::numbers::pi / 180.0;
  }
  const std::string prefix = reader.get_string("prefix", "trc/");
  if (reader.has("markers")) {
    const YAML::Node list = reader.node()["markers"];
    if (!list.IsSequence()) reader.fail("markers", "expected a list of marker names");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string key = "markers[" + std::to_string(i) + "]";
      if (!list[i].IsScalar()) reader.fail(key, "expected a marker name");
      const std::string name = list[i].Scalar();
      const auto& all = source.data.marker_names;
      const auto it = std::find(all.begin(), all.end(), name);
      if (it == all.end()) reader.fail(key, "no marker '" + name + "' in " + file.string());
      source.columns.push_back(static_cast<std::size_t>(it - all.begin()));
    }
  } else {
    for (std::size_t i = 0; i < source.data.marker_count(); ++i) source.columns.push_back(i);
  }
  for (std::size_t column : source.columns) names.push_back(prefix + source.data.marker_names[column]);
  read_trc_hide(reader, file, source);
  return source;
}

// File time (s after the first frame) that ping-pong playback shows at scene time t. Playing
// backwards on odd passes keeps positions continuous, unlike wrapping. With a turnaround b > 0 the
// playback clock also keeps its rate continuous: it decelerates uniformly to a stop over the last
// b/2 s before each end of the recording and accelerates away over the first b/2 s after it,
// instead of reversing instantly (which would need infinite acceleration).
//
// In u (scene time plus an offset) one cycle is a triangle wave between -b/4 and span + b/4 whose
// corners are replaced by parabolas over |u - corner| <= b/2; they touch 0 and span and meet the
// straight parts with slope +-1.
double pingpong_file_time(double t, double start, double span, double turnaround) {
  const double b = turnaround;
  const double half = b / 2.0;
  const double quarter = b / 4.0;
  const double pass = span + half;  // u from a trough to the next peak
  const double period = 2.0 * pass;
  // u at t = 0: the rising pass shows `start` there.
  double u0 = start + quarter;
  if (b > 0.0 && start < quarter) u0 = std::sqrt(start * b);
  if (b > 0.0 && start > span - quarter) u0 = pass - std::sqrt((span - start) * b);
  double u = std::fmod(std::fmod(t + u0, period) + period, period);
  if (u > pass) u = period - u;  // the falling pass mirrors the rising one
  if (u < half) return u * u / b;
  if (u > pass - half) return span - (u - pass) * (u - pass) / b;
  return u - quarter;
}

// The TRC markers belong to one body, roughly a vertical cylinder: each marker faces away from the
// vertical line through the centroid of the valid markers, horizontally. A marker on that line
// has no normal and is never hidden.
void add_body_normals(const TrcSource& source, std::vector<MarkerTruth>& out, std::size_t first) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  std::size_t valid = 0;
  for (std::size_t i = 0; i < source.columns.size(); ++i) {
    if (!out[first + i].valid) continue;
    centroid += out[first + i].p.head<2>();
    ++valid;
  }
  if (valid == 0) return;
  centroid /= static_cast<double>(valid);
  constexpr double kOnAxisM = 1e-6;
  for (std::size_t i = 0; i < source.columns.size(); ++i) {
    MarkerTruth& truth = out[first + i];
    if (!truth.valid) continue;
    const Eigen::Vector2d outward = truth.p.head<2>() - centroid;
    if (outward.norm() < kOnAxisM) continue;
    truth.normal << outward.normalized(), 0.0;
    truth.facing_angle_rad = source.facing_angle_rad;
  }
}

// Fills `out[first + i]` for every selected TRC marker at scene time t_s.
void sample_trc(const TrcSource& source, double t_s, std::vector<MarkerTruth>& out, std::size_t first) {
  const TrcData& data = source.data;
  const auto& times = data.times_s;
  const double t0 = times.front();
  const double span = times.back() - t0;
  double local = t_s + source.start_s;  // seconds since the first frame
  bool inside = true;
  if (span <= 0.0) {
    local = 0.0;
  } else if (source.loop == TrcLoop::kNone) {
    // A nanosecond of slack: scene times converted from ns rarely land exactly on a file time.
    constexpr double kSlack = 1e-9;
    inside = local >= -kSlack && local <= span + kSlack;
    local = std::clamp(local, 0.0, span);
  } else if (source.loop == TrcLoop::kPingPong) {
    local = pingpong_file_time(t_s, source.start_s, span, source.turnaround_s);
  } else {
    // One frame interval after the last frame holds it, so the wrap never interpolates across
    // the jump back to the first frame.
    const double period = span + 1.0 / data.data_rate_hz;
    local = std::min(std::fmod(std::fmod(local, period) + period, period), span);
  }
  local += t0;

  std::size_t frame = 0;
  double s = 0.0;
  if (times.size() > 1) {
    const auto upper = std::upper_bound(times.begin(), times.end(), local);
    frame = std::min<std::size_t>(
        static_cast<std::size_t>(std::max<std::ptrdiff_t>(upper - times.begin() - 1, 0)), times.size() - 2);
    s = std::clamp((local - times[frame]) / (times[frame + 1] - times[frame]), 0.0, 1.0);
    // Snap to a sample so a time on (or within rounding of) a frame needs only that frame.
    constexpr double kSnap = 1e-9;
    if (s > 1.0 - kSnap) {
      ++frame;
      s = 0.0;
    } else if (s < kSnap) {
      s = 0.0;
    }
  }
  for (std::size_t i = 0; i < source.columns.size(); ++i) {
    MarkerTruth& truth = out[first + i];
    const std::size_t column = source.columns[i];
    bool valid = inside && data.is_valid(frame, column);
    Eigen::Vector3d p = data.position(frame, column);
    if (s > 0.0) {
      valid = valid && data.is_valid(frame + 1, column);
      p = (1.0 - s) * p + s * data.position(frame + 1, column);
    }
    truth.valid = valid;
    truth.p = valid ? Eigen::Vector3d(source.R_world_file * p + source.offset) : Eigen::Vector3d::Zero();
  }
  if (source.facing_angle_rad > 0.0) add_body_normals(source, out, first);
  // After the normals: a hidden marker still belongs to the body whose axis places the others'.
  for (const TrcSource::Hidden& hidden : source.hidden) {
    if (t_s < hidden.from_s || t_s >= hidden.to_s) continue;
    MarkerTruth& truth = out[first + hidden.marker];
    truth.valid = false;
    truth.p = Eigen::Vector3d::Zero();
  }
}

}  // namespace

struct Scene::Impl {
  std::string file;
  std::uint64_t seed = 0;
  TimeNs duration_ns = 0;
  std::vector<SimCameraConfig> cameras;
  std::vector<MarkerSpec> markers;
  std::vector<TrcSource> trcs;  // `trc:`, one or a list
  std::vector<BodySpec> bodies;
  std::vector<sim::ChainSpec> chains;
  std::vector<std::string> marker_names;
  std::vector<double> marker_radii;
  std::vector<std::optional<RigSpec>> camera_rigs;  // per camera
  std::vector<LandmarkGroup> landmarks;

  void parse(const YamlReader& root, const std::filesystem::path& base_dir);

 private:
  // parse()'s steps, in the order the markers are numbered (markers_at fills them so).
  void parse_cameras(const YamlReader& root);
  void parse_markers(const YamlReader& root, std::set<std::string>& names);
  void parse_landmarks(const YamlReader& root, std::set<std::string>& names);
  void parse_trc(const YamlReader& root, const std::filesystem::path& base_dir, std::set<std::string>& names);
  void parse_bodies(const YamlReader& root, std::set<std::string>& names, std::set<std::string>& body_names);
  void add_rig_marker_names(const YamlReader& root, std::set<std::string>& names);
  void parse_chains(const YamlReader& root, std::set<std::string>& names, std::set<std::string>& body_names);
  // A marker's name, unique among `names`, and its radius.
  void add_marker_name(std::set<std::string>& names, const YamlReader& reader, const std::string& key,
                       const std::string& name, double radius);
};

void Scene::Impl::parse(const YamlReader& root, const std::filesystem::path& base_dir) {
  reject_unknown_keys(root, {"seed", "duration", "description", "defaults", "cameras", "markers", "trc",
                             "bodies", "landmarks", "chains"});
  seed = static_cast<std::uint64_t>(root.get_int("seed", 0));
  const double duration_s = root.get_double("duration", kDefaultDurationS);
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) root.fail("duration", "must be > 0 s");
  duration_ns = seconds_to_ns(duration_s);

  parse_cameras(root);
  std::set<std::string> names;
  std::set<std::string> body_names;
  parse_markers(root, names);
  parse_landmarks(root, names);
  parse_trc(root, base_dir, names);
  parse_bodies(root, names, body_names);
  add_rig_marker_names(root, names);
  parse_chains(root, names, body_names);
  if (marker_names.empty())
    root.fail("markers", "the scene has no markers (give markers, trc, bodies, landmarks or chains)");
}

void Scene::Impl::add_marker_name(std::set<std::string>& names, const YamlReader& reader,
                                  const std::string& key, const std::string& name, double radius) {
  if (!names.insert(name).second) reader.fail(key, "duplicate marker name '" + name + "'");
  marker_names.push_back(name);
  marker_radii.push_back(radius);
}

void Scene::Impl::parse_cameras(const YamlReader& root) {
  std::optional<YamlReader> defaults;
  if (root.has("defaults")) {
    defaults.emplace(root.child("defaults"));
    reject_unknown_keys(*defaults, {"drift", PANOPTES_SIM_CAMERA_KEYS});
  }
  const std::vector<YamlReader> camera_readers = root.sequence("cameras");
  if (camera_readers.empty()) root.fail("cameras", "expected at least one camera");
  std::set<std::string> camera_ids;
  for (const YamlReader& camera : camera_readers) {
    SimCameraConfig config = read_camera(camera, defaults);
    if (config.drifting && config.drift_axis.isZero()) config.drift_axis = random_axis(seed, cameras.size());
    if (!camera_ids.insert(config.calibration.id).second) {
      camera.fail("id", "duplicate camera id '" + config.calibration.id + "'");
    }
    std::optional<RigSpec> rig;
    if (config.calibration.moving) {
      rig = read_rig(camera, config.calibration.id);
      config.calibration.rig = rig->name;
    }
    camera_rigs.push_back(std::move(rig));
    cameras.push_back(std::move(config));
  }
}

void Scene::Impl::parse_markers(const YamlReader& root, std::set<std::string>& names) {
  const std::vector<YamlReader> marker_readers = root.sequence_or_empty("markers");
  for (std::size_t i = 0; i < marker_readers.size(); ++i) {
    const YamlReader& marker = marker_readers[i];
    reject_unknown_keys(marker, {"name", "radius", "path", "pen_down"});
    MarkerSpec spec;
    // Appending rather than "m" + to_string(i) sidesteps a GCC 12 -Wrestrict false positive.
    std::string default_name = "m";
    default_name.append(std::to_string(i));
    spec.name = marker.get_string("name", default_name);
    if (spec.name.empty()) marker.fail("name", "must not be empty");
    spec.radius = read_marker_radius(marker, "radius");
    spec.path = sim::read_path(marker.child("path"));
    if (marker.has("pen_down")) {
      double previous_end = -std::numeric_limits<double>::infinity();
      for (const auto& interval : marker.get_double_rows("pen_down", 2)) {
        if (!(interval[0] < interval[1]) || !(interval[0] >= previous_end) || !std::isfinite(interval[1]))
          marker.fail("pen_down", "intervals [start, end] must be finite, start < end, in increasing order");
        spec.pen_down.emplace_back(interval[0], interval[1]);
        previous_end = interval[1];
      }
    }
    add_marker_name(names, marker, "name", spec.name, spec.radius);
    markers.push_back(std::move(spec));
  }
}

// Fixed in the room: static markers "<name>/<index>" (a single one: "<name>"), after `markers` as
// markers_at() fills them.
void Scene::Impl::parse_landmarks(const YamlReader& root, std::set<std::string>& names) {
  if (!root.has("landmarks")) return;
  landmarks = read_landmarks(root);
  for (const LandmarkGroup& group : landmarks) {
    for (std::size_t m = 0; m < group.points.size(); ++m) {
      MarkerSpec spec;
      spec.name = group.constellation ? group.name + "/" + std::to_string(m) : group.name;
      spec.path = sim::StaticPath{group.points[m]};
      add_marker_name(names, root, "landmarks", spec.name, spec.radius);
      markers.push_back(std::move(spec));
    }
  }
}

void Scene::Impl::parse_trc(const YamlReader& root, const std::filesystem::path& base_dir,
                            std::set<std::string>& names) {
  if (!root.has("trc")) return;
  // One recording, or a list of them (several people: each with its own prefix, offset and start).
  const std::vector<YamlReader> readers = root.node()["trc"].IsSequence()
                                              ? root.sequence_or_empty("trc")
                                              : std::vector<YamlReader>{root.child("trc")};
  for (const YamlReader& reader : readers) {
    std::vector<std::string> trc_names;
    trcs.push_back(read_trc(reader, base_dir, trc_names));
    for (const std::string& name : trc_names)
      add_marker_name(names, reader, "prefix", name, trcs.back().radius);
  }
}

namespace {

// A body's `occlusion:` section: markers hidden when seen from behind.
void read_occlusion(const YamlReader& body, BodySpec& spec) {
  const YamlReader occlusion = body.child("occlusion");
  reject_unknown_keys(occlusion, {"facing_angle", "normal"});
  const double degrees = occlusion.get_double("facing_angle");
  if (!(degrees > 0.0 && degrees <= 180.0)) occlusion.fail("facing_angle", "must be in (0, 180] degrees");
  spec.facing_angle_rad = degrees * std::numbers::pi / 180.0;
  if (occlusion.has("normal")) {
    const auto n = occlusion.get_doubles("normal", 3);
    spec.normal = Eigen::Vector3d(n[0], n[1], n[2]);
    if (!(spec.normal.norm() > 0.0)) occlusion.fail("normal", "must be a non-zero vector");
    spec.normal.normalize();
  }
}

}  // namespace

void Scene::Impl::parse_bodies(const YamlReader& root, std::set<std::string>& names,
                               std::set<std::string>& body_names) {
  for (const YamlReader& body : root.sequence_or_empty("bodies")) {
    reject_unknown_keys(body, {"name", "markers", "type", "marker_radius", "path", "rotation", "occlusion"});
    BodySpec spec;
    BodyDefinition definition = read_body_definition(body, body_names);
    spec.name = std::move(definition.name);
    spec.markers = std::move(definition.markers);
    spec.kind = definition.kind;
    if (body.has("occlusion")) read_occlusion(body, spec);
    spec.marker_radius = read_marker_radius(body, "marker_radius");
    spec.path = sim::read_path(body.child("path"));
    if (body.has("rotation")) spec.rotation = sim::read_rotation(body.child("rotation"));
    for (std::size_t m = 0; m < spec.markers.size(); ++m) {
      add_marker_name(names, body, "name", spec.name + "/" + std::to_string(m), spec.marker_radius);
    }
    bodies.push_back(std::move(spec));
  }
}

void Scene::Impl::add_rig_marker_names(const YamlReader& root, std::set<std::string>& names) {
  for (const auto& rig : camera_rigs) {
    for (std::size_t m = 0; rig && m < rig->markers.size(); ++m)
      add_marker_name(names, root, "cameras", rig->name + "/" + std::to_string(m), kDefaultMarkerRadius);
  }
}

void Scene::Impl::parse_chains(const YamlReader& root, std::set<std::string>& names,
                               std::set<std::string>& body_names) {
  for (const YamlReader& chain : root.sequence_or_empty("chains")) {
    sim::ChainSpec spec = sim::read_chain_spec(chain, kDefaultMarkerRadius);
    if (!body_names.insert(spec.definition.name).second)
      chain.fail("name", "duplicate body or chain name '" + spec.definition.name + "'");
    for (int m = 0; m < spec.definition.marker_count(); ++m)
      add_marker_name(names, chain, "name", spec.definition.name + "/" + std::to_string(m),
                      spec.marker_radius);
    chains.push_back(std::move(spec));
  }
}

Scene::Scene() : impl_(std::make_unique<Impl>()) {}
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;
Scene::~Scene() = default;

Scene Scene::load(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  Scene scene;
  scene.impl_->file = path.string();
  std::filesystem::path base_dir = path.parent_path();
  if (base_dir.empty()) base_dir = ".";
  scene.impl_->parse(YamlReader(path.string(), root), base_dir);
  return scene;
}

Scene Scene::from_yaml_string(const std::string& yaml, const std::filesystem::path& base_dir,
                              const std::string& name_for_errors) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::ParserException& error) {
    throw ConfigError(name_for_errors, "",
                      "YAML syntax error at line " + std::to_string(error.mark.line + 1) + ": " + error.msg);
  }
  Scene scene;
  scene.impl_->file = name_for_errors;
  scene.impl_->parse(YamlReader(name_for_errors, root), base_dir);
  return scene;
}

std::uint64_t Scene::seed() const {
  return impl_->seed;
}
TimeNs Scene::duration_ns() const {
  return impl_->duration_ns;
}
const std::vector<SimCameraConfig>& Scene::cameras() const {
  return impl_->cameras;
}

const SimCameraConfig* Scene::find_camera(std::string_view id) const {
  for (const auto& camera : impl_->cameras) {
    if (camera.calibration.id == id) return &camera;
  }
  return nullptr;
}

SystemCalibration Scene::calibration() const {
  SystemCalibration calibration;
  for (const auto& camera : impl_->cameras) calibration.cameras.push_back(camera.calibration);
  return calibration;
}

const std::vector<std::string>& Scene::marker_names() const {
  return impl_->marker_names;
}

std::vector<MarkerTruth> Scene::markers_at(TimeNs scene_time_ns) const {
  const double t_s = ns_to_seconds(scene_time_ns);
  std::vector<MarkerTruth> out(impl_->marker_names.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i].name = impl_->marker_names[i];
  std::size_t index = 0;
  for (const MarkerSpec& marker : impl_->markers) {
    out[index].valid = marker.exists_at(t_s);
    out[index++].p = sim::evaluate(marker.path, t_s);
  }
  for (const TrcSource& trc : impl_->trcs) {
    sample_trc(trc, t_s, out, index);
    index += trc.columns.size();
  }
  for (const BodySpec& body : impl_->bodies) {
    const Eigen::Quaterniond q = sim::evaluate(body.rotation, t_s);
    const Eigen::Vector3d t = sim::evaluate(body.path, t_s);
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& marker : body.markers) centroid += marker;
    centroid /= static_cast<double>(body.markers.size());
    for (const Eigen::Vector3d& marker : body.markers) {
      MarkerTruth& truth = out[index++];
      truth.p = q * marker + t;
      if (body.facing_angle_rad <= 0.0) continue;
      const Eigen::Vector3d outward = body.normal.isZero() ? (marker - centroid) : body.normal;
      if (outward.norm() < 1e-9) continue;
      truth.normal = q * outward.normalized();
      truth.facing_angle_rad = body.facing_angle_rad;
    }
  }
  for (const auto& rig : impl_->camera_rigs) {
    if (!rig || rig->markers.empty()) continue;
    const RigidTransform T_world_rig{sim::evaluate(rig->rotation, t_s), sim::evaluate(rig->path, t_s)};
    for (const Eigen::Vector3d& marker : rig->markers) out[index++].p = T_world_rig.apply(marker);
  }
  for (const sim::ChainSpec& chain : impl_->chains) {
    for (const Eigen::Vector3d& marker : sim::sample_chain(chain, t_s).markers) out[index++].p = marker;
  }
  return out;
}

std::vector<ChainTruth> Scene::chains_at(TimeNs scene_time_ns) const {
  const double t_s = ns_to_seconds(scene_time_ns);
  std::vector<ChainTruth> out;
  for (const sim::ChainSpec& chain : impl_->chains) {
    sim::ChainSample sample = sim::sample_chain(chain, t_s);
    out.push_back({chain.definition.name, sample.T_world_base, std::move(sample.angles),
                   std::move(sample.markers), sample.tip});
  }
  return out;
}

std::vector<BodyTruth> Scene::bodies_at(TimeNs scene_time_ns) const {
  const double t_s = ns_to_seconds(scene_time_ns);
  std::vector<BodyTruth> out;
  out.reserve(impl_->bodies.size());
  for (const BodySpec& body : impl_->bodies) {
    out.push_back(
        {body.name, RigidTransform{sim::evaluate(body.rotation, t_s), sim::evaluate(body.path, t_s)}});
  }
  for (const auto& rig : impl_->camera_rigs) {
    if (rig)
      out.push_back(
          {rig->name, RigidTransform{sim::evaluate(rig->rotation, t_s), sim::evaluate(rig->path, t_s)}});
  }
  return out;
}

RigidTransform Scene::camera_pose_at(std::size_t camera_index, TimeNs scene_time_ns) const {
  const SimCameraConfig& config = impl_->cameras.at(camera_index);
  RigidTransform mount = *config.calibration.T_world_cam;
  if (config.drifting && scene_time_ns > config.drift_from_ns) {
    const double t_s = ns_to_seconds(scene_time_ns - config.drift_from_ns);
    mount =
        mount * RigidTransform{
                    Eigen::Quaterniond(Eigen::AngleAxisd(config.drift_rate_rad_s * t_s, config.drift_axis)),
                    config.drift_velocity_m_s * t_s};
  }
  if (config.bumped && scene_time_ns >= config.bump_at_ns) mount = mount * config.bump;
  const auto& rig = impl_->camera_rigs.at(camera_index);
  if (!rig) return mount;
  const double t_s = ns_to_seconds(scene_time_ns);
  return RigidTransform{sim::evaluate(rig->rotation, t_s), sim::evaluate(rig->path, t_s)} * mount;
}

void Scene::set_camera_bump(std::size_t camera_index, TimeNs at_ns, const RigidTransform& bump) {
  SimCameraConfig& config = impl_->cameras.at(camera_index);
  config.bumped = true;
  config.bump_at_ns = at_ns;
  config.bump = bump;
}

void Scene::set_camera_drift(std::size_t camera_index, TimeNs from_ns, double degrees_per_minute,
                             const Eigen::Vector3d& axis, const Eigen::Vector3d& millimetres_per_minute) {
  set_drift(impl_->cameras.at(camera_index), from_ns, degrees_per_minute,
            axis.norm() > 0.0 ? axis : random_axis(impl_->seed, camera_index), millimetres_per_minute);
}

std::map<std::string, std::vector<Eigen::Vector3d>> Scene::rig_markers() const {
  std::map<std::string, std::vector<Eigen::Vector3d>> markers;
  for (const auto& rig : impl_->camera_rigs)
    if (rig && !rig->markers.empty()) markers[rig->name] = rig->markers;
  return markers;
}

std::vector<std::string> Scene::rig_names() const {
  std::vector<std::string> names;
  for (const auto& rig : impl_->camera_rigs)
    if (rig) names.push_back(rig->name);
  return names;
}

const std::vector<LandmarkGroup>& Scene::landmarks() const {
  return impl_->landmarks;
}

std::vector<BodyDefinition> Scene::body_definitions() const {
  std::vector<BodyDefinition> out;
  for (const BodySpec& body : impl_->bodies) out.push_back({body.name, body.markers, body.kind});
  return out;
}

double Scene::marker_radius(std::size_t marker_index) const {
  return impl_->marker_radii.at(marker_index);
}

}  // namespace panoptes
