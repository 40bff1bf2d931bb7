// SPDX-License-Identifier: Apache-2.0
// C3D reader (c3d.org, "The C3D File Format User Guide"): header block, parameter section
// (groups and parameters), 3D point data in integer or floating-point storage. Every error names
// the file and the byte offset where reading stopped.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "c3d_bytes.h"
#include "panoptes/errors.h"
#include "panoptes/formats/c3d.h"

namespace panoptes {

namespace {

using c3d::kBlockBytes;

// Bounds-checked access to the file's bytes in the file's byte order.
class ByteReader {
 public:
  ByteReader(std::span<const std::uint8_t> bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {}

  [[noreturn]] void fail(std::size_t offset, const std::string& reason) const {
    throw ConfigError(name_, "offset " + std::to_string(offset), reason);
  }
  void need(std::size_t offset, std::size_t count, const char* what) const {
    if (offset > bytes_.size() || count > bytes_.size() - offset) {
      fail(offset, std::string("file ends inside ") + what + " (" + std::to_string(bytes_.size()) +
                       " bytes, " + std::to_string(count) + " needed here)");
    }
  }
  std::uint8_t u8(std::size_t offset, const char* what) const {
    need(offset, 1, what);
    return bytes_[offset];
  }
  // A signed byte (two's complement), widened without a signed-char conversion.
  int i8(std::size_t offset, const char* what) const {
    const int value = u8(offset, what);
    return value < 128 ? value : value - 256;
  }
  std::uint16_t u16(std::size_t offset, const char* what) const {
    need(offset, 2, what);
    return c3d::to_u16(&bytes_[offset], processor);
  }
  std::int16_t i16(std::size_t offset, const char* what) const {
    return static_cast<std::int16_t>(u16(offset, what));
  }
  float f32(std::size_t offset, const char* what) const {
    need(offset, 4, what);
    return c3d::to_float(&bytes_[offset], processor);
  }
  std::string text(std::size_t offset, std::size_t count, const char* what) const {
    need(offset, count, what);
    return {reinterpret_cast<const char*>(&bytes_[offset]), count};
  }
  std::size_t size() const { return bytes_.size(); }
  const std::string& name() const { return name_; }

  C3dProcessor processor = C3dProcessor::kIntel;

 private:
  std::span<const std::uint8_t> bytes_;
  std::string name_;
};

std::string upper_trimmed(std::string text) {
  const auto last = text.find_last_not_of(" \t\r\n");
  text.erase(last == std::string::npos ? 0 : last + 1);
  const auto first = text.find_first_not_of(" \t\r\n");
  text.erase(0, first == std::string::npos ? text.size() : first);
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return text;
}

std::string trimmed(std::string text) {
  const auto last = text.find_last_not_of(std::string(" \t\r\n\0", 5));
  text.erase(last == std::string::npos ? 0 : last + 1);
  const auto first = text.find_first_not_of(" \t\r\n");
  text.erase(0, first == std::string::npos ? text.size() : first);
  return text;
}

// Reads the value bytes of a parameter of `type` and `dimensions` at `offset`.
void read_values(const ByteReader& in, std::size_t offset, C3dParameter& parameter) {
  std::size_t count = 1;
  for (int d : parameter.dimensions) {
    count *= static_cast<std::size_t>(d);
    if (count > in.size()) in.fail(offset, "parameter '" + parameter.name + "' is larger than the file");
  }
  const int type = parameter.type;
  const std::size_t element = static_cast<std::size_t>(std::abs(type));
  in.need(offset, count * element, "a parameter's values");
  if (type == -1) {
    // Char arrays: the first dimension is the length of each string.
    const std::size_t length =
        parameter.dimensions.empty() ? count : static_cast<std::size_t>(parameter.dimensions[0]);
    if (length == 0) return;
    for (std::size_t start = 0; start + length <= count; start += length) {
      parameter.strings.push_back(trimmed(in.text(offset + start, length, "a parameter's text")));
    }
    return;
  }
  parameter.numbers.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t at = offset + i * element;
    if (type == 1) parameter.numbers.push_back(in.u8(at, "a parameter's values"));
    if (type == 2) parameter.numbers.push_back(in.i16(at, "a parameter's values"));
    if (type == 4) parameter.numbers.push_back(in.f32(at, "a parameter's values"));
  }
}

// The parameter section: records of groups (negative id) and parameters (positive id), each
// pointing to the next; a zero pointer or a zero-length name ends it.
void read_parameters(const ByteReader& in, std::size_t section, C3dFile& file) {
  std::vector<std::pair<int, std::string>> group_ids;
  struct Pending {
    int group_id;
    C3dParameter parameter;
  };
  std::vector<Pending> pending;
  std::size_t position = section + 4;
  constexpr int kMaxRecords = 100000;
  for (int record = 0; record < kMaxRecords; ++record) {
    const int name_length = in.i8(position, "the parameter section");
    if (name_length == 0) break;
    const int id = in.i8(position + 1, "the parameter section");
    const std::size_t length = static_cast<std::size_t>(std::abs(name_length));
    const std::string name = upper_trimmed(in.text(position + 2, length, "a parameter name"));
    const std::size_t pointer_at = position + 2 + length;
    const std::uint16_t pointer = in.u16(pointer_at, "a parameter record");
    if (id < 0) {
      group_ids.emplace_back(-id, name);
      file.groups.push_back(name);
    } else if (id > 0) {
      C3dParameter parameter;
      parameter.name = name;
      std::size_t at = pointer_at + 2;
      parameter.type = in.i8(at, "a parameter record");
      if (parameter.type != -1 && parameter.type != 1 && parameter.type != 2 && parameter.type != 4) {
        in.fail(at, "parameter '" + name + "' has type " + std::to_string(parameter.type) +
                        " (expected -1, 1, 2 or 4)");
      }
      const int dimension_count = in.u8(at + 1, "a parameter record");
      constexpr int kMaxDimensions = 7;
      if (dimension_count > kMaxDimensions) {
        in.fail(at + 1, "parameter '" + name + "' has " + std::to_string(dimension_count) +
                            " dimensions (at most 7)");
      }
      at += 2;
      for (int d = 0; d < dimension_count; ++d)
        parameter.dimensions.push_back(in.u8(at + d, "a parameter's dimensions"));
      at += static_cast<std::size_t>(dimension_count);
      read_values(in, at, parameter);
      pending.push_back({id, std::move(parameter)});
    } else {
      in.fail(position + 1, "record '" + name + "' has group id 0");
    }
    if (pointer == 0) break;
    // Some writers store the pointer signed; a pointer that does not move forward ends the loop.
    const std::size_t next = pointer_at + pointer;
    if (next <= pointer_at || next >= in.size()) {
      if (next == in.size()) break;
      in.fail(pointer_at, "parameter '" + name + "' points to offset " + std::to_string(next) +
                              ", past the end of the file");
    }
    position = next;
  }
  for (Pending& item : pending) {
    const auto group = std::find_if(group_ids.begin(), group_ids.end(),
                                    [&](const auto& entry) { return entry.first == item.group_id; });
    item.parameter.group = group == group_ids.end() ? "" : group->second;
    file.parameters.push_back(std::move(item.parameter));
  }
}

double first_number(const C3dFile& file, const char* group, const char* name, double fallback) {
  const C3dParameter* parameter = file.find(group, name);
  return parameter != nullptr && !parameter->numbers.empty() ? parameter->numbers.front() : fallback;
}

// POINT:LABELS, then LABELS2, LABELS3, ... for files with more than 255 points.
std::vector<std::string> point_labels(const C3dFile& file, std::size_t count) {
  std::vector<std::string> labels;
  for (int index = 1; labels.size() < count; ++index) {
    const C3dParameter* parameter =
        file.find("POINT", index == 1 ? "LABELS" : "LABELS" + std::to_string(index));
    if (parameter == nullptr) break;
    if (parameter->strings.empty()) break;
    for (const std::string& label : parameter->strings) labels.push_back(label);
  }
  labels.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (labels[i].empty()) labels[i] = "point_" + std::to_string(i + 1);
  }
  return labels;
}

// Frame count: TRIAL:ACTUAL_START_FIELD/END_FIELD (two 16-bit words each, for more than 65535
// frames) when present, else the header's first and last frame.
std::size_t frame_count(const C3dFile& file, int header_first, int header_last) {
  const C3dParameter* start = file.find("TRIAL", "ACTUAL_START_FIELD");
  const C3dParameter* end = file.find("TRIAL", "ACTUAL_END_FIELD");
  auto word_pair = [](const C3dParameter* p) {
    const auto low = static_cast<std::uint32_t>(static_cast<std::uint16_t>(p->numbers[0]));
    const auto high = static_cast<std::uint32_t>(static_cast<std::uint16_t>(p->numbers[1]));
    return static_cast<std::int64_t>(low | (high << 16));
  };
  if (start != nullptr && end != nullptr && start->type == 2 && end->type == 2 &&
      start->numbers.size() >= 2 && end->numbers.size() >= 2) {
    const std::int64_t first = word_pair(start);
    const std::int64_t last = word_pair(end);
    if (last >= first && first >= 1) return static_cast<std::size_t>(last - first + 1);
  }
  return header_last >= header_first ? static_cast<std::size_t>(header_last - header_first + 1) : 0;
}

void read_points(const ByteReader& in, std::size_t data_start, std::size_t frames, C3dFile& file) {
  MarkerTrajectories& points = file.points;
  const std::size_t markers = points.marker_count();
  const std::size_t word = file.float_storage ? 4 : 2;
  const std::size_t frame_bytes = (markers * 4 + static_cast<std::size_t>(file.analog_per_frame)) * word;
  const std::size_t needed = frames * frame_bytes;
  if (data_start > in.size() || needed > in.size() - data_start) {
    const std::size_t available = in.size() > data_start ? in.size() - data_start : 0;
    in.fail(data_start + available / frame_bytes * frame_bytes,
            "data section truncated: " + std::to_string(frames) + " frames of " +
                std::to_string(frame_bytes) + " bytes need " + std::to_string(needed) +
                " bytes from offset " + std::to_string(data_start) + ", the file has " +
                std::to_string(available));
  }
  const double to_metres = metres_per_unit(points.units);
  const double scale = std::abs(file.point_scale);
  points.positions.resize(frames * markers, Eigen::Vector3d::Zero());
  points.valid.assign(frames * markers, 0);
  points.residuals_m.assign(frames * markers, -1.0F);
  points.camera_masks.assign(frames * markers, 0);
  points.times_s.resize(frames);
  for (std::size_t f = 0; f < frames; ++f) {
    points.times_s[f] = static_cast<double>(file.first_frame - 1 + static_cast<int>(f)) / points.data_rate_hz;
    const std::size_t frame_at = data_start + f * frame_bytes;
    for (std::size_t m = 0; m < markers; ++m) {
      const std::size_t at = frame_at + m * 4 * word;
      Eigen::Vector3d p;
      std::int32_t fourth = 0;
      if (file.float_storage) {
        for (std::size_t axis = 0; axis < 3; ++axis)
          p[static_cast<Eigen::Index>(axis)] = in.f32(at + 4 * axis, "point data");
        const float stored = in.f32(at + 12, "point data");
        fourth = std::isfinite(stored) && std::abs(stored) < 2.1e9F ? static_cast<std::int32_t>(stored) : -1;
      } else {
        for (std::size_t axis = 0; axis < 3; ++axis) {
          p[static_cast<Eigen::Index>(axis)] = in.i16(at + 2 * axis, "point data") * scale;
        }
        fourth = in.i16(at + 6, "point data");
      }
      const std::size_t sample = f * markers + m;
      if (fourth < 0 || !p.allFinite()) continue;
      points.valid[sample] = 1;
      points.positions[sample] = p * to_metres;
      points.residuals_m[sample] = static_cast<float>((fourth & 0xff) * scale * to_metres);
      points.camera_masks[sample] = static_cast<std::uint8_t>((fourth >> 8) & 0x7f);
    }
  }
}

// The data section's first block. The header (word 9, offset 16) and POINT:DATA_START both hold
// it. Several vendors' files leave the parameter at 0 or 1 and the header right (issue 32), so a
// value that cannot be the data section (before the end of the parameters, or past the end of the
// file) yields to the other; the parameter wins when both are possible, as the C3D guide says.
std::size_t data_section_block(const ByteReader& in, const C3dFile& file, std::size_t parameter_block,
                               std::size_t header_block) {
  const std::size_t first_possible = parameter_block + 1;
  const auto possible = [&](std::size_t block) {
    return block >= first_possible && (block - 1) * kBlockBytes < in.size();
  };
  const C3dParameter* parameter = file.find("POINT", "DATA_START");
  if (parameter == nullptr || parameter->numbers.empty()) {
    if (!possible(header_block)) {
      in.fail(16, "the header puts the data section at block " + std::to_string(header_block) +
                      " and there is no POINT:DATA_START; it must be a block from " +
                      std::to_string(first_possible) + " to the end of the file");
    }
    return header_block;
  }
  // Stored as a signed 16-bit word; blocks above 32767 appear negative.
  const auto parameter_value =
      static_cast<std::size_t>(static_cast<std::uint16_t>(parameter->numbers.front()));
  if (possible(parameter_value)) return parameter_value;
  if (possible(header_block)) return header_block;
  in.fail(16, "the header puts the data section at block " + std::to_string(header_block) +
                  " and POINT:DATA_START at block " + std::to_string(parameter_value) +
                  "; neither can be: it must be a block from " + std::to_string(first_possible) +
                  " (after the parameters) to the end of the file");
}

}  // namespace

