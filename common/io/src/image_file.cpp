// SPDX-License-Identifier: Apache-2.0
#include "panoptes/image_file.h"

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>
#include <png.h>

namespace panoptes {
namespace {

// libpng and libjpeg report errors through a callback that must not return: it longjmps back to
// the setjmp of the function that called the library. That function keeps every C++ object it
// changes after setjmp in its caller's frame (the *State structs), so nothing it needs after the
// jump lives in a register the jump restored, and no destructor is skipped.

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// ---- PNM (P2, P3, P5, P6) ----

struct PnmReader {
  const std::uint8_t* bytes = nullptr;
  std::size_t size = 0;
  std::size_t at = 2;

  // The next header number, after whitespace and # comments; -1 if there is none.
  long long number() {
    while (at < size && (std::isspace(bytes[at]) || bytes[at] == '#')) {
      if (bytes[at] == '#') {
        while (at < size && bytes[at] != '\n') ++at;
      } else {
        ++at;
      }
    }
    if (at >= size || !std::isdigit(bytes[at])) return -1;
    long long value = 0;
    while (at < size && std::isdigit(bytes[at])) {
      value = value * 10 + (bytes[at++] - '0');
      if (value > 1'000'000'000) return -1;
    }
    return value;
  }
};

int bits_for_maxval(long long maxval) {
  int bits = 1;
  while (bits < 16 && (1LL << bits) - 1 < maxval) ++bits;
  return bits;
}

Picture decode_pnm(const std::uint8_t* bytes, std::size_t size, const std::string& name) {
  const char kind = static_cast<char>(bytes[1]);
  PnmReader reader{bytes, size};
  const long long width = reader.number();
  const long long height = reader.number();
  const long long maxval = reader.number();
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535)
    throw std::runtime_error(name + ": PNM header: bad width or height");
  if (maxval <= 0 || maxval > 65535)
    throw std::runtime_error(name + ": PNM header: maxval must be 1-65535, got " + std::to_string(maxval));
  Picture picture;
  picture.width = static_cast<int>(width);
  picture.height = static_cast<int>(height);
  picture.channels = kind == '3' || kind == '6' ? 3 : 1;
  picture.bits = maxval > 255 ? 16 : 8;
  picture.significant_bits = maxval > 255 ? bits_for_maxval(maxval) : 8;
  const std::size_t samples = static_cast<std::size_t>(width) * height * picture.channels;
  picture.data.resize(samples * (picture.bits / 8));
  std::vector<std::uint16_t> values(samples);
  if (kind == '5' || kind == '6') {
    ++reader.at;  // the single whitespace character after maxval
    const std::size_t bytes_per_sample = picture.bits / 8;
    if (reader.at > size || size - reader.at < samples * bytes_per_sample)
      throw std::runtime_error(name + ": PNM pixel data truncated");
    const std::uint8_t* data = bytes + reader.at;
    for (std::size_t i = 0; i < samples; ++i) {
      values[i] =
          bytes_per_sample == 1 ? data[i] : static_cast<std::uint16_t>(data[2 * i] << 8 | data[2 * i + 1]);
    }
  } else {
    for (std::size_t i = 0; i < samples; ++i) {
      const long long value = reader.number();
      if (value < 0 || value > 65535)
        throw std::runtime_error(name + ": PNM pixel data truncated or malformed");
      values[i] = static_cast<std::uint16_t>(value);
    }
  }
  // P3/P6 are R G B; Picture keeps OpenCV's B G R.
  if (picture.channels == 3) {
    for (std::size_t i = 0; i < samples; i += 3) std::swap(values[i], values[i + 2]);
  }
  if (picture.bits == 8) {
    std::transform(values.begin(), values.end(), picture.data.begin(),
                   [](std::uint16_t v) { return static_cast<std::uint8_t>(v); });
  } else {
    std::memcpy(picture.data.data(), values.data(), picture.data.size());
  }
  return picture;
}

// ---- PNG ----

struct PngState {
  const std::uint8_t* bytes = nullptr;  // reading
  std::size_t size = 0;
  std::size_t at = 0;
  std::vector<std::uint8_t>* out = nullptr;  // writing
  std::vector<png_bytep> rows;
  char error[256] = "";
};

void png_fail(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngState*>(png_get_error_ptr(png));
  std::snprintf(state->error, sizeof(state->error), "%s", message);
  std::longjmp(png_jmpbuf(png), 1);
}

void png_quiet(png_structp /*png*/, png_const_charp /*message*/) {}

void png_read_bytes(png_structp png, png_bytep out, png_size_t count) {
  auto* state = static_cast<PngState*>(png_get_io_ptr(png));
  if (count > state->size - state->at) png_error(png, "file truncated");
  std::memcpy(out, state->bytes + state->at, count);
  state->at += count;
}

void png_write_bytes(png_structp png, png_bytep data, png_size_t count) {
  auto* state = static_cast<PngState*>(png_get_io_ptr(png));
  state->out->insert(state->out->end(), data, data + count);
}

void png_flush_nothing(png_structp /*png*/) {}

// Decodes into `picture`, which lives in the caller's frame; false with state.error on failure.
bool decode_png_into(PngState& state, Picture& picture) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, png_fail, png_quiet);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, &state, png_read_bytes);
  png_read_info(png, info);
  const int colour_type = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (colour_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour_type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  png_set_strip_alpha(png);  // a transparency chunk is not expanded into an alpha channel either
  if (colour_type & PNG_COLOR_MASK_COLOR) png_set_bgr(png);
  if (depth == 16 && host_is_little_endian()) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  picture.width = static_cast<int>(png_get_image_width(png, info));
  picture.height = static_cast<int>(png_get_image_height(png, info));
  picture.channels = png_get_channels(png, info);
  picture.bits = png_get_bit_depth(png, info);
  picture.significant_bits = picture.bits;
  picture.data.resize(picture.stride() * picture.height);
  state.rows.resize(picture.height);
  for (int y = 0; y < picture.height; ++y) state.rows[y] = picture.data.data() + y * picture.stride();
  png_read_image(png, state.rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

bool encode_png_into(PngState& state, const PixelsView& pixels) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, png_fail, png_quiet);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &state, png_write_bytes, png_flush_nothing);
  const int colour_type = pixels.channels == 1   ? PNG_COLOR_TYPE_GRAY
                          : pixels.channels == 3 ? PNG_COLOR_TYPE_RGB
                                                 : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(png, info, static_cast<png_uint_32>(pixels.width), static_cast<png_uint_32>(pixels.height),
               pixels.bits, colour_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  // Plots and test pictures: a fast level rather than the last few percent of size.
  png_set_compression_level(png, 3);
  png_write_info(png, info);
  if (pixels.channels > 1) png_set_bgr(png);
  if (pixels.bits == 16 && host_is_little_endian()) png_set_swap(png);
  state.rows.resize(pixels.height);
  for (int y = 0; y < pixels.height; ++y)
    state.rows[y] = const_cast<png_bytep>(pixels.data + static_cast<std::size_t>(y) * pixels.stride);
  png_write_image(png, state.rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

// ---- JPEG ----

struct JpegState {
  jpeg_error_mgr manager{};
  std::jmp_buf jump{};
  char error[JMSG_LENGTH_MAX] = "";
  unsigned char* encoded = nullptr;  // jpeg_mem_dest's buffer (malloc'ed by libjpeg)
  unsigned long encoded_size = 0;
};

void jpeg_fail(j_common_ptr info) {
  auto* state = reinterpret_cast<JpegState*>(info->err);
  (*info->err->format_message)(info, state->error);
  std::longjmp(state->jump, 1);
}

// Warnings (a few bytes of garbage before a marker, data ending early) do not stop decoding; a
// camera's MJPG frame with one is kept, as OpenCV kept it.
void jpeg_quiet(j_common_ptr /*info*/, int /*level*/) {}

jpeg_error_mgr* error_manager(JpegState& state) {
  jpeg_error_mgr* manager = jpeg_std_error(&state.manager);
  manager->error_exit = jpeg_fail;
  manager->emit_message = jpeg_quiet;
  return manager;
}

// `state` and `picture` live in the caller's frame; `decoder` too (jpeg_destroy needs it after a jump).
bool decode_jpeg_into(JpegState& state, jpeg_decompress_struct& decoder, const std::uint8_t* bytes,
                      std::size_t size, bool grey, Picture& picture) {
  decoder.err = error_manager(state);
  if (setjmp(state.jump)) {
    jpeg_destroy_decompress(&decoder);
    return false;
  }
  jpeg_create_decompress(&decoder);
  jpeg_mem_src(&decoder, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(&decoder, TRUE);
  decoder.out_color_space = grey || decoder.num_components == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(&decoder);
  picture.width = static_cast<int>(decoder.output_width);
  picture.height = static_cast<int>(decoder.output_height);
  picture.channels = decoder.output_components;
  picture.bits = picture.significant_bits = 8;
  picture.data.resize(picture.stride() * picture.height);
  while (decoder.output_scanline < decoder.output_height) {
    JSAMPROW row = picture.data.data() + decoder.output_scanline * picture.stride();
    jpeg_read_scanlines(&decoder, &row, 1);
  }
  jpeg_finish_decompress(&decoder);
  jpeg_destroy_decompress(&decoder);
  return true;
}

bool encode_jpeg_into(JpegState& state, jpeg_compress_struct& encoder, const Image& image, int quality) {
  encoder.err = error_manager(state);
  if (setjmp(state.jump)) {
    jpeg_destroy_compress(&encoder);
    return false;
  }
  jpeg_create_compress(&encoder);
  jpeg_mem_dest(&encoder, &state.encoded, &state.encoded_size);
  encoder.image_width = static_cast<JDIMENSION>(image.width);
  encoder.image_height = static_cast<JDIMENSION>(image.height);
  encoder.input_components = 1;
  encoder.in_color_space = JCS_GRAYSCALE;
  jpeg_set_defaults(&encoder);
  jpeg_set_quality(&encoder, quality, TRUE);
  jpeg_start_compress(&encoder, TRUE);
  while (encoder.next_scanline < encoder.image_height) {
    auto row = const_cast<JSAMPROW>(image.row8(static_cast<int>(encoder.next_scanline)));
    jpeg_write_scanlines(&encoder, &row, 1);
  }
  jpeg_finish_compress(&encoder);
  jpeg_destroy_compress(&encoder);
  return true;
}

bool is_png(const std::uint8_t* bytes, std::size_t size) {
  return size >= 8 && png_sig_cmp(bytes, 0, 8) == 0;
}

bool is_jpeg(const std::uint8_t* bytes, std::size_t size) {
  return size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF;
}

bool is_pnm(const std::uint8_t* bytes, std::size_t size) {
  return size >= 2 && bytes[0] == 'P' && std::strchr("2356", bytes[1]) != nullptr && bytes[1] != '\0';
}

// `grey`: a colour JPEG is decoded to its luma, as libjpeg stores it (a PNG or PNM keeps its colour
// for to_grey: they store no luma).
Picture decode(const std::uint8_t* bytes, std::size_t size, const std::string& name, bool grey) {
  if (is_pnm(bytes, size)) return decode_pnm(bytes, size, name);
  Picture picture;
  if (is_png(bytes, size)) {
    PngState state;
    state.bytes = bytes;
    state.size = size;
    if (!decode_png_into(state, picture)) throw std::runtime_error(name + ": PNG: " + state.error);
    return picture;
  }
  if (is_jpeg(bytes, size)) {
    JpegState state;
    jpeg_decompress_struct decoder{};
    if (!decode_jpeg_into(state, decoder, bytes, size, grey, picture))
      throw std::runtime_error(name + ": JPEG: " + state.error);
    return picture;
  }
  throw std::runtime_error(name + ": not a PGM/PPM, PNG or JPEG file");
}

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw std::runtime_error(path.string() + ": read failed");
  return bytes;
}

}  // namespace

Picture decode_picture(const std::uint8_t* bytes, std::size_t size, const std::string& name) {
  return decode(bytes, size, name, false);
}

Picture read_picture(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  return decode(bytes.data(), bytes.size(), path.string(), false);
}

Image to_grey(const Picture& picture) {
  // A 16-bit picture keeps its significant bits (9-16: a PNM's maxval above 255, or 16).
  Image image(picture.width, picture.height, picture.bits == 16 ? picture.significant_bits : 8);
  const std::size_t pixels = static_cast<std::size_t>(picture.width) * picture.height;
  if (picture.channels == 1) {
    std::memcpy(image.data.data(), picture.data.data(), image.data.size());
    return image;
  }
  // Fixed point as OpenCV's cvtColor: weights scaled by 2^14, rounded.
  constexpr std::uint32_t kB = 1868, kG = 9617, kR = 4899, kShift = 14;
  const auto grey = [&](std::uint32_t b, std::uint32_t g, std::uint32_t r) {
    return (b * kB + g * kG + r * kR + (1U << (kShift - 1))) >> kShift;
  };
  const int c = picture.channels;
  if (picture.bits == 8) {
    const std::uint8_t* in = picture.data.data();
    for (std::size_t i = 0; i < pixels; ++i, in += c)
      image.data[i] = static_cast<std::uint8_t>(grey(in[0], in[1], in[2]));
  } else {
    const auto* in = reinterpret_cast<const std::uint16_t*>(picture.data.data());
    auto* out = reinterpret_cast<std::uint16_t*>(image.data.data());
    for (std::size_t i = 0; i < pixels; ++i, in += c)
      out[i] = static_cast<std::uint16_t>(grey(in[0], in[1], in[2]));
  }
  return image;
}

Image read_grey_image(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  return to_grey(decode(bytes.data(), bytes.size(), path.string(), true));
}

bool decode_jpeg_grey(const std::uint8_t* bytes, std::size_t size, Image& out, std::string* error) {
  if (!is_jpeg(bytes, size)) {
    if (error != nullptr) *error = "not a JPEG image (no start-of-image marker)";
    return false;
  }
  JpegState state;
  jpeg_decompress_struct decoder{};
  Picture picture;
  if (!decode_jpeg_into(state, decoder, bytes, size, true, picture)) {
    if (error != nullptr) *error = state.error;
    return false;
  }
  out = Image(picture.width, picture.height, 8);
  out.data = std::move(picture.data);
  return true;
}

std::vector<std::uint8_t> encode_jpeg_grey(const Image& image, int quality) {
  if (image.bits != 8) throw std::invalid_argument("encode_jpeg_grey: the image must be 8-bit");
  JpegState state;
  jpeg_compress_struct encoder{};
  const bool done = encode_jpeg_into(state, encoder, image, std::clamp(quality, 1, 100));
  std::vector<std::uint8_t> bytes;
  if (done) bytes.assign(state.encoded, state.encoded + state.encoded_size);
  std::free(state.encoded);  // NOLINT(cppcoreguidelines-no-malloc): allocated by libjpeg
  if (!done) throw std::runtime_error(std::string("JPEG encoding failed: ") + state.error);
  return bytes;
}

std::vector<std::uint8_t> encode_png(const PixelsView& pixels) {
  const bool layout =
      (pixels.bits == 8 && (pixels.channels == 1 || pixels.channels == 3 || pixels.channels == 4)) ||
      (pixels.bits == 16 && pixels.channels == 1);
  if (!layout || pixels.width <= 0 || pixels.height <= 0 || pixels.data == nullptr)
    throw std::invalid_argument("encode_png: need 8-bit grey, BGR or BGRA or 16-bit grey pixels, got " +
                                std::to_string(pixels.channels) + " channel(s) of " +
                                std::to_string(pixels.bits) + " bits, " + std::to_string(pixels.width) + "x" +
                                std::to_string(pixels.height));
  std::vector<std::uint8_t> bytes;
  PngState state;
  state.out = &bytes;
  if (!encode_png_into(state, pixels))
    throw std::runtime_error(std::string("PNG encoding failed: ") + state.error);
  return bytes;
}

void write_png(const std::filesystem::path& path, const PixelsView& pixels) {
  const std::vector<std::uint8_t> bytes = encode_png(pixels);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

PixelsView view_of(const Image& image) {
  return {image.width, image.height, 1, image.bits > 8 ? 16 : 8, image.data.data(), image.stride()};
}

}  // namespace panoptes
