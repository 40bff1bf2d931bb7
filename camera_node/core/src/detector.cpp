// SPDX-License-Identifier: Apache-2.0
// Blob detector: per-pixel threshold, run-length rows, union-find over runs (full frame) or
// seeded scanline growth (guided), one moment pass, background-subtracted centroid refinement
// (seed 004 §2.2.1; seed 003 §2.2.2).
#include "panoptes/camera/detector.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace panoptes::camera {

namespace {

// ---- Row scanning -------------------------------------------------------------------------
// Background pixels are the vast majority: each block of one cache line is tested with a
// branch-free OR of comparisons, which the compiler turns into vector compares; only blocks
// with a bright pixel are walked pixel by pixel. The kernels are compiled for AVX2 and for the
// x86-64 baseline (SSE2) and chosen at load time by the dynamic linker (GCC target_clones), so
// one binary runs on any x86-64 and uses the wider registers where they exist.

template <class Pixel>
constexpr int kBlock = 64 / static_cast<int>(sizeof(Pixel));

// Appends the runs [x0, x1) of pixels above threshold within [begin, end) to `out` as pairs and
// returns the number of ints written. `map` is the per-pixel threshold row or null for `scalar`.
template <class Pixel, bool kMap>
[[gnu::always_inline]] inline int scan_row(const Pixel* row, const Pixel* map, Pixel scalar, int begin,
                                           int end, int* out) {
  const auto above = [&](int x) { return row[x] > (kMap ? map[x] : scalar); };
  int written = 0;
  int x = begin;
  while (x < end) {
    // Skip dark blocks. The accumulators stay in the pixel type so the vectoriser keeps one
    // lane per pixel (widening to int would quarter the throughput).
    while (x + kBlock<Pixel> <= end) {
      Pixel any = 0;
      if constexpr (kMap) {
        for (int i = 0; i < kBlock<Pixel>; ++i) any |= static_cast<Pixel>(row[x + i] > map[x + i]);
      } else {
        for (int i = 0; i < kBlock<Pixel>; ++i) any = std::max(any, row[x + i]);
        any = static_cast<Pixel>(any > scalar);
      }
      if (any != 0) break;
      x += kBlock<Pixel>;
    }
    const int block_end = std::min(end, x + kBlock<Pixel>);
    while (x < block_end && !above(x)) ++x;
    if (x >= block_end) continue;
    const int x0 = x;
    while (x < end && above(x)) ++x;
    out[written++] = x0;
    out[written++] = x;
  }
  return written;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
#define PANOPTES_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PANOPTES_CLONES
#endif

PANOPTES_CLONES int scan_row_u8(const std::uint8_t* row, const std::uint8_t* map, std::uint8_t scalar,
                                int begin, int end, int* out) {
  return map != nullptr ? scan_row<std::uint8_t, true>(row, map, scalar, begin, end, out)
                        : scan_row<std::uint8_t, false>(row, map, scalar, begin, end, out);
}

PANOPTES_CLONES int scan_row_u16(const std::uint16_t* row, const std::uint16_t* map, std::uint16_t scalar,
                                 int begin, int end, int* out) {
  return map != nullptr ? scan_row<std::uint16_t, true>(row, map, scalar, begin, end, out)
                        : scan_row<std::uint16_t, false>(row, map, scalar, begin, end, out);
}

template <class Pixel>
const Pixel* row_of(const Image& image, int y) {
  if constexpr (sizeof(Pixel) == 1) {
    return image.row8(y);
  } else {
    return image.row16(y);
  }
}

template <class Pixel>
int scan(const Image& image, const Image& map, int scalar, int y, int begin, int end, int* out) {
  const Pixel* threshold_row = map.data.empty() ? nullptr : row_of<Pixel>(map, y);
  if constexpr (sizeof(Pixel) == 1) {
    return scan_row_u8(image.row8(y), threshold_row, static_cast<std::uint8_t>(scalar), begin, end, out);
  } else {
    return scan_row_u16(image.row16(y), threshold_row, static_cast<std::uint16_t>(scalar), begin, end, out);
  }
}

template <CentroidWeighting kWeighting>
inline double weight_of(int intensity, int threshold) {
  if constexpr (kWeighting == CentroidWeighting::kIntensitySquared) {
    // Seed 004 §2.2.1 eq. 2: squaring suppresses the flickering dim border pixels. Done in double
    // because 16-bit I^2 sums overflow 32 bits.
    const double value = intensity;
    return value * value;
  } else if constexpr (kWeighting == CentroidWeighting::kIntensity) {
    return intensity;
  } else {
    return intensity - threshold;
  }
}

// Even-odd rule on pixel centres: fills [x_begin, x_end) ranges of row y inside the polygon.
template <class Fill>
void rasterise_polygon_row(const std::vector<std::array<double, 2>>& polygon, int y, int width, Fill&& fill) {
  std::vector<double> crossings;
  const double yc = y;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = polygon[i];
    const auto& b = polygon[(i + 1) % polygon.size()];
    if ((a[1] <= yc) == (b[1] <= yc)) continue;  // edge does not straddle the row's centre line
    crossings.push_back(a[0] + (yc - a[1]) * (b[0] - a[0]) / (b[1] - a[1]));
  }
  std::sort(crossings.begin(), crossings.end());
  for (std::size_t i = 0; i + 1 < crossings.size(); i += 2) {
    const int x_begin = std::max(0, static_cast<int>(std::ceil(crossings[i])));
    const int x_end = std::min(width, static_cast<int>(std::floor(crossings[i + 1])) + 1);
    if (x_begin < x_end) fill(x_begin, x_end);
  }
}

}  // namespace