const C3dParameter* C3dFile::find(const std::string& group, const std::string& name) const {
  for (const C3dParameter& parameter : parameters) {
    if (parameter.group == group && parameter.name == name) return &parameter;
  }
  return nullptr;
}

C3dFile parse_c3d(std::span<const std::uint8_t> bytes, const std::string& name_for_errors) {
  ByteReader in(bytes, name_for_errors);
  in.need(0, kBlockBytes, "the header block (a C3D file starts with a 512-byte header)");
  const std::size_t parameter_block = in.u8(0, "the header");
  if (in.u8(1, "the header") != c3d::kParameterKey) {
    in.fail(1,
            "not a C3D file: byte 2 is " + std::to_string(in.u8(1, "the header")) + ", expected 80 (0x50)");
  }
  if (parameter_block < 2)
    in.fail(0, "parameter section at block " + std::to_string(parameter_block) + " (must be 2 or later)");
  const std::size_t section = (parameter_block - 1) * kBlockBytes;
  const int processor = in.u8(section + 3, "the parameter section's header");
  if (processor < c3d::kProcessorBase + 1 || processor > c3d::kProcessorBase + 3) {
    in.fail(section + 3, "unknown processor type " + std::to_string(processor) +
                             " (84 Intel, 85 DEC, 86 MIPS): cannot tell the byte order");
  }
  in.processor = static_cast<C3dProcessor>(processor);
  C3dFile file;
  file.processor = in.processor;
  file.analog_per_frame = in.u16(4, "the header");
  const int header_first = in.u16(6, "the header");
  const int header_last = in.u16(8, "the header");
  const double header_scale = in.f32(12, "the header");
  const std::size_t header_data_block = in.u16(16, "the header");
  const double header_rate = in.f32(20, "the header");

  read_parameters(in, section, file);
  const bool has_point_group =
      std::find(file.groups.begin(), file.groups.end(), "POINT") != file.groups.end();
  if (!has_point_group) in.fail(section, "no POINT group in the parameter section");
  const C3dParameter* used = file.find("POINT", "USED");
  if (used == nullptr || used->numbers.empty()) in.fail(section, "POINT group has no USED parameter");
  // Stored as a signed 16-bit word; counts above 32767 appear negative.
  const auto marker_count = static_cast<std::size_t>(static_cast<std::uint16_t>(used->numbers.front()));
  if (marker_count == 0) in.fail(section, "POINT:USED is 0: the file has no markers");
  file.point_scale = first_number(file, "POINT", "SCALE", header_scale);
  if (!std::isfinite(file.point_scale) || file.point_scale == 0.0) {
    in.fail(12, "POINT:SCALE is " + std::to_string(file.point_scale) + " (must be non-zero)");
  }
  file.float_storage = file.point_scale < 0.0;
  MarkerTrajectories& points = file.points;
  points.data_rate_hz = first_number(file, "POINT", "RATE", header_rate);
  if (!std::isfinite(points.data_rate_hz) || points.data_rate_hz <= 0.0) {
    in.fail(20, "POINT:RATE is " + std::to_string(points.data_rate_hz) + " (must be positive)");
  }
  const C3dParameter* units = file.find("POINT", "UNITS");
  points.units = units != nullptr && !units->strings.empty() ? units->strings.front() : "mm";
  if (metres_per_unit(points.units) == 0.0)
    in.fail(section, "POINT:UNITS '" + points.units + "' (expected mm, cm or m)");
  points.marker_names = point_labels(file, marker_count);
  file.first_frame = std::max(1, header_first);
  const std::size_t data_start_block = data_section_block(in, file, parameter_block, header_data_block);
  const std::size_t frames = frame_count(file, header_first, header_last);
  if (frames == 0)
    in.fail(8, "no frames (last frame " + std::to_string(header_last) + " < first " +
                   std::to_string(header_first) + ")");
  read_points(in, (data_start_block - 1) * kBlockBytes, frames, file);
  return file;
}

C3dFile read_c3d(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string(), "", "cannot open C3D file");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  return parse_c3d(bytes, path.string());
}

MarkerTrajectories load_c3d(const std::filesystem::path& path) {
  return read_c3d(path).points;
}

}  // namespace panoptes
