// SPDX-License-Identifier: Apache-2.0
// Hand-built C3D files for the reader tests: any processor, integer or float storage, and the
// defects the bad-input tests need. Written apart from the library's writer on purpose.
#pragma once

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../shared_data.h"

namespace panoptes::test {

namespace fs = std::filesystem;

// ../shared/data/c3d beside the checkout (tests/data/README.md: fail under CI, skip elsewhere).
inline fs::path shared_c3d(const std::string& name) {
  return shared_data("c3d/" + name);
}

struct HandBuiltC3d {
  int processor = 84;  // 84 Intel, 85 DEC, 86 MIPS
  bool float_storage = true;
  float scale = 0.1F;  // |POINT:SCALE|
  float rate = 50.0F;
  int points = 2;
  int frames = 3;
  bool point_group = true;
  bool used_parameter = true;
  int analog_per_frame = 0;
  // Where the header (offset 16) and POINT:DATA_START put the data section: block 3 is right.
  int header_data_start = 3;
  int parameter_data_start = 3;
  // Point m of frame f: (100 f + m, -10 m, 0.5 f) mm; invalid where (f + m) % 3 == 2.
  static bool valid(int f, int m) { return (f + m) % 3 != 2; }
  static double coordinate(int f, int m, int axis) {
    return axis == 0 ? 100.0 * f + m : axis == 1 ? -10.0 * m : 0.5 * f;
  }

  void put16(std::vector<std::uint8_t>& out, std::size_t at, std::int16_t value) const {
    const auto u = static_cast<std::uint16_t>(value);
    const bool big = processor == 86;
    out[at] = static_cast<std::uint8_t>(big ? u >> 8 : u & 0xff);
    out[at + 1] = static_cast<std::uint8_t>(big ? u & 0xff : u >> 8);
  }
  void putf(std::vector<std::uint8_t>& out, std::size_t at, float value) const {
    if (processor == 85) {
      // VAX F_floating: the IEEE bits of 4x the value with the 16-bit halves swapped.
      const auto bits = std::bit_cast<std::uint32_t>(value * 4.0F);
      const std::uint8_t ieee[4] = {static_cast<std::uint8_t>(bits), static_cast<std::uint8_t>(bits >> 8),
                                    static_cast<std::uint8_t>(bits >> 16),
                                    static_cast<std::uint8_t>(bits >> 24)};
      out[at] = ieee[2];
      out[at + 1] = ieee[3];
      out[at + 2] = ieee[0];
      out[at + 3] = ieee[1];
      return;
    }
    const auto bits = std::bit_cast<std::uint32_t>(value);
    for (int i = 0; i < 4; ++i) {
      const int shift = processor == 86 ? 24 - 8 * i : 8 * i;
      out[at + i] = static_cast<std::uint8_t>(bits >> shift);
    }
  }

  std::vector<std::uint8_t> build() const {
    std::vector<std::uint8_t> out(std::size_t{2} * 512, 0);  // header, one parameter block; data from block 3
    out[0] = 2;
    out[1] = 0x50;
    put16(out, 2, static_cast<std::int16_t>(points));
    put16(out, 4, static_cast<std::int16_t>(analog_per_frame));
    put16(out, 6, 1);
    put16(out, 8, static_cast<std::int16_t>(frames));
    putf(out, 12, float_storage ? -scale : scale);
    put16(out, 16, static_cast<std::int16_t>(header_data_start));
    putf(out, 20, rate);
    out[512 + 2] = 1;
    out[512 + 3] = static_cast<std::uint8_t>(processor);
    std::size_t at = 512 + 4;
    auto record = [&](int id, const std::string& name, const std::vector<std::uint8_t>& body) {
      out[at] = static_cast<std::uint8_t>(name.size());
      out[at + 1] = static_cast<std::uint8_t>(static_cast<std::int8_t>(id));
      for (std::size_t i = 0; i < name.size(); ++i) out[at + 2 + i] = static_cast<std::uint8_t>(name[i]);
      const std::size_t pointer = at + 2 + name.size();
      put16(out, pointer, static_cast<std::int16_t>(2 + body.size() + 1));
      for (std::size_t i = 0; i < body.size(); ++i) out[pointer + 2 + i] = body[i];
      out[pointer + 2 + body.size()] = 0;  // empty description
      at = pointer + 2 + body.size() + 1;
    };
    auto int_body = [&](int value) {
      std::vector<std::uint8_t> body = {2, 0, 0, 0};
      put16(body, 2, static_cast<std::int16_t>(value));
      return body;
    };
    auto float_body = [&](float value) {
      std::vector<std::uint8_t> body = {4, 0, 0, 0, 0, 0};
      putf(body, 2, value);
      return body;
    };
    const int group = point_group ? 1 : 5;
    record(-group, point_group ? "POINT" : "OTHER", {});
    if (used_parameter) record(group, "USED", int_body(points));
    record(group, "SCALE", float_body(float_storage ? -scale : scale));
    record(group, "RATE", float_body(rate));
    record(group, "DATA_START", int_body(parameter_data_start));
    std::vector<std::uint8_t> labels = {0xff, 2, 4, static_cast<std::uint8_t>(points)};
    for (int m = 0; m < points; ++m) {
      const std::string label = "M" + std::to_string(m) + "  ";
      labels.insert(labels.end(), label.begin(), label.begin() + 4);
    }
    record(group, "LABELS", labels);
    record(group, "UNITS", {0xff, 1, 2, 'm', 'm'});
    out[at] = 0;  // end of the parameters
    const std::size_t word = float_storage ? 4 : 2;
    for (int f = 0; f < frames; ++f) {
      for (int m = 0; m < points; ++m) {
        std::vector<std::uint8_t> point(4 * word, 0);
        for (int axis = 0; axis < 3; ++axis) {
          const double v = coordinate(f, m, axis);
          if (float_storage) {
            putf(point, std::size_t{4} * static_cast<std::size_t>(axis), static_cast<float>(v));
          } else {
            put16(point, std::size_t{2} * static_cast<std::size_t>(axis),
                  static_cast<std::int16_t>(std::lround(v / scale)));
          }
        }
        // Camera mask 0b101, residual 3 steps.
        const int fourth = valid(f, m) ? (0x05 << 8) | 3 : -1;
        if (float_storage) {
          putf(point, 12, static_cast<float>(fourth));
        } else {
          put16(point, 6, static_cast<std::int16_t>(fourth));
        }
        out.insert(out.end(), point.begin(), point.end());
      }
      out.insert(out.end(), static_cast<std::size_t>(analog_per_frame) * word, 0);
    }
    return out;
  }
};

}  // namespace panoptes::test