Detector::Detector(DetectorConfig config) : config_(std::move(config)) {}

void Detector::set_threshold(int threshold) {
  config_.threshold = std::max(0, threshold);
  threshold_map_dirty_ = true;
}

void Detector::set_relative_threshold(int threshold) {
  config_.relative_threshold = std::max(0, threshold);
  threshold_map_dirty_ = true;
}

void Detector::capture_background(int frames) {
  background_frames_left_ = std::max(1, frames);
  pending_background_ = Image();
}

void Detector::set_background(const Image& background) {
  background_ = background;
  background_frames_left_ = 0;
  pending_background_ = Image();
  threshold_map_dirty_ = true;
}

void Detector::clear_background() {
  background_ = Image();
  background_frames_left_ = 0;
  pending_background_ = Image();
  threshold_map_dirty_ = true;
}

void Detector::set_masks(std::vector<MaskRegion> masks) {
  config_.masks = std::move(masks);
  threshold_map_dirty_ = true;
}

void Detector::add_mask(const MaskRegion& mask) {
  config_.masks.push_back(mask);
  threshold_map_dirty_ = true;
}

void Detector::clear_masks() {
  config_.masks.clear();
  threshold_map_dirty_ = true;
}

// T(x, y) = max(B(x, y) + T_r, T_a), and "never" inside a blind region (seed 003 §2.2.2).
void Detector::rebuild_threshold_map(const Image& image) {
  threshold_map_dirty_ = false;
  const bool use_background = has_background() && background_.width == image.width &&
                              background_.height == image.height && background_.bits == image.bits;
  if (!use_background && config_.masks.empty()) {
    threshold_map_ = Image();
    return;
  }
  threshold_map_ = Image(image.width, image.height, image.bits);
  const int never = image.bytes_per_pixel() == 1 ? 0xff : 0xffff;  // no pixel can exceed it
  const int relative = config_.relative_threshold_for_bits(image.bits);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      int value = threshold_;
      if (use_background) {
        const int b = background_.bytes_per_pixel() == 1 ? background_.row8(y)[x] : background_.row16(y)[x];
        value = std::max(value, b + relative);
      }
      value = std::min(value, never);
      if (threshold_map_.bytes_per_pixel() == 1) {
        threshold_map_.row8(y)[x] = static_cast<std::uint8_t>(value);
      } else {
        threshold_map_.row16(y)[x] = static_cast<std::uint16_t>(value);
      }
    }
  }
  const auto blind = [&](int y, int x_begin, int x_end) {
    for (int x = x_begin; x < x_end; ++x) {
      if (threshold_map_.bytes_per_pixel() == 1) {
        threshold_map_.row8(y)[x] = static_cast<std::uint8_t>(never);
      } else {
        threshold_map_.row16(y)[x] = static_cast<std::uint16_t>(never);
      }
    }
  };
  for (const MaskRegion& mask : config_.masks) {
    if (mask.is_polygon()) {
      for (int y = 0; y < image.height; ++y) {
        rasterise_polygon_row(mask.polygon, y, image.width, [&](int a, int b) { blind(y, a, b); });
      }
    } else {
      const int x_begin = std::clamp(mask.x0, 0, image.width), x_end = std::clamp(mask.x1, 0, image.width);
      for (int y = std::clamp(mask.y0, 0, image.height); y < std::clamp(mask.y1, 0, image.height); ++y) {
        blind(y, x_begin, x_end);
      }
    }
  }
}

