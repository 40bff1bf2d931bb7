// SPDX-License-Identifier: Apache-2.0
// TRC reader and writer. Layout (OpenSim's and Motion Analysis' writers agree on it):
//   1  PathFileType  4  (X/Y/Z)  <path>
//   2  DataRate CameraRate NumFrames NumMarkers Units OrigDataRate ...   (keys)
//   3  values for line 2
//   4  Frame#  Time  name1 <tab><tab> name2 ...
//   5  <tab><tab> X1 Y1 Z1 X2 ...
//   then optional blank lines and one row per frame: frame, time, x y z per marker, tab separated,
//   an empty field where the marker was not seen.
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "number_format.h"
#include "panoptes/errors.h"
#include "panoptes/formats/trc.h"

namespace panoptes {

namespace {

std::string_view trim(std::string_view text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

std::vector<std::string_view> split_tabs(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const auto tab = line.find('\t', start);
    fields.push_back(
        trim(line.substr(start, tab == std::string_view::npos ? std::string_view::npos : tab - start)));
    if (tab == std::string_view::npos) break;
    start = tab + 1;
  }
  return fields;
}

// The header's value line pads with runs of tabs, so it is split on whitespace instead.
std::vector<std::string> split_whitespace(std::string_view line) {
  std::vector<std::string> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) tokens.emplace_back(line.substr(start, i - start));
  }
  return tokens;
}

bool parse_number(std::string_view text, double& value) {
  if (text.empty()) return false;
  if (text.front() == '+') text.remove_prefix(1);
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  return result.ec == std::errc() && result.ptr == text.data() + text.size() && std::isfinite(value);
}

}  // namespace

MarkerTrajectories load_trc(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw ConfigError(file, "", "cannot open TRC file");
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  auto line_key = [](std::size_t index) { return "line " + std::to_string(index + 1); };
  if (lines.size() < 5) throw ConfigError(file, "", "not a TRC file: fewer than 5 header lines");
  if (lines[0].rfind("PathFileType", 0) != 0) {
    throw ConfigError(file, line_key(0), "not a TRC file: expected 'PathFileType'");
  }

  const std::vector<std::string> keys = split_whitespace(lines[1]);
  const std::vector<std::string> values = split_whitespace(lines[2]);
  if (keys.size() != values.size()) {
    throw ConfigError(
        file, line_key(2),
        "expected " + std::to_string(keys.size()) + " header values, got " + std::to_string(values.size()));
  }
  std::map<std::string, std::string> header;
  for (std::size_t i = 0; i < keys.size(); ++i) header[keys[i]] = values[i];
  auto header_value = [&](const std::string& key) -> const std::string& {
    const auto it = header.find(key);
    if (it == header.end()) throw ConfigError(file, line_key(1), "missing header field '" + key + "'");
    return it->second;
  };

  MarkerTrajectories data;
  if (!parse_number(header_value("DataRate"), data.data_rate_hz) || data.data_rate_hz <= 0.0) {
    throw ConfigError(file, line_key(2), "DataRate must be a positive number");
  }
  data.units = header_value("Units");
  const double scale = metres_per_unit(data.units);
  if (scale == 0.0)
    throw ConfigError(file, line_key(2), "unsupported Units '" + data.units + "' (mm, cm or m)");
  double declared_markers = 0.0;
  if (!parse_number(header_value("NumMarkers"), declared_markers) || declared_markers < 1.0) {
    throw ConfigError(file, line_key(2), "NumMarkers must be a positive integer");
  }

  const std::vector<std::string_view> name_fields = split_tabs(lines[3]);
  if (name_fields.size() < 2 || name_fields[0] != "Frame#") {
    throw ConfigError(file, line_key(3), "expected 'Frame#<tab>Time<tab>names...'");
  }
  for (std::size_t i = 2; i < name_fields.size(); ++i) {
    if (!name_fields[i].empty()) data.marker_names.emplace_back(name_fields[i]);
  }
  if (data.marker_names.size() != static_cast<std::size_t>(declared_markers)) {
    throw ConfigError(file, line_key(3),
                      "NumMarkers says " + header_value("NumMarkers") + " but " +
                          std::to_string(data.marker_names.size()) + " marker names are listed");
  }

  const std::size_t marker_count = data.marker_names.size();
  for (std::size_t index = 5; index < lines.size(); ++index) {
    if (trim(lines[index]).empty()) continue;
    const std::vector<std::string_view> fields = split_tabs(lines[index]);
    double frame_number = 0.0;
    double time = 0.0;
    if (fields.size() < 2 || !parse_number(fields[0], frame_number) || !parse_number(fields[1], time)) {
      throw ConfigError(file, line_key(index), "expected a frame number and a time");
    }
    if (!data.times_s.empty() && !(time > data.times_s.back())) {
      throw ConfigError(file, line_key(index), "Time must increase from row to row");
    }
    if (fields.size() > 2 + 3 * marker_count && !fields.back().empty()) {
      throw ConfigError(file, line_key(index),
                        "more values than the " + std::to_string(marker_count) + " markers of the header");
    }
    data.times_s.push_back(time);
    for (std::size_t marker = 0; marker < marker_count; ++marker) {
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      int present = 0;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const std::size_t column = 2 + 3 * marker + axis;
        if (column >= fields.size() || fields[column].empty()) continue;
        if (!parse_number(fields[column], p[axis])) {
          throw ConfigError(file, line_key(index),
                            "column " + std::to_string(column + 1) + ": expected a number, got '" +
                                std::string(fields[column]) + "'");
        }
        ++present;
      }
      // A partly written marker is as unusable as a missing one.
      data.positions.push_back(present == 3 ? Eigen::Vector3d(p * scale) : Eigen::Vector3d::Zero());
      data.valid.push_back(present == 3 ? 1 : 0);
    }
  }
  if (data.times_s.empty()) throw ConfigError(file, "", "no data rows");
  return data;
}

