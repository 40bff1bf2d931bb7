// SPDX-License-Identifier: Apache-2.0
// DetectorConfig defaults and YAML, and blind-region (mask) parsing.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>
#include "panoptes/camera/detector.h"

#include "panoptes/config.h"

namespace panoptes::camera {

namespace {

long long full_scale_of(int bits) {
  return 1LL << std::clamp(bits, 1, 30);
}

}  // namespace

int DetectorConfig::threshold_for_bits(int bits) const {
  if (threshold > 0) return threshold;
  // 25% of full scale keeps the default meaningful whatever the sensor's bit depth.
  return static_cast<int>(full_scale_of(bits) / 4);
}

int DetectorConfig::relative_threshold_for_bits(int bits) const {
  if (relative_threshold > 0) return relative_threshold;
  return static_cast<int>(std::max<long long>(1, full_scale_of(bits) * 2 / 25));  // 8%: 20 DN at 8 bits
}

MaskRegion MaskRegion::parse(const std::string& text) {
  std::istringstream in(text);
  std::string kind;
  in >> kind;
  std::vector<double> numbers;
  std::string token;
  while (in >> token) {
    try {
      std::size_t used = 0;
      const double value = std::stod(token, &used);
      if (used != token.size() || !std::isfinite(value)) throw std::invalid_argument(token);
      numbers.push_back(value);
    } catch (const std::exception&) {
      throw std::invalid_argument(
          std::string("mask '").append(text).append("': '").append(token).append("' is not a number"));
    }
  }
  if (kind == "rect") {
    if (numbers.size() != 4 || numbers[2] <= 0 || numbers[3] <= 0) {
      throw std::invalid_argument("mask '" + text +
                                  "': expected rect <x> <y> <width> <height> (width, height > 0)");
    }
    return rectangle(static_cast<int>(std::floor(numbers[0])), static_cast<int>(std::floor(numbers[1])),
                     static_cast<int>(std::ceil(numbers[2])), static_cast<int>(std::ceil(numbers[3])));
  }
  if (kind == "poly") {
    if (numbers.size() < 6 || numbers.size() % 2 != 0) {
      throw std::invalid_argument("mask '" + text + "': expected poly <x1> <y1> <x2> <y2> <x3> <y3> ...");
    }
    MaskRegion region;
    for (std::size_t i = 0; i < numbers.size(); i += 2)
      region.polygon.push_back({numbers[i], numbers[i + 1]});
    return region;
  }
  throw std::invalid_argument("mask '" + text + "': expected 'rect x y w h' or 'poly x1 y1 x2 y2 x3 y3 ...'");
}

std::string MaskRegion::to_string() const {
  std::ostringstream out;
  if (is_polygon()) {
    out << "poly";
    for (const auto& vertex : polygon) out << ' ' << vertex[0] << ' ' << vertex[1];
  } else {
    out << "rect " << x0 << ' ' << y0 << ' ' << (x1 - x0) << ' ' << (y1 - y0);
  }
  return out.str();
}

DetectorConfig DetectorConfig::from_yaml(const YamlReader& reader) {
  reader.expect_only({"threshold", "relative_threshold", "min_area", "max_area", "min_peak", "max_elongation",
                      "weighting", "refine_margin", "grid_step", "masks"});
  DetectorConfig config;
  const auto read_int = [&reader](const std::string& key, int fallback, long long minimum,
                                  long long maximum) {
    const long long value = reader.get_int(key, fallback);
    if (value < minimum || value > maximum) {
      reader.fail(key,
                  "must be an integer in [" + std::to_string(minimum) + ", " + std::to_string(maximum) + "]");
    }
    return static_cast<int>(value);
  };
  constexpr long long kMaxDn = 65535;
  config.threshold = read_int("threshold", config.threshold, 0, kMaxDn);
  config.relative_threshold = read_int("relative_threshold", config.relative_threshold, 0, kMaxDn);
  config.min_area = read_int("min_area", config.min_area, 1, std::numeric_limits<int>::max());
  config.max_area = read_int("max_area", config.max_area, 1, std::numeric_limits<int>::max());
  if (config.max_area < config.min_area) {
    reader.fail("max_area", "must not be smaller than min_area (" + std::to_string(config.min_area) + ")");
  }
  config.min_peak = read_int("min_peak", config.min_peak, 0, kMaxDn);
  config.max_elongation = reader.get_double("max_elongation", config.max_elongation);
  if (!(config.max_elongation == 0 || config.max_elongation >= 1)) {
    reader.fail("max_elongation", "must be 0 (disabled) or >= 1");
  }
  config.refine_margin = read_int("refine_margin", config.refine_margin, 0, 16);
  config.grid_step = read_int("grid_step", config.grid_step, 1, 64);
  if (reader.has("weighting")) {
    const std::string weighting = reader.get_string("weighting");
    if (weighting == "i2") {
      config.weighting = CentroidWeighting::kIntensitySquared;
    } else if (weighting == "i") {
      config.weighting = CentroidWeighting::kIntensity;
    } else if (weighting == "above_threshold") {
      config.weighting = CentroidWeighting::kAboveThreshold;
    } else {
      reader.fail("weighting", "unknown weighting '" + weighting + "' (expected i2, i or above_threshold)");
    }
  }
  for (const YamlReader& item : reader.sequence_or_empty("masks")) {
    MaskRegion region;
    if (item.node().IsSequence()) {
      std::vector<double> rect;
      for (const auto& value : item.node()) {
        try {
          rect.push_back(value.as<double>());
        } catch (const std::exception&) {
          item.fail("", "expected [x, y, width, height] numbers");
        }
      }
      if (rect.size() != 4 || rect[2] <= 0 || rect[3] <= 0)
        item.fail("", "expected [x, y, width, height] with width, height > 0");
      region =
          MaskRegion::rectangle(static_cast<int>(std::floor(rect[0])), static_cast<int>(std::floor(rect[1])),
                                static_cast<int>(std::ceil(rect[2])), static_cast<int>(std::ceil(rect[3])));
    } else {
      item.expect_only({"polygon"});
      for (const auto& vertex : item.get_double_rows("polygon", 2))
        region.polygon.push_back({vertex[0], vertex[1]});
      if (region.polygon.size() < 3) item.fail("polygon", "needs at least 3 vertices");
    }
    config.masks.push_back(std::move(region));
  }
  return config;
}

}  // namespace panoptes::camera