void Detector::prepare(const Image& image) {
  if (image.width < 0 || image.height < 0 || image.width > 65535 || image.height > 65535 ||
      image.data.size() < static_cast<std::size_t>(image.height) * image.stride()) {
    throw std::invalid_argument("Detector::detect: image buffer smaller than " + std::to_string(image.width) +
                                "x" + std::to_string(image.height) + " or larger than 65535 px a side");
  }
  const int threshold = config_.threshold_for_bits(image.bits);
  if (threshold != threshold_) {
    threshold_ = threshold;
    threshold_map_dirty_ = true;
  }
  if (!threshold_map_.data.empty() &&
      (threshold_map_.width != image.width || threshold_map_.height != image.height ||
       threshold_map_.bits != image.bits)) {
    threshold_map_dirty_ = true;
  }
  if (threshold_map_dirty_) rebuild_threshold_map(image);
  stats_ = DetectionStats{};
  runs_.clear();
  moments_.clear();
}

template <class Pixel>
void Detector::find_runs(const Image& image) {
  row_start_.assign(static_cast<std::size_t>(image.height) + 1, 0);
  std::vector<int>& pairs = stack_;  // scratch: at most width/2 + 1 runs per row
  pairs.resize(static_cast<std::size_t>(image.width) + 2);
  const int scalar = std::min<int>(threshold_, std::numeric_limits<Pixel>::max());
  for (int y = 0; y < image.height; ++y) {
    row_start_[y] = static_cast<int>(runs_.size());
    const int written = scan<Pixel>(image, threshold_map_, scalar, y, 0, image.width, pairs.data());
    for (int i = 0; i < written; i += 2) {
      const int index = static_cast<int>(runs_.size());
      runs_.push_back(Run{y, pairs[i], pairs[i + 1], index});
    }
  }
  row_start_[image.height] = static_cast<int>(runs_.size());
  stats_.pixels_scanned = static_cast<std::int64_t>(image.width) * image.height;
}

void Detector::label_components() {
  // Union by smaller index keeps every parent index below its child's, so each root is its
  // component's first run in raster order and one forward pass can resolve all labels.
  const auto find = [this](int i) {
    while (runs_[i].parent != i) {
      runs_[i].parent = runs_[runs_[i].parent].parent;
      i = runs_[i].parent;
    }
    return i;
  };
  const auto unite = [this, &find](int a, int b) {
    a = find(a);
    b = find(b);
    if (a < b) {
      runs_[b].parent = a;
    } else if (b < a) {
      runs_[a].parent = b;
    }
  };

  const int rows = static_cast<int>(row_start_.size()) - 1;
  for (int y = 1; y < rows; ++y) {
    int above = row_start_[y - 1];
    const int above_end = row_start_[y];
    int current = row_start_[y];
    const int current_end = row_start_[y + 1];
    while (above < above_end && current < current_end) {
      const Run& a = runs_[above];
      const Run& c = runs_[current];
      // 8-connectivity: runs [x0, x1) touch if they overlap or meet diagonally.
      if (a.x0 <= c.x1 && c.x0 <= a.x1) unite(above, current);
      // The run that ends first cannot touch anything further right in the other row, because
      // runs within a row are separated by at least one background pixel.
      if (a.x1 < c.x1) {
        ++above;
      } else {
        ++current;
      }
    }
  }

  // Labels are stored in `parent` as -(label + 1) so that unresolved entries (indices >= 0)
  // and resolved ones can be told apart during the single pass.
  for (int i = 0; i < static_cast<int>(runs_.size()); ++i) {
    Run& run = runs_[i];
    if (run.parent == i) {
      run.parent = -static_cast<int>(moments_.size()) - 1;
      moments_.push_back(Moments{run.x0, run.y, 0, 0, 0, 0, 0, 0, 0, 0, 0, run.x0, run.y, run.x1, run.y + 1});
    } else {
      run.parent = runs_[run.parent].parent;
    }
  }
  for (Run& run : runs_) run.parent = -run.parent - 1;
}

