// SPDX-License-Identifier: Apache-2.0
// Frame timing, ideal features and rendered images of one simulated camera.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "panoptes/simulator.h"
#include "panoptes/union_find.h"
#include "random.h"

namespace panoptes {

namespace {

// Separate streams below one frame key, so that e.g. switching pixel noise off leaves every
// marker's jitter and dropout unchanged.
constexpr std::uint64_t kMarkerStream = 1;
constexpr std::uint64_t kPixelNoiseStream = 2;
constexpr std::uint64_t kFalseBlobStream = 3;
constexpr std::uint64_t kDeliveryStream = 4;

// Spots are truncated where the Gaussian has fallen below 3.4e-4 of its peak.
constexpr double kSpotHalfWidthSigmas = 4.0;

// Points further off-axis than this (in normalised coordinates, ~84 degrees) are never projected:
// the polynomial distortion model folds such points back into the image.
constexpr double kMaxNormalizedRadius = 10.0;

__extension__ typedef __int128 Int128;

// round(k * 1e9 / rate) in exact integer arithmetic when the rate is a whole number of millihertz
// (all practical camera rates), so frame times never drift however large k grows.
TimeNs frame_offset_ns(std::int64_t k, double rate_hz) {
  const double millihertz = rate_hz * 1000.0;
  const double rounded = std::round(millihertz);
  if (rounded >= 1.0 && rounded < 9e15 && std::abs(millihertz - rounded) <= 1e-9 * rounded) {
    const auto denominator = static_cast<Int128>(rounded);
    const Int128 numerator = static_cast<Int128>(k) * 1'000'000'000'000;
    Int128 quotient = numerator / denominator;
    const Int128 remainder = numerator % denominator;
    // Half away from zero, like std::llround.
    if (2 * (remainder < 0 ? -remainder : remainder) >= denominator) quotient += numerator < 0 ? -1 : 1;
    return static_cast<TimeNs>(quotient);
  }
  return static_cast<TimeNs>(std::llround(static_cast<long double>(k) * 1e9L / rate_hz));
}

struct Spot {
  Eigen::Vector2d centre;  // pixels, jitter included
  double sigma_px = 1.0;
  double flux = 0.0;  // DN summed over the spot, background excluded
  int marker = -1;    // index into Scene::marker_names(); -1 for a false blob
};

std::uint64_t frame_key(const Scene& scene, std::size_t camera_index, std::int64_t k) {
  return sim::hash_key(scene.seed(), static_cast<std::uint64_t>(camera_index), static_cast<std::uint64_t>(k));
}

// Constant surface brightness, as for a resolved retro-reflector: every spot has the same peak
// density, so larger (closer) spots carry more flux. The density is set so that a minimum-size
// spot centred on a pixel lights that pixel blob_peak above the background.
double peak_density(const SimCameraConfig& config) {
  const double centre_fraction = std::erf(0.5 / (std::numbers::sqrt2 * config.blob_min_sigma_px));
  return config.blob_peak_dn / (2.0 * std::numbers::pi * config.blob_min_sigma_px * config.blob_min_sigma_px *
                                centre_fraction * centre_fraction);
}

// The one place that decides which markers a frame shows and where: features() reports,
// visible_markers() lists and render() draws exactly these (features() after merging).
std::vector<Spot> marker_spots(const Scene& scene, const SimCameraConfig& config, std::size_t camera_index,
                               std::int64_t k, TimeNs scene_time_ns) {
  const std::uint64_t marker_key = sim::hash_key(frame_key(scene, camera_index, k), kMarkerStream);
  // A moving camera's pose changes with the frame (inside-out tracking).
  const CameraModel model(config.calibration.intrinsics, scene.camera_pose_at(camera_index, scene_time_ns));
  const CameraIntrinsics& intrinsics = model.intrinsics();
  const double focal = 0.5 * (intrinsics.fx + intrinsics.fy);
  const Eigen::Vector3d camera_centre = model.T_world_cam().t;
  const std::vector<MarkerTruth> markers = scene.markers_at(scene_time_ns);
  const double density = peak_density(config);

  std::vector<Spot> spots;
  for (std::size_t i = 0; i < markers.size(); ++i) {
    // Draw first, whatever happens to the marker, so each marker's draws depend only on its index.
    sim::Rng rng(sim::hash_key(marker_key, static_cast<std::uint64_t>(i)));
    const double dropout_draw = rng.uniform();
    const Eigen::Vector2d jitter(rng.normal(), rng.normal());

    if (!markers[i].valid) continue;
    const Eigen::Vector3d p_cam = model.T_cam_world().apply(markers[i].p);
    if (!(p_cam.z() > 0.0)) continue;
    if (p_cam.head<2>().norm() > kMaxNormalizedRadius * p_cam.z()) continue;
    if (!markers[i].normal.isZero()) {
      // Hidden by the body when the camera lies more than facing_angle away from the normal.
      const Eigen::Vector3d to_camera = (camera_centre - markers[i].p).normalized();
      if (markers[i].normal.dot(to_camera) < std::cos(markers[i].facing_angle_rad)) continue;
    }
    const auto pixel = model.project_camera_point(p_cam);
    if (!pixel) continue;
    if (dropout_draw < config.dropout_probability) continue;
    Spot spot;
    spot.centre = *pixel + config.centroid_noise_px * jitter;
    if (!model.in_image(spot.centre)) continue;
    // A sphere of radius r at depth z images to a disc of radius f r / z; a Gaussian with half
    // that sigma puts its 2-sigma contour on the disc's edge.
    spot.sigma_px = std::max(config.blob_min_sigma_px, 0.5 * focal * scene.marker_radius(i) / p_cam.z());
    spot.flux = density * 2.0 * std::numbers::pi * spot.sigma_px * spot.sigma_px;
    spot.marker = static_cast<int>(i);
    spots.push_back(spot);
  }
  return spots;
}

// Spurious blobs (reflections, lamps): a Poisson number per frame, each a minimum-size spot
// uniform over the image. The count comes from its own stream and every blob's position from
// another, so a frame's false blobs never depend on its markers.
std::vector<Spot> false_spots(const Scene& scene, const SimCameraConfig& config, std::size_t camera_index,
                              std::int64_t k) {
  std::vector<Spot> spots;
  if (!(config.false_blobs > 0.0)) return spots;
  const std::uint64_t false_key = sim::hash_key(frame_key(scene, camera_index, k), kFalseBlobStream);
  // Poisson: the number of unit-rate exponential gaps that fit in the mean.
  sim::Rng count_rng(false_key);
  std::size_t count = 0;
  for (double elapsed = -std::log(1.0 - count_rng.uniform()); elapsed <= config.false_blobs;
       elapsed -= std::log(1.0 - count_rng.uniform())) {
    ++count;
  }
  const double width = config.calibration.intrinsics.width;
  const double height = config.calibration.intrinsics.height;
  const double sigma = config.blob_min_sigma_px;
  const double flux = peak_density(config) * 2.0 * std::numbers::pi * sigma * sigma;
  for (std::size_t j = 0; j < count; ++j) {
    sim::Rng rng(sim::hash_key(false_key, static_cast<std::uint64_t>(j)));
    Spot spot;
    spot.centre.x() = -0.5 + width * rng.uniform();
    spot.centre.y() = -0.5 + height * rng.uniform();
    spot.sigma_px = sigma;
    spot.flux = flux;
    spots.push_back(spot);
  }
  return spots;
}

// Marker spots (in marker order) followed by false blobs: everything frame k shows.
std::vector<Spot> all_spots(const Scene& scene, const SimCameraConfig& config, std::size_t camera_index,
                            std::int64_t k, TimeNs scene_time_ns) {
  std::vector<Spot> spots = marker_spots(scene, config, camera_index, k, scene_time_ns);
  std::vector<Spot> extra = false_spots(scene, config, camera_index, k);
  spots.insert(spots.end(), extra.begin(), extra.end());
  return spots;
}

// Groups of spots whose centres are chained by distances below merge_distance (their images
// overlap into one connected blob), each group in ascending spot order, groups ordered by their
// first spot. Without merging every spot is its own group.
std::vector<std::vector<std::size_t>> merge_groups(const std::vector<Spot>& spots, double merge_distance) {
  UnionFind merged(spots.size());
  if (merge_distance > 0.0) {
    // Sweep in x so only spots within merge_distance in x are compared.
    std::vector<std::size_t> by_x(spots.size());
    for (std::size_t i = 0; i < spots.size(); ++i) by_x[i] = i;
    std::sort(by_x.begin(), by_x.end(),
              [&](std::size_t a, std::size_t b) { return spots[a].centre.x() < spots[b].centre.x(); });
    for (std::size_t a = 0; a < by_x.size(); ++a) {
      for (std::size_t b = a + 1; b < by_x.size(); ++b) {
        const Spot& first = spots[by_x[a]];
        const Spot& second = spots[by_x[b]];
        if (second.centre.x() - first.centre.x() >= merge_distance) break;
        if ((second.centre - first.centre).norm() >= merge_distance) continue;
        const std::size_t ra = merged.find(by_x[a]);
        const std::size_t rb = merged.find(by_x[b]);
        // The smaller index stays the root, so a group's root is its first spot.
        if (ra != rb) merged.unite(std::min(ra, rb), std::max(ra, rb));
      }
    }
  }
  std::vector<std::vector<std::size_t>> groups;
  std::vector<std::size_t> group_of(spots.size(), 0);
  for (std::size_t i = 0; i < spots.size(); ++i) {
    const std::size_t r = merged.find(i);
    if (r == i) {
      group_of[i] = groups.size();
      groups.push_back({i});
    } else {
      groups[group_of[r]].push_back(i);
    }
  }
  return groups;
}

// Fraction of a unit Gaussian (centre c, std sigma) falling on each pixel first..last of one axis;
// pixel i covers [i - 0.5, i + 0.5].
std::vector<float> pixel_fractions(double centre, double sigma, int first, int last) {
  const double scale = 1.0 / (std::numbers::sqrt2 * sigma);
  std::vector<float> fractions(static_cast<std::size_t>(last - first + 1));
  double lower = std::erf((first - 0.5 - centre) * scale);
  for (int i = first; i <= last; ++i) {
    const double upper = std::erf((i + 0.5 - centre) * scale);
    fractions[static_cast<std::size_t>(i - first)] = static_cast<float>(0.5 * (upper - lower));
    lower = upper;
  }
  return fractions;
}

struct Footprint {
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
  std::vector<float> weight_x;  // fraction per column
  std::vector<float> weight_y;  // flux times fraction per row
};

template <class Pixel>
void quantize_row(const float* values, Pixel* out, int width, float max_value) {
  for (int x = 0; x < width; ++x) {
    const float value = std::clamp(values[x], 0.0f, max_value);
    // Clamped to >= 0, so adding 0.5 and truncating rounds correctly, and faster than lround.
    out[x] = static_cast<Pixel>(value + 0.5f);  // NOLINT(bugprone-incorrect-roundings)
  }
}

}  // namespace

CameraSimulator::CameraSimulator(const Scene& scene, std::string_view camera_id) : scene_(&scene) {
  const auto& cameras = scene.cameras();
  const auto it = std::find_if(cameras.begin(), cameras.end(), [&](const SimCameraConfig& camera) {
    return camera.calibration.id == camera_id;
  });
  if (it == cameras.end())
    throw std::invalid_argument("scene has no camera '" + std::string(camera_id) + "'");
  config_ = &*it;
  camera_index_ = static_cast<std::size_t>(it - cameras.begin());
}

TimeNs CameraSimulator::frame_time_ns(std::int64_t k) const {
  return config_->phase_ns + frame_offset_ns(k, config_->rate_hz);
}

CameraSimulator::FrameRange CameraSimulator::frames_in(TimeNs from_ns, TimeNs to_ns) const {
  FrameRange range;
  while (frame_time_ns(range.first) < from_ns) ++range.first;
  while (range.first > 0 && frame_time_ns(range.first - 1) >= from_ns) --range.first;
  range.end = range.first;
  while (frame_time_ns(range.end) < to_ns) ++range.end;
  return range;
}

TimeNs CameraSimulator::frame_stamp_ns(std::int64_t k) const {
  return frame_time_ns(k) + config_->clock_offset_ns;
}

TimeNs CameraSimulator::frame_received_ns(std::int64_t k) const {
  sim::Rng rng(sim::hash_key(frame_key(*scene_, camera_index_, k), kDeliveryStream));
  // All drawn always, so the late decision and the delays never shift other draws.
  const double late_draw = rng.uniform();
  const double delay_draw = rng.uniform();
  const double jitter_draw = rng.uniform();
  TimeNs received = frame_time_ns(k) + config_->exposure_ns / 2 + config_->latency_ns;
  if (config_->latency_jitter_ns > 0) {
    received += static_cast<TimeNs>(
        std::llround(-std::log1p(-jitter_draw) * static_cast<double>(config_->latency_jitter_ns)));
  }
  if (late_draw < config_->late_fraction) {
    const auto range = static_cast<double>(config_->late_delay_max_ns - config_->late_delay_min_ns);
    received += config_->late_delay_min_ns + static_cast<TimeNs>(std::llround(delay_draw * range));
  }
  return received;
}

std::vector<int> CameraSimulator::visible_markers(std::int64_t k) const {
  std::vector<int> markers;
  for (const Spot& spot : marker_spots(*scene_, *config_, camera_index_, k, frame_time_ns(k))) {
    markers.push_back(spot.marker);
  }
  return markers;
}

int CameraSimulator::false_blob_count(std::int64_t k) const {
  return static_cast<int>(false_spots(*scene_, *config_, camera_index_, k).size());
}

namespace {

// Value of the pixel nearest `at` without sensor noise, from the spots listed.
double noiseless_pixel(const std::vector<Spot>& spots, const std::vector<std::size_t>& members,
                       const Eigen::Vector2d& at) {
  const int column = static_cast<int>(std::lround(at.x()));
  const int row = static_cast<int>(std::lround(at.y()));
  double value = 0.0;
  for (std::size_t i : members) {
    const Spot& spot = spots[i];
    value += spot.flux * pixel_fractions(spot.centre.x(), spot.sigma_px, column, column)[0] *
             pixel_fractions(spot.centre.y(), spot.sigma_px, row, row)[0];
  }
  return value;
}

// One blob from several overlapping spots: fluxes and areas add, the centre is flux-weighted, and
// the second moments are those of the combined intensity (each spot's own plus its offset from
// the common centre). The peak is the brightest of the pixels at the centre and at each spot.
Blob merged_blob(const std::vector<Spot>& spots, const std::vector<std::size_t>& members, double background,
                 double max_value) {
  Blob blob;
  Eigen::Vector2d weighted = Eigen::Vector2d::Zero();
  for (std::size_t i : members) {
    blob.sum += spots[i].flux;
    blob.area += 4.0 * std::numbers::pi * spots[i].sigma_px * spots[i].sigma_px;
    weighted += spots[i].flux * spots[i].centre;
  }
  const Eigen::Vector2d centre = weighted / blob.sum;
  blob.x = centre.x();
  blob.y = centre.y();
  double brightest = noiseless_pixel(spots, members, centre);
  for (std::size_t i : members) {
    const Eigen::Vector2d offset = spots[i].centre - centre;
    const double own = spots[i].sigma_px * spots[i].sigma_px + 1.0 / 12.0;
    const double weight = spots[i].flux / blob.sum;
    blob.m20 += weight * (own + offset.x() * offset.x());
    blob.m02 += weight * (own + offset.y() * offset.y());
    blob.m11 += weight * offset.x() * offset.y();
    brightest = std::max(brightest, noiseless_pixel(spots, members, spots[i].centre));
  }
  blob.peak = static_cast<int>(std::lround(std::clamp(background + brightest, 0.0, max_value)));
  return blob;
}

}  // namespace

FeatureFrame CameraSimulator::features(std::int64_t k) const {
  FeatureFrame frame;
  frame.camera_id = config_->calibration.id;
  frame.frame = k;
  frame.stamp_ns = frame_stamp_ns(k);
  frame.received_ns = frame_received_ns(k);
  const double max_value = static_cast<double>((1 << config_->bits) - 1);
  const std::vector<Spot> spots = all_spots(*scene_, *config_, camera_index_, k, frame_time_ns(k));
  for (const std::vector<std::size_t>& group : merge_groups(spots, config_->merge_distance_px)) {
    if (group.size() > 1) {
      frame.blobs.push_back(merged_blob(spots, group, config_->background_dn, max_value));
      continue;
    }
    const Spot& spot = spots[group.front()];
    Blob blob;
    blob.x = spot.centre.x();
    blob.y = spot.centre.y();
    const double sigma2 = spot.sigma_px * spot.sigma_px;
    blob.area = 4.0 * std::numbers::pi * sigma2;
    blob.sum = spot.flux;
    const int column = static_cast<int>(std::lround(spot.centre.x()));
    const int row = static_cast<int>(std::lround(spot.centre.y()));
    const double brightest = spot.flux * pixel_fractions(spot.centre.x(), spot.sigma_px, column, column)[0] *
                             pixel_fractions(spot.centre.y(), spot.sigma_px, row, row)[0];
    blob.peak = static_cast<int>(std::lround(std::clamp(config_->background_dn + brightest, 0.0, max_value)));
    // Integrating over a pixel adds the variance of a unit box, 1/12.
    blob.m20 = sigma2 + 1.0 / 12.0;
    blob.m02 = sigma2 + 1.0 / 12.0;
    blob.m11 = 0.0;
    frame.blobs.push_back(blob);
  }
  return frame;
}

Image CameraSimulator::render(std::int64_t k) const {
  const SimCameraConfig& config = *config_;
  const int width = config.calibration.intrinsics.width;
  const int height = config.calibration.intrinsics.height;
  Image image(width, height, config.bits);

  std::vector<Footprint> footprints;
  for (const Spot& spot : all_spots(*scene_, config, camera_index_, k, frame_time_ns(k))) {
    const int half = static_cast<int>(std::ceil(kSpotHalfWidthSigmas * spot.sigma_px));
    const int cx = static_cast<int>(std::lround(spot.centre.x()));
    const int cy = static_cast<int>(std::lround(spot.centre.y()));
    Footprint footprint;
    footprint.x0 = std::max(0, cx - half);
    footprint.x1 = std::min(width - 1, cx + half);
    footprint.y0 = std::max(0, cy - half);
    footprint.y1 = std::min(height - 1, cy + half);
    if (footprint.x0 > footprint.x1 || footprint.y0 > footprint.y1) continue;
    footprint.weight_x = pixel_fractions(spot.centre.x(), spot.sigma_px, footprint.x0, footprint.x1);
    footprint.weight_y = pixel_fractions(spot.centre.y(), spot.sigma_px, footprint.y0, footprint.y1);
    for (float& weight : footprint.weight_y) weight = static_cast<float>(weight * spot.flux);
    footprints.push_back(std::move(footprint));
  }

  const std::uint64_t noise_key = sim::hash_key(frame_key(*scene_, camera_index_, k), kPixelNoiseStream);
  const float* normal = sim::normal_quantile_table();
  const auto background = static_cast<float>(config.background_dn);
  const auto noise = static_cast<float>(config.pixel_noise_dn);
  const auto max_value = static_cast<float>(image.max_value());
  std::vector<float> row(static_cast<std::size_t>(width));
  for (int y = 0; y < height; ++y) {
    if (noise > 0.0f) {
      // One stream per row: rows are independent, and 16 bits per pixel index the quantile table.
      sim::Rng rng(sim::hash_key(noise_key, static_cast<std::uint64_t>(y)));
      int x = 0;
      for (; x + 4 <= width; x += 4) {
        const std::uint64_t bits = rng.next();
        row[x] = background + noise * normal[bits & 0xFFFF];
        row[x + 1] = background + noise * normal[(bits >> 16) & 0xFFFF];
        row[x + 2] = background + noise * normal[(bits >> 32) & 0xFFFF];
        row[x + 3] = background + noise * normal[bits >> 48];
      }
      for (std::uint64_t bits = rng.next(); x < width; ++x, bits >>= 16) {
        row[x] = background + noise * normal[bits & 0xFFFF];
      }
    } else {
      std::fill(row.begin(), row.end(), background);
    }
    for (const Footprint& footprint : footprints) {
      if (y < footprint.y0 || y > footprint.y1) continue;
      const float weight = footprint.weight_y[static_cast<std::size_t>(y - footprint.y0)];
      const float* weight_x = footprint.weight_x.data();
      for (int x = footprint.x0; x <= footprint.x1; ++x) row[x] += weight * weight_x[x - footprint.x0];
    }
    if (image.bytes_per_pixel() == 1) {
      quantize_row(row.data(), image.row8(y), width, max_value);
    } else {
      quantize_row(row.data(), image.row16(y), width, max_value);
    }
  }
  return image;
}

}  // namespace panoptes
