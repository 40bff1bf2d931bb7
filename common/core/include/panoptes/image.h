// SPDX-License-Identifier: Apache-2.0
// A plain grey image, 8 or 16 bits per pixel, row-major, tightly packed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace panoptes {

struct Image {
  int width = 0;
  int height = 0;
  int bits = 8;                    // significant bits per pixel: 8 for Mono8; 10/12/16 stored in 16-bit words
  std::vector<std::uint8_t> data;  // width*height*bytes_per_pixel()

  Image() = default;
  Image(int w, int h, int bits_per_pixel) : width(w), height(h), bits(bits_per_pixel) {
    data.assign(static_cast<std::size_t>(w) * h * bytes_per_pixel(), 0);
  }
  int bytes_per_pixel() const { return bits > 8 ? 2 : 1; }
  std::size_t stride() const { return static_cast<std::size_t>(width) * bytes_per_pixel(); }
  std::uint8_t* row8(int y) { return data.data() + y * stride(); }
  const std::uint8_t* row8(int y) const { return data.data() + y * stride(); }
  std::uint16_t* row16(int y) { return reinterpret_cast<std::uint16_t*>(data.data() + y * stride()); }
  const std::uint16_t* row16(int y) const {
    return reinterpret_cast<const std::uint16_t*>(data.data() + y * stride());
  }
  int max_value() const { return (1 << bits) - 1; }
};

}  // namespace panoptes