// Scanline growth of the component containing (seed_x, seed_y): each run found is marked in
// visited_ and its neighbours in the rows above and below are searched (8-connectivity).
template <class Pixel>
void Detector::flood_component(const Image& image, int seed_x, int seed_y) {
  const int width = image.width;
  const bool has_map = !threshold_map_.data.empty();
  const int scalar = std::min<int>(threshold_, std::numeric_limits<Pixel>::max());
  const auto above = [&](int y, int x) {
    const int limit = has_map ? row_of<Pixel>(threshold_map_, y)[x] : scalar;
    return row_of<Pixel>(image, y)[x] > limit;
  };
  const int component = static_cast<int>(moments_.size());
  const auto take_run = [&](int y, int x) {
    int x0 = x, x1 = x + 1;
    while (x0 > 0 && above(y, x0 - 1)) --x0;
    while (x1 < width && above(y, x1)) ++x1;
    std::fill(visited_.begin() + static_cast<std::ptrdiff_t>(y) * width + x0,
              visited_.begin() + static_cast<std::ptrdiff_t>(y) * width + x1, std::uint8_t{1});
    stack_.push_back(static_cast<int>(runs_.size()));
    runs_.push_back(Run{y, x0, x1, component});
    return x1;
  };
  moments_.push_back(
      Moments{seed_x, seed_y, 0, 0, 0, 0, 0, 0, 0, 0, 0, seed_x, seed_y, seed_x + 1, seed_y + 1});
  stack_.clear();
  take_run(seed_y, seed_x);
  while (!stack_.empty()) {
    const Run run = runs_[stack_.back()];
    stack_.pop_back();
    for (const int y : {run.y - 1, run.y + 1}) {
      if (y < 0 || y >= image.height) continue;
      const std::uint8_t* seen = visited_.data() + static_cast<std::ptrdiff_t>(y) * width;
      for (int x = std::max(0, run.x0 - 1); x < std::min(width, run.x1 + 1); ++x) {
        if (seen[x] == 0 && above(y, x)) x = take_run(y, x);
      }
    }
  }
}

template <class Pixel>
void Detector::find_runs_guided(const Image& image, std::span<const SearchWindow> windows) {
  stats_.guided = true;
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  if (visited_.size() != pixels) visited_.assign(pixels, 0);
  std::vector<int> pairs(static_cast<std::size_t>(image.width) + 2);
  const int scalar = std::min<int>(threshold_, std::numeric_limits<Pixel>::max());
  const auto search = [&](int y, int x_begin, int x_end) {
    stats_.pixels_scanned += x_end - x_begin;
    const int written = scan<Pixel>(image, threshold_map_, scalar, y, x_begin, x_end, pairs.data());
    for (int i = 0; i < written; i += 2) {
      // Any pixel of a run already taken means the whole run belongs to a known component.
      const int x0 = pairs[i];
      if (visited_[static_cast<std::size_t>(y) * image.width + x0] == 0) flood_component<Pixel>(image, x0, y);
    }
  };
  // 1. Windows around predicted positions.
  for (const SearchWindow& window : windows) {
    if (!(std::isfinite(window.x) && std::isfinite(window.y) && window.half_width >= 0 &&
          window.half_height >= 0)) {
      continue;
    }
    // Clamped in double first: a wild prediction must not overflow the int conversion.
    const auto bound = [](double value, int limit) {
      return static_cast<int>(std::clamp(value, 0.0, static_cast<double>(limit)));
    };
    const int x_begin = bound(std::floor(window.x - window.half_width), image.width);
    const int x_end = bound(std::ceil(window.x + window.half_width) + 1, image.width);
    const int y_begin = bound(std::floor(window.y - window.half_height), image.height);
    const int y_end = bound(std::ceil(window.y + window.half_height) + 1, image.height);
    if (x_begin >= x_end) continue;
    for (int y = y_begin; y < y_end; ++y) search(y, x_begin, x_end);
  }
  // 2. The coarse grid over the whole frame finds what no prediction covered (new markers).
  const int step = std::max(1, config_.grid_step);
  for (int y = step / 2; y < image.height; y += step) search(y, 0, image.width);
  // Leave visited_ all zero for the next frame, touching only what was set.
  for (const Run& run : runs_) {
    std::fill(visited_.begin() + static_cast<std::ptrdiff_t>(run.y) * image.width + run.x0,
              visited_.begin() + static_cast<std::ptrdiff_t>(run.y) * image.width + run.x1, std::uint8_t{0});
  }
}

