// SPDX-License-Identifier: Apache-2.0
// Frame timing, ideal features and rendered images of one simulated camera.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "panoptes/simulator.h"
#include "random.h"

namespace panoptes {

namespace {

// Separate streams below one frame key, so that e.g. switching pixel noise off leaves every
// marker's jitter and dropout unchanged.
constexpr std::uint64_t kMarkerStream = 1;
constexpr std::uint64_t kPixelNoiseStream = 2;

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
};

// The one place that decides which markers a frame shows and where: features() reports and
// render() draws exactly these.
std::vector<Spot> visible_spots(const Scene& scene, const SimCameraConfig& config, std::size_t camera_index,
                                std::int64_t k, TimeNs scene_time_ns) {
  const std::uint64_t frame_key =
      sim::hash_key(scene.seed(), static_cast<std::uint64_t>(camera_index), static_cast<std::uint64_t>(k));
  const std::uint64_t marker_key = sim::hash_key(frame_key, kMarkerStream);
  const CameraModel model = config.calibration.model();
  const CameraIntrinsics& intrinsics = model.intrinsics();
  const double focal = 0.5 * (intrinsics.fx + intrinsics.fy);
  const std::vector<MarkerTruth> markers = scene.markers_at(scene_time_ns);

  const double centre_fraction = std::erf(0.5 / (std::numbers::sqrt2 * config.blob_min_sigma_px));
  const double peak_density =
      config.blob_peak_dn / (2.0 * std::numbers::pi * config.blob_min_sigma_px * config.blob_min_sigma_px *
                             centre_fraction * centre_fraction);

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
    const auto pixel = model.project_camera_point(p_cam);
    if (!pixel) continue;
    if (dropout_draw < config.dropout_probability) continue;
    Spot spot;
    spot.centre = *pixel + config.centroid_noise_px * jitter;
    if (!model.in_image(spot.centre)) continue;
    // A sphere of radius r at depth z images to a disc of radius f r / z; a Gaussian with half
    // that sigma puts its 2-sigma contour on the disc's edge.
    spot.sigma_px = std::max(config.blob_min_sigma_px, 0.5 * focal * scene.marker_radius(i) / p_cam.z());
    // Constant surface brightness, as for a resolved retro-reflector: every spot has the same
    // peak density, so larger (closer) spots carry more flux. The density is set so that a
    // minimum-size spot centred on a pixel lights that pixel blob_peak above the background.
    spot.flux = peak_density * 2.0 * std::numbers::pi * spot.sigma_px * spot.sigma_px;
    spots.push_back(spot);
  }
  return spots;
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

TimeNs CameraSimulator::frame_stamp_ns(std::int64_t k) const {
  return frame_time_ns(k) + config_->clock_offset_ns;
}

FeatureFrame CameraSimulator::features(std::int64_t k) const {
  FeatureFrame frame;
  frame.camera_id = config_->calibration.id;
  frame.frame = k;
  frame.stamp_ns = frame_stamp_ns(k);
  const double max_value = static_cast<double>((1 << config_->bits) - 1);
  for (const Spot& spot : visible_spots(*scene_, *config_, camera_index_, k, frame_time_ns(k))) {
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
  for (const Spot& spot : visible_spots(*scene_, config, camera_index_, k, frame_time_ns(k))) {
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

  const std::uint64_t noise_key = sim::hash_key(
      sim::hash_key(scene_->seed(), static_cast<std::uint64_t>(camera_index_), static_cast<std::uint64_t>(k)),
      kPixelNoiseStream);
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
