// SPDX-License-Identifier: Apache-2.0
#include "panoptes/pgm.h"

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace panoptes {

void write_pgm(const Image& image, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
  out << "P5\n" << image.width << ' ' << image.height << '\n' << image.max_value() << '\n';
  if (image.bytes_per_pixel() == 1) {
    out.write(reinterpret_cast<const char*>(image.data.data()),
              static_cast<std::streamsize>(image.data.size()));
  } else {
    std::vector<char> row(image.stride());
    for (int y = 0; y < image.height; ++y) {
      const std::uint16_t* pixels = image.row16(y);
      for (std::size_t x = 0; x < static_cast<std::size_t>(image.width); ++x) {
        row[2 * x] = static_cast<char>(pixels[x] >> 8);
        row[2 * x + 1] = static_cast<char>(pixels[x] & 0xFF);
      }
      out.write(row.data(), static_cast<std::streamsize>(row.size()));
    }
  }
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace panoptes