template <class Pixel, CentroidWeighting kWeighting>
void Detector::accumulate_moments(const Image& image, int threshold) {
  for (const Run& run : runs_) {
    Moments& m = moments_[run.parent];
    const Pixel* row = row_of<Pixel>(image, run.y);
    // y is constant along a run, so only the x sums need a per-pixel loop.
    double weight = 0, weight_x = 0, weight_xx = 0, sum = 0;
    int peak = 0;
    for (int x = run.x0; x < run.x1; ++x) {
      const int intensity = row[x];
      const double w = weight_of<kWeighting>(intensity, threshold);
      const double dx = x - m.origin_x;
      weight += w;
      weight_x += w * dx;
      weight_xx += w * dx * dx;
      sum += intensity;
      peak = std::max(peak, intensity);
    }
    const double dy = run.y - m.origin_y;
    m.weight += weight;
    m.weight_x += weight_x;
    m.weight_y += weight * dy;
    m.weight_xx += weight_xx;
    m.weight_xy += weight_x * dy;
    m.weight_yy += weight * dy * dy;
    m.sum += sum;
    m.area += run.x1 - run.x0;
    m.peak = std::max(m.peak, peak);
    m.x0 = std::min(m.x0, run.x0);
    m.x1 = std::max(m.x1, run.x1);
    m.y0 = std::min(m.y0, run.y);
    m.y1 = std::max(m.y1, run.y + 1);
  }
}

// The pixels above threshold are the Gaussian cut at T, and which pixels make the cut depends on
// the sub-pixel position: a centroid over them alone carries an error of a few hundredths of a
// pixel (0.034 px RMS at T = 25% full scale with I^2). Over the bounding box grown by a margin,
// with the local background (median of the grown box's border) subtracted and weights
// (I - b)^2 (or I - b), the profile's tails are included symmetrically and that error vanishes
// (0.002 px noise-free). Skipped when the grown box touches another component, whose light
// would pull the centroid.
template <class Pixel>
void Detector::refine_centroid(const Image& image, Blob& blob, std::size_t component) const {
  const int margin = config_.refine_margin;
  const int x_begin = std::max(0, blob.x0 - margin), x_end = std::min(image.width, blob.x1 + margin);
  const int y_begin = std::max(0, blob.y0 - margin), y_end = std::min(image.height, blob.y1 + margin);
  for (std::size_t other = 0; other < moments_.size(); ++other) {
    if (other == component) continue;
    const Moments& m = moments_[other];
    if (m.x0 < x_end && x_begin < m.x1 && m.y0 < y_end && y_begin < m.y1) return;
  }
  // Median of the border: robust to a neighbouring blob's tail on one side.
  thread_local std::vector<int> border;
  border.clear();
  for (int x = x_begin; x < x_end; ++x) {
    border.push_back(row_of<Pixel>(image, y_begin)[x]);
    if (y_end - 1 > y_begin) border.push_back(row_of<Pixel>(image, y_end - 1)[x]);
  }
  for (int y = y_begin + 1; y < y_end - 1; ++y) {
    border.push_back(row_of<Pixel>(image, y)[x_begin]);
    if (x_end - 1 > x_begin) border.push_back(row_of<Pixel>(image, y)[x_end - 1]);
  }
  if (border.empty()) return;
  const auto middle = border.begin() + static_cast<std::ptrdiff_t>(border.size() / 2);
  std::nth_element(border.begin(), middle, border.end());
  const double background = *middle;
  const bool squared = config_.weighting == CentroidWeighting::kIntensitySquared;
  double weight = 0, weight_x = 0, weight_y = 0;
  for (int y = y_begin; y < y_end; ++y) {
    const Pixel* row = row_of<Pixel>(image, y);
    double row_weight = 0, row_weight_x = 0;
    for (int x = x_begin; x < x_end; ++x) {
      const double above = std::max(0.0, row[x] - background);
      const double w = squared ? above * above : above;
      row_weight += w;
      row_weight_x += w * (x - x_begin);
    }
    weight += row_weight;
    weight_x += row_weight_x;
    weight_y += row_weight * (y - y_begin);
  }
  if (!(weight > 0)) return;
  blob.x = x_begin + weight_x / weight;
  blob.y = y_begin + weight_y / weight;
}

