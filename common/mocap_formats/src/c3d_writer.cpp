// SPDX-License-Identifier: Apache-2.0
// C3D writer: Intel byte order, floating-point point storage (POINT:SCALE < 0) with the residual
// and camera mask word of each point, an ANALOG group with no channels.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "c3d_bytes.h"
#include "panoptes/errors.h"
#include "panoptes/formats/c3d.h"

namespace panoptes {

namespace {

using c3d::kBlockBytes;

constexpr std::size_t kMaxPointsPerLabelParameter = 255;
constexpr std::size_t kMaxLabelLength = 255;
constexpr std::size_t kMaxHeaderFrames = 65535;
constexpr std::size_t kMaxPoints = 32767;

// Builds the parameter section: records of groups and parameters, each pointing to the next.
class ParameterSection {
 public:
  ParameterSection() : bytes_(4, 0) {}

  void group(int id, const std::string& name, const std::string& description) {
    begin_record(-id, name);
    end_record(description);
  }
  void integers(int group, const std::string& name, const std::vector<int>& values, bool scalar = false) {
    begin_record(group, name);
    push_header(2, scalar ? std::vector<int>{} : std::vector<int>{static_cast<int>(values.size())});
    for (int value : values) push_u16(static_cast<std::uint16_t>(value));
    end_record("");
  }
  void real(int group, const std::string& name, float value) {
    begin_record(group, name);
    push_header(4, {});
    std::uint8_t b[4];
    c3d::put_float(b, value);
    bytes_.insert(bytes_.end(), b, b + 4);
    end_record("");
  }
  void text(int group, const std::string& name, const std::string& value) {
    begin_record(group, name);
    push_header(-1, {static_cast<int>(value.size())});
    bytes_.insert(bytes_.end(), value.begin(), value.end());
    end_record("");
  }
  // A 2-D char array: `width` characters per string, blank padded.
  void texts(int group, const std::string& name, const std::vector<std::string>& values, std::size_t width) {
    begin_record(group, name);
    push_header(-1, {static_cast<int>(width), static_cast<int>(values.size())});
    for (const std::string& value : values) {
      std::string padded = value.substr(0, width);
      padded.resize(width, ' ');
      bytes_.insert(bytes_.end(), padded.begin(), padded.end());
    }
    end_record("");
  }
  // Pads to whole blocks and fills the section's 4-byte header; returns the block count.
  std::vector<std::uint8_t> finish(std::size_t& blocks) {
    if (last_pointer_ != 0) c3d::put_u16(&bytes_[last_pointer_], 0);  // the last record points nowhere
    blocks = (bytes_.size() + kBlockBytes - 1) / kBlockBytes;
    bytes_.resize(blocks * kBlockBytes, 0);
    bytes_[0] = 1;
    bytes_[1] = c3d::kParameterKey;
    bytes_[2] = static_cast<std::uint8_t>(blocks);
    bytes_[3] = static_cast<std::uint8_t>(c3d::kProcessorBase + 1);  // Intel
    return std::move(bytes_);
  }

 private:
  void begin_record(int id, const std::string& name) {
    bytes_.push_back(static_cast<std::uint8_t>(name.size()));
    bytes_.push_back(static_cast<std::uint8_t>(static_cast<std::int8_t>(id)));
    bytes_.insert(bytes_.end(), name.begin(), name.end());
    last_pointer_ = bytes_.size();
    push_u16(0);
  }
  void push_header(int type, const std::vector<int>& dimensions) {
    bytes_.push_back(static_cast<std::uint8_t>(static_cast<std::int8_t>(type)));
    bytes_.push_back(static_cast<std::uint8_t>(dimensions.size()));
    for (int d : dimensions) bytes_.push_back(static_cast<std::uint8_t>(d));
  }
  void end_record(const std::string& description) {
    bytes_.push_back(static_cast<std::uint8_t>(description.size()));
    bytes_.insert(bytes_.end(), description.begin(), description.end());
    c3d::put_u16(&bytes_[last_pointer_], static_cast<std::uint16_t>(bytes_.size() - last_pointer_));
  }
  void push_u16(std::uint16_t value) {
    bytes_.push_back(static_cast<std::uint8_t>(value & 0xff));
    bytes_.push_back(static_cast<std::uint8_t>(value >> 8));
  }

