// SPDX-License-Identifier: Apache-2.0
// CSV writers (formats in csv.h).
#include <fstream>
#include <string>

#include "number_format.h"
#include "panoptes/errors.h"
#include "panoptes/formats/csv.h"

namespace panoptes {

namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  if (!stream) throw ConfigError(path.string(), "", "cannot open for writing");
  stream.write(text.data(), static_cast<std::streamsize>(text.size()));
  stream.close();
  if (!stream) throw ConfigError(path.string(), "", "write failed (disk full?)");
}

// A name as one CSV field: quoted when it holds a comma, quote or line break.
std::string csv_field(const std::string& name) {
  if (name.find_first_of(",\"\n\r") == std::string::npos) return name;
  std::string quoted = "\"";
  for (char c : name) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

// Metres with 7 decimals (0.1 µm); quaternion components with 9.
constexpr int kMetreDecimals = 7;
constexpr int kQuaternionDecimals = 9;

}  // namespace

void write_markers_csv(const std::filesystem::path& path, const MarkerTrajectories& data) {
  const std::size_t markers = data.marker_count();
  const std::size_t frames = data.frame_count();
  std::string out;
  out.reserve(64 + frames * (16 + markers * 3 * 12));
  out += "frame,time_s";
  for (const std::string& name : data.marker_names) {
    for (const char* axis : {"_x", "_y", "_z"}) {
      out += ',';
      out += csv_field(name + axis);
    }
  }
  out += '\n';
  for (std::size_t f = 0; f < frames; ++f) {
    out += std::to_string(f + 1);
    out += ',';
    formats::append_fixed(out, data.times_s[f], 6);
    for (std::size_t m = 0; m < markers; ++m) {
      const bool valid = data.is_valid(f, m);
      for (int axis = 0; axis < 3; ++axis) {
        out += ',';
        if (valid) formats::append_fixed(out, data.position(f, m)[axis], kMetreDecimals);
      }
    }
    out += '\n';
  }
  write_text(path, out);
}

void write_bodies_csv(const std::filesystem::path& path, const BodyTrajectories& data) {
  std::string out = "frame,time_s,body,x,y,z,qx,qy,qz,qw\n";
  const std::size_t bodies = data.body_count();
  for (std::size_t f = 0; f < data.frame_count(); ++f) {
    for (std::size_t b = 0; b < bodies; ++b) {
      const std::size_t sample = f * bodies + b;
      if (data.valid[sample] == 0) continue;
      out += std::to_string(f + 1);
      out += ',';
      formats::append_fixed(out, data.times_s[f], 6);
      out += ',';
      out += csv_field(data.body_names[b]);
      for (int axis = 0; axis < 3; ++axis) {
        out += ',';
        formats::append_fixed(out, data.positions[sample][axis], kMetreDecimals);
      }
      for (int i = 0; i < 4; ++i) {
        out += ',';
        formats::append_fixed(out, data.quaternions[sample][i], kQuaternionDecimals);
      }
      out += '\n';
    }
  }
  write_text(path, out);
}

}  // namespace panoptes