void Detector::emit_blobs(const Image& image, std::vector<Blob>& blobs) {
  stats_.components = static_cast<int>(moments_.size());
  const bool refine = config_.refine_margin > 0 && config_.weighting != CentroidWeighting::kAboveThreshold;
  for (std::size_t i = 0; i < moments_.size(); ++i) {
    const Moments& m = moments_[i];
    const bool rejected = m.area < config_.min_area || m.area > config_.max_area ||
                          (config_.min_peak > 0 && m.peak < config_.min_peak) || !(m.weight > 0);
    if (rejected) {
      ++stats_.rejected;
      continue;
    }
    const double mean_x = m.weight_x / m.weight;
    const double mean_y = m.weight_y / m.weight;
    Blob blob;
    blob.x = m.origin_x + mean_x;
    blob.y = m.origin_y + mean_y;
    blob.area = m.area;
    blob.sum = m.sum;
    blob.peak = m.peak;
    blob.m20 = std::max(0.0, m.weight_xx / m.weight - mean_x * mean_x);
    blob.m11 = m.weight_xy / m.weight - mean_x * mean_y;
    blob.m02 = std::max(0.0, m.weight_yy / m.weight - mean_y * mean_y);
    blob.x0 = m.x0;
    blob.y0 = m.y0;
    blob.x1 = m.x1;
    blob.y1 = m.y1;
    if (config_.max_elongation > 0) {
      // Each pixel is a unit square, not a point: adding its own variance (1/12) keeps one- and
      // two-pixel blobs from looking infinitely elongated.
      const double a = blob.m20 + 1.0 / 12.0;
      const double c = blob.m02 + 1.0 / 12.0;
      const double half_trace = 0.5 * (a + c);
      const double radius = std::hypot(0.5 * (a - c), blob.m11);
      const double major = half_trace + radius;
      const double minor = half_trace - radius;
      if (!(minor > 0) || std::sqrt(major / minor) > config_.max_elongation) {
        ++stats_.rejected;
        continue;
      }
    }
    if (refine) {
      if (image.bytes_per_pixel() == 2) {
        refine_centroid<std::uint16_t>(image, blob, i);
      } else {
        refine_centroid<std::uint8_t>(image, blob, i);
      }
    }
    blobs.push_back(blob);
  }
}

std::vector<Blob> Detector::finish(const Image& image) {
  // The weighting is a template parameter so the per-pixel loop carries no branch on it.
  const auto accumulate = [&]<class Pixel>() {
    switch (config_.weighting) {
      case CentroidWeighting::kIntensitySquared:
        accumulate_moments<Pixel, CentroidWeighting::kIntensitySquared>(image, threshold_);
        break;
      case CentroidWeighting::kIntensity:
        accumulate_moments<Pixel, CentroidWeighting::kIntensity>(image, threshold_);
        break;
      case CentroidWeighting::kAboveThreshold:
        accumulate_moments<Pixel, CentroidWeighting::kAboveThreshold>(image, threshold_);
        break;
    }
  };
  if (image.bytes_per_pixel() == 2) {
    accumulate.template operator()<std::uint16_t>();
  } else {
    accumulate.template operator()<std::uint8_t>();
  }
  std::vector<Blob> blobs;
  blobs.reserve(moments_.size());
  emit_blobs(image, blobs);

  // Fold this frame into a background being captured (per-pixel maximum, so a flickering
  // light is covered at its brightest); it takes effect from the next frame.
  if (background_frames_left_ > 0) {
    if (pending_background_.width != image.width || pending_background_.height != image.height ||
        pending_background_.bits != image.bits || pending_background_.data.empty()) {
      pending_background_ = image;
    } else if (image.bytes_per_pixel() == 1) {
      for (std::size_t i = 0; i < image.data.size(); ++i) {
        pending_background_.data[i] = std::max(pending_background_.data[i], image.data[i]);
      }
    } else {
      for (int y = 0; y < image.height; ++y) {
        std::uint16_t* to = pending_background_.row16(y);
        const std::uint16_t* from = image.row16(y);
        for (int x = 0; x < image.width; ++x) to[x] = std::max(to[x], from[x]);
      }
    }
    if (--background_frames_left_ == 0) {
      background_ = std::move(pending_background_);
      pending_background_ = Image();
      threshold_map_dirty_ = true;
    }
  }
  return blobs;
}

std::vector<Blob> Detector::detect(const Image& image) {
  prepare(image);
  if (image.bytes_per_pixel() == 2) {
    find_runs<std::uint16_t>(image);
  } else {
    find_runs<std::uint8_t>(image);
  }
  label_components();
  return finish(image);
}

std::vector<Blob> Detector::detect(const Image& image, std::span<const SearchWindow> windows) {
  if (windows.empty()) return detect(image);
  prepare(image);
  if (image.bytes_per_pixel() == 2) {
    find_runs_guided<std::uint16_t>(image, windows);
  } else {
    find_runs_guided<std::uint8_t>(image, windows);
  }
  return finish(image);
}

}  // namespace panoptes::camera