namespace {

constexpr int kTrcDecimals = 6;

}  // namespace

void write_trc(const std::filesystem::path& path, const MarkerTrajectories& data) {
  const std::string file = path.string();
  const std::string units = data.units.empty() ? "mm" : data.units;
  const double per_metre = metres_per_unit(units);
  if (per_metre == 0.0) throw ConfigError(file, "", "unsupported units '" + units + "' (mm, cm or m)");
  if (data.marker_count() == 0) throw ConfigError(file, "", "no markers to write");
  if (!(data.data_rate_hz > 0.0)) throw ConfigError(file, "", "the rate must be positive");
  const double units_per_metre = 1.0 / per_metre;
  const std::size_t markers = data.marker_count();
  const std::size_t frames = data.frame_count();
  std::string out;
  out.reserve(64 + frames * (16 + markers * 3 * 14));
  out += "PathFileType\t4\t(X/Y/Z)\t";
  out += path.filename().string();
  out +=
      "\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
      "\n";
  std::string rate;
  formats::append_fixed(rate, data.data_rate_hz, kTrcDecimals);
  out += rate + "\t" + rate + "\t" + std::to_string(frames) + "\t" + std::to_string(markers) + "\t" + units +
         "\t" + rate + "\t1\t" + std::to_string(frames) + "\nFrame#\tTime";
  for (const std::string& name : data.marker_names) {
    out += '\t';
    out += name;
    out += "\t\t";
  }
  out += "\n\t";
  for (std::size_t m = 1; m <= markers; ++m) {
    const std::string index = std::to_string(m);
    for (const char* axis : {"\tX", "\tY", "\tZ"}) {
      out += axis;
      out += index;
    }
  }
  out += "\n\n";
  for (std::size_t f = 0; f < frames; ++f) {
    out += std::to_string(f + 1);
    out += '\t';
    formats::append_fixed(out, data.times_s[f], kTrcDecimals);
    for (std::size_t m = 0; m < markers; ++m) {
      const bool valid = data.is_valid(f, m);
      for (int axis = 0; axis < 3; ++axis) {
        out += '\t';
        if (valid) formats::append_fixed(out, data.position(f, m)[axis] * units_per_metre, kTrcDecimals);
      }
    }
    out += '\n';
  }
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  if (!stream) throw ConfigError(file, "", "cannot open for writing");
  stream.write(out.data(), static_cast<std::streamsize>(out.size()));
  stream.close();
  if (!stream) throw ConfigError(file, "", "write failed (disk full?)");
}

}  // namespace panoptes