  std::vector<std::uint8_t> bytes_;
  std::size_t last_pointer_ = 0;
};

enum Group { kPoint = 1, kAnalog = 2, kTrial = 3, kManufacturer = 4 };

void check_input(const MarkerTrajectories& data, const C3dWriteOptions& options, const std::string& name) {
  auto fail = [&](const std::string& reason) { throw ConfigError(name, "", reason); };
  if (data.marker_count() == 0) fail("no markers to write");
  if (data.marker_count() > kMaxPoints) fail("more than 32767 markers");
  if (!(std::isfinite(data.data_rate_hz) && data.data_rate_hz > 0.0)) fail("the rate must be positive");
  if (data.frame_count() == 0) fail("no frames to write");
  if (data.positions.size() != data.frame_count() * data.marker_count() ||
      data.valid.size() != data.positions.size()) {
    fail("positions and validity do not match frames x markers");
  }
  if (metres_per_unit(options.units) == 0.0) fail("units '" + options.units + "' (expected mm, cm or m)");
}

// |POINT:SCALE|: the largest coordinate / 32000, as the format asks of float files too (it scales
// the residuals and any later conversion to integers).
float point_scale(const MarkerTrajectories& data, double units_per_metre) {
  double largest = 0.0;
  for (std::size_t i = 0; i < data.positions.size(); ++i) {
    if (data.valid[i] != 0) largest = std::max(largest, data.positions[i].cwiseAbs().maxCoeff());
  }
  const double scale = largest * units_per_metre / 32000.0;
  return scale > 0.0 ? static_cast<float>(scale) : 1.0F;
}

std::vector<std::uint8_t> parameters(const MarkerTrajectories& data, const C3dWriteOptions& options,
                                     float scale, std::size_t& blocks) {
  ParameterSection section;
  const std::size_t frames = data.frame_count();
  const std::size_t points = data.marker_count();
  section.group(kPoint, "POINT", "3-D point parameters");
  section.integers(kPoint, "USED", {static_cast<int>(points)}, true);
  section.real(kPoint, "SCALE", -scale);
  section.real(kPoint, "RATE", static_cast<float>(data.data_rate_hz));
  section.integers(kPoint, "DATA_START", {0}, true);  // patched below once the size is known
  section.integers(kPoint, "FRAMES", {static_cast<int>(std::min(frames, kMaxHeaderFrames))}, true);
  section.text(kPoint, "UNITS", options.units);
  std::size_t width = 1;
  for (const std::string& label : data.marker_names)
    width = std::max(width, std::min(label.size(), kMaxLabelLength));
  for (std::size_t first = 0, index = 1; first < points; first += kMaxPointsPerLabelParameter, ++index) {
    const std::size_t last = std::min(points, first + kMaxPointsPerLabelParameter);
    const std::vector<std::string> labels(data.marker_names.begin() + static_cast<std::ptrdiff_t>(first),
                                          data.marker_names.begin() + static_cast<std::ptrdiff_t>(last));
    const std::string suffix = index == 1 ? "" : std::to_string(index);
    section.texts(kPoint, "LABELS" + suffix, labels, width);
    section.texts(kPoint, "DESCRIPTIONS" + suffix, std::vector<std::string>(labels.size(), ""), 1);
  }
  section.group(kAnalog, "ANALOG", "analog data parameters (no channels)");
  section.integers(kAnalog, "USED", {0}, true);
  section.real(kAnalog, "RATE", static_cast<float>(data.data_rate_hz));
  section.real(kAnalog, "GEN_SCALE", 1.0F);
  section.group(kTrial, "TRIAL", "trial parameters");
  const auto last_frame = static_cast<std::uint32_t>(frames);
  section.integers(kTrial, "ACTUAL_START_FIELD", {1, 0});
  section.integers(kTrial, "ACTUAL_END_FIELD",
                   {static_cast<int>(last_frame & 0xffff), static_cast<int>(last_frame >> 16)});
  section.real(kTrial, "CAMERA_RATE", static_cast<float>(data.data_rate_hz));
  section.group(kManufacturer, "MANUFACTURER", "the writer");
  section.text(kManufacturer, "COMPANY", "Panoptes");
  section.text(kManufacturer, "SOFTWARE", options.software);
  return section.finish(blocks);
}

void patch_data_start(std::vector<std::uint8_t>& section, std::uint16_t block) {
  // Find the POINT:DATA_START record: name length 10, group 1, "DATA_START", pointer, type 2, 0 dims.
  const std::string key = "DATA_START";
  for (std::size_t i = 4; i + 2 + key.size() + 6 <= section.size(); ++i) {
    if (section[i] == key.size() && section[i + 1] == kPoint &&
        std::equal(key.begin(), key.end(), section.begin() + static_cast<std::ptrdiff_t>(i + 2))) {
      c3d::put_u16(&section[i + 2 + key.size() + 4], block);
      return;
    }
  }
}

void write_header(std::uint8_t* header, const MarkerTrajectories& data, float scale,
                  std::uint16_t data_block) {
  header[0] = 2;  // the parameter section starts at block 2
  header[1] = c3d::kParameterKey;
  c3d::put_u16(header + 2, static_cast<std::uint16_t>(data.marker_count()));
  c3d::put_u16(header + 4, 0);  // analog samples per frame, all channels
  c3d::put_u16(header + 6, 1);  // first frame
  c3d::put_u16(header + 8, static_cast<std::uint16_t>(std::min(data.frame_count(), kMaxHeaderFrames)));
  c3d::put_u16(header + 10, 0);  // largest interpolation gap
  c3d::put_float(header + 12, -scale);
  c3d::put_u16(header + 16, data_block);
  c3d::put_u16(header + 18, 0);  // analog samples per channel and frame
  c3d::put_float(header + 20, static_cast<float>(data.data_rate_hz));
}

// The fourth word of a point: camera mask (high byte) and residual / |scale| (low byte) as a float;
// -1 for an invalid point. A measured point never rounds to residual 0 ("computed").
float residual_word(const MarkerTrajectories& data, std::size_t sample, double units_per_metre, float scale) {
  if (data.valid[sample] == 0) return -1.0F;
  int residual = 0;
  int mask = 0;
  if (!data.residuals_m.empty() && data.residuals_m[sample] > 0.0F) {
    const double steps = data.residuals_m[sample] * units_per_metre / scale;
    residual = static_cast<int>(std::clamp(std::lround(steps), 1L, 255L));
  }
  if (!data.camera_masks.empty()) mask = data.camera_masks[sample] & 0x7f;
  return static_cast<float>((mask << 8) | residual);
}

}  // namespace

std::vector<std::uint8_t> encode_c3d(const MarkerTrajectories& data, const C3dWriteOptions& options,
                                     const std::string& name_for_errors) {
  check_input(data, options, name_for_errors);
  const double units_per_metre = 1.0 / metres_per_unit(options.units);
  const float scale = point_scale(data, units_per_metre);
  std::size_t parameter_blocks = 0;
  std::vector<std::uint8_t> section = parameters(data, options, scale, parameter_blocks);
  if (parameter_blocks > 255)
    throw ConfigError(name_for_errors, "", "too many labels for the parameter section");
  const auto data_block = static_cast<std::uint16_t>(2 + parameter_blocks);
  patch_data_start(section, data_block);

  const std::size_t samples = data.positions.size();
  std::vector<std::uint8_t> bytes(kBlockBytes + section.size() + samples * 16, 0);
  write_header(bytes.data(), data, scale, data_block);
  std::copy(section.begin(), section.end(), bytes.begin() + kBlockBytes);
  std::uint8_t* out = bytes.data() + kBlockBytes + section.size();
  for (std::size_t sample = 0; sample < samples; ++sample, out += 16) {
    const bool valid = data.valid[sample] != 0;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double value =
          valid ? data.positions[sample][static_cast<Eigen::Index>(axis)] * units_per_metre : 0.0;
      c3d::put_float(out + 4 * axis, static_cast<float>(value));
    }
    c3d::put_float(out + 12, residual_word(data, sample, units_per_metre, scale));
  }
  return bytes;
}

void write_c3d(const std::filesystem::path& path, const MarkerTrajectories& data,
               const C3dWriteOptions& options) {
  const std::vector<std::uint8_t> bytes = encode_c3d(data, options, path.string());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw ConfigError(path.string(), "", "cannot open for writing");
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw ConfigError(path.string(), "", "write failed (disk full?)");
}

}  // namespace panoptes
