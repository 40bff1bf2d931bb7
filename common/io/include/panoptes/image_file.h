// SPDX-License-Identifier: Apache-2.0
// Picture files: PGM/PNM (our parser), PNG (libpng) and JPEG (libjpeg-turbo), read and written
// without OpenCV's imgcodecs. Debian's imgcodecs links GDAL and GDCM: about 140 shared libraries that
// every program linking it loaded at start (0.15-0.2 s of CPU per process, docs/testing.md "Process
// start"). Sample values are kept exactly as stored (no gamma or colour-space conversion).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "panoptes/image.h"

namespace panoptes {

// Decoded pixels as stored: 1 (grey) or 3 (B, G, R: OpenCV's order) channels of 8- or 16-bit samples
// (16-bit in native byte order), rows tightly packed; an alpha channel is dropped when reading.
struct Picture {
  int width = 0;
  int height = 0;
  int channels = 1;
  int bits = 8;              // bits per stored sample: 8 or 16
  int significant_bits = 8;  // fewer than `bits` for a PNM whose maxval says so (12-bit: 4095)
  std::vector<std::uint8_t> data;

  std::size_t stride() const { return static_cast<std::size_t>(width) * channels * (bits / 8); }
};

// A view of pixels owned elsewhere (an Image, a cv::Mat), for writing.
struct PixelsView {
  int width = 0;
  int height = 0;
  int channels = 1;  // 1 grey, 3 B G R, 4 B G R A
  int bits = 8;      // 8, or 16 for grey only
  const std::uint8_t* data = nullptr;
  std::size_t stride = 0;  // bytes from one row to the next
};

// Reads a PGM/PPM (P2, P3, P5, P6; maxval up to 65535), PNG (any colour type, 1-16 bits) or JPEG
// (baseline or progressive, grey or colour), recognised by content, not by name. Palette and
// low-bit-depth PNGs are expanded to 8 bits. Throws std::runtime_error "<path>: <reason>".
Picture read_picture(const std::filesystem::path& path);
// The same from bytes in memory; `name` is what errors are prefixed with.
Picture decode_picture(const std::uint8_t* bytes, std::size_t size, const std::string& name);

// Grey from colour with ITU-R BT.601 weights (0.299 R + 0.587 G + 0.114 B, rounded, as OpenCV's
// conversion), alpha ignored; 16-bit samples stay 16-bit with the picture's significant bits.
Image to_grey(const Picture& picture);
// read_picture + to_grey, except that a colour JPEG is decoded to its stored luma (as OpenCV's
// IMREAD_GRAYSCALE does).
Image read_grey_image(const std::filesystem::path& path);

// JPEG bytes (a camera's MJPG frame) to 8-bit grey, decoded as grey by libjpeg (luma only).
// Returns false and names the problem in *error for bytes that are not a whole JPEG image.
bool decode_jpeg_grey(const std::uint8_t* bytes, std::size_t size, Image& out, std::string* error = nullptr);
// An 8-bit grey image as a baseline JPEG of the given quality (1-100).
std::vector<std::uint8_t> encode_jpeg_grey(const Image& image, int quality);

// PNG bytes of 8-bit grey, BGR or BGRA pixels, or of 16-bit grey (stored big-endian as PNG requires).
// Throws std::invalid_argument for another layout.
std::vector<std::uint8_t> encode_png(const PixelsView& pixels);
// encode_png written to a file; throws std::runtime_error naming the file if it cannot be written.
void write_png(const std::filesystem::path& path, const PixelsView& pixels);
// A view of an Image (grey, 8 or 16 bits).
PixelsView view_of(const Image& image);

}  // namespace panoptes
