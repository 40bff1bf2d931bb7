// SPDX-License-Identifier: Apache-2.0
// C3D files (c3d.org's "The C3D File Format User Guide"): a reader for the point data of Intel,
// DEC and MIPS files in integer or floating-point storage, and a writer of Intel floating-point
// files with an empty analog section. docs/recording.md, "Export".
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "panoptes/formats/marker_trajectories.h"

namespace panoptes {

enum class C3dProcessor { kIntel = 84, kDec = 85, kMips = 86 };

// One parameter as stored: its group and name, type (-1 char, 1 byte, 2 int16, 4 float),
// dimensions, and the values decoded to the host (numbers) or as text (char arrays: one string per
// column of the first dimension, trailing blanks removed).
struct C3dParameter {
  std::string group;
  std::string name;
  int type = 0;
  std::vector<int> dimensions;
  std::vector<double> numbers;
  std::vector<std::string> strings;
};

struct C3dFile {
  C3dProcessor processor = C3dProcessor::kIntel;
  bool float_storage = false;  // POINT:SCALE < 0
  double point_scale = 0.0;    // POINT:SCALE as stored
  int first_frame = 1;
  int analog_per_frame = 0;  // analog samples stored after the points of each frame
  std::vector<std::string> groups;
  std::vector<C3dParameter> parameters;
  MarkerTrajectories points;  // metres; times_s start at (first_frame - 1) / rate

  const C3dParameter* find(const std::string& group, const std::string& name) const;
};

// Throws ConfigError "<file>: offset <n>: <reason>" on anything it cannot read: not a C3D file, an
// unknown processor byte, a parameter section that runs past its end, no POINT group, no markers
// (POINT:USED 0), a data section shorter than the frames it declares. Groups other than POINT are
// optional (ANALOG is absent from some files).
C3dFile read_c3d(const std::filesystem::path& path);
C3dFile parse_c3d(std::span<const std::uint8_t> bytes, const std::string& name_for_errors);
// The point data of read_c3d.
MarkerTrajectories load_c3d(const std::filesystem::path& path);

struct C3dWriteOptions {
  std::string units = "mm";  // POINT:UNITS: mm, cm or m
  std::string software = "panoptes_export";
};

// Intel, floating-point storage, first frame 1, no analog channels (ANALOG:USED 0). Labels are
// cut to 255 characters; more than 255 points continue in POINT:LABELS2, LABELS3, ... More than
// 65535 frames: the header and POINT:FRAMES hold 65535 and TRIAL:ACTUAL_START_FIELD/END_FIELD the
// true range. Frames are taken as uniformly spaced at data_rate_hz (times_s is not written).
// Throws ConfigError naming the file on a bad input (no markers, more than 32767, rate not
// positive) or when the file cannot be written.
std::vector<std::uint8_t> encode_c3d(const MarkerTrajectories& data, const C3dWriteOptions& options,
                                     const std::string& name_for_errors = "<c3d>");
void write_c3d(const std::filesystem::path& path, const MarkerTrajectories& data,
               const C3dWriteOptions& options = {});

}  // namespace panoptes
