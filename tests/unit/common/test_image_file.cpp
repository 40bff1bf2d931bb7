// SPDX-License-Identifier: Apache-2.0
// Picture files without OpenCV's imgcodecs (panoptes/image_file.h): PGM/PPM, PNG and JPEG read by
// content, exact sample values, colour to grey with OpenCV's weights, errors naming the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "panoptes/image_file.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

using testing::TempDir;

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

std::string error_of(const std::filesystem::path& path) {
  try {
    read_picture(path);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

std::uint16_t at16(const Image& image, int x, int y) {
  return image.row16(y)[x];
}

TEST(ImageFile, PngRoundTripsEightBitGreyAndColourExactly) {
  TempDir dir;
  std::vector<std::uint8_t> grey(35), bgr(105);
  for (std::size_t i = 0; i < grey.size(); ++i) grey[i] = static_cast<std::uint8_t>(i * 7);
  for (std::size_t i = 0; i < bgr.size(); ++i) bgr[i] = static_cast<std::uint8_t>(255 - i);
  write_png(dir.file("grey.png"), {7, 5, 1, 8, grey.data(), 7});
  write_png(dir.file("colour.png"), {7, 5, 3, 8, bgr.data(), 21});

  const Picture g = read_picture(dir.file("grey.png"));
  EXPECT_EQ(g.width, 7);
  EXPECT_EQ(g.height, 5);
  EXPECT_EQ(g.channels, 1);
  EXPECT_EQ(g.bits, 8);
  EXPECT_EQ(g.data, grey);
  const Picture c = read_picture(dir.file("colour.png"));
  EXPECT_EQ(c.channels, 3);
  EXPECT_EQ(c.data, bgr);  // B, G, R in and out
}

TEST(ImageFile, PngKeepsSixteenBitSamplesAndDropsAlpha) {
  TempDir dir;
  Image deep(300, 2, 16);
  for (int x = 0; x < 300; ++x) {
    deep.row16(0)[x] = static_cast<std::uint16_t>(x * 218);
    deep.row16(1)[x] = static_cast<std::uint16_t>(65535 - x);
  }
  write_png(dir.file("deep.png"), view_of(deep));
  const Image back = read_grey_image(dir.file("deep.png"));
  EXPECT_EQ(back.bits, 16);
  EXPECT_EQ(back.data, deep.data);

  const std::uint8_t bgra[] = {10, 20, 30, 0, 40, 50, 60, 255};
  write_png(dir.file("alpha.png"), {2, 1, 4, 8, bgra, 8});
  const Picture p = read_picture(dir.file("alpha.png"));
  EXPECT_EQ(p.channels, 3);
  EXPECT_EQ(p.data, (std::vector<std::uint8_t>{10, 20, 30, 40, 50, 60}));
}

TEST(ImageFile, ColourBecomesGreyWithOpenCvsWeights) {
  TempDir dir;
  // Pure blue, green, red and white, as B G R.
  const std::uint8_t bgr[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
  write_png(dir.file("c.png"), {4, 1, 3, 8, bgr, 12});
  const Image grey = read_grey_image(dir.file("c.png"));
  ASSERT_EQ(grey.bits, 8);
  // cv::cvtColor(BGR2GRAY) gives 29, 150, 76 and 255 for these.
  EXPECT_EQ(grey.data, (std::vector<std::uint8_t>{29, 150, 76, 255}));
}

TEST(ImageFile, PnmBinaryAsciiAndColourWithTheirSignificantBits) {
  TempDir dir;
  write_bytes(dir.file("a.pgm"), std::string("P5\n# a comment\n3 1\n255\n") + std::string("\x01\x80\xff", 3));
  const Image a = read_grey_image(dir.file("a.pgm"));
  EXPECT_EQ(a.bits, 8);
  EXPECT_EQ(a.data, (std::vector<std::uint8_t>{1, 128, 255}));

  // 12-bit: the maxval is the only place that says so; samples are big-endian 16-bit words.
  write_bytes(dir.file("b.pgm"), std::string("P5 2 1 4095\n") + std::string("\x0f\xff\x01\x02", 4));
  const Image b = read_grey_image(dir.file("b.pgm"));
  EXPECT_EQ(b.bits, 12);
  EXPECT_EQ(at16(b, 0, 0), 4095);
  EXPECT_EQ(at16(b, 1, 0), 0x0102);

  write_bytes(dir.file("c.pgm"),
              "P2\n2 2\n# comment between samples? only in the header\n65535\n0 1\n65535 300\n");
  const Image c = read_grey_image(dir.file("c.pgm"));
  EXPECT_EQ(c.bits, 16);
  EXPECT_EQ(at16(c, 0, 1), 65535);
  EXPECT_EQ(at16(c, 1, 1), 300);

  write_bytes(dir.file("d.ppm"), std::string("P6\n1 1\n255\n") + std::string("\xff\x00\x00", 3));  // red
  const Picture d = read_picture(dir.file("d.ppm"));
  EXPECT_EQ(d.channels, 3);
  EXPECT_EQ(d.data, (std::vector<std::uint8_t>{0, 0, 255}));  // as B G R
  EXPECT_EQ(to_grey(d).data, (std::vector<std::uint8_t>{76}));
}

TEST(ImageFile, JpegRoundTripsGreyWithinTheCodecsError) {
  Image image(64, 48, 8);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) image.row8(y)[x] = static_cast<std::uint8_t>(2 * x + y);
  const std::vector<std::uint8_t> jpeg = encode_jpeg_grey(image, 95);
  ASSERT_GT(jpeg.size(), 100u);
  Image back;
  std::string error;
  ASSERT_TRUE(decode_jpeg_grey(jpeg.data(), jpeg.size(), back, &error)) << error;
  ASSERT_EQ(back.width, 64);
  ASSERT_EQ(back.height, 48);
  double worst = 0;
  for (std::size_t i = 0; i < image.data.size(); ++i)
    worst = std::max(worst, std::abs(static_cast<double>(image.data[i]) - back.data[i]));
  EXPECT_LE(worst, 3.0);

  // The same bytes as a file: a grey JPEG is read by content, whatever the name says.
  TempDir dir;
  write_bytes(dir.file("shot.png"), std::string(jpeg.begin(), jpeg.end()));
  const Picture picture = read_picture(dir.file("shot.png"));
  EXPECT_EQ(picture.channels, 1);
  EXPECT_EQ(picture.data, back.data);
}

TEST(ImageFile, BrokenInputIsAnErrorNamingTheFileOrTheProblem) {
  TempDir dir;
  write_bytes(dir.file("text.png"), "not a picture at all");
  EXPECT_NE(error_of(dir.file("text.png")).find("text.png: not a PGM/PPM, PNG or JPEG file"),
            std::string::npos)
      << error_of(dir.file("text.png"));
  write_bytes(dir.file("short.pgm"), "P5\n4 4\n255\n\x01\x02");
  EXPECT_NE(error_of(dir.file("short.pgm")).find("short.pgm: PNM pixel data truncated"), std::string::npos);
  write_bytes(dir.file("wide.pgm"), "P5\n4 4\n70000\n");
  EXPECT_NE(error_of(dir.file("wide.pgm")).find("maxval must be 1-65535"), std::string::npos);
  EXPECT_NE(error_of(dir.file("missing.png")).find("missing.png: cannot open"), std::string::npos);

  // A PNG cut in half: libpng's error, named.
  Image image(32, 32, 8);
  write_png(dir.file("whole.png"), view_of(image));
  std::ifstream in(dir.file("whole.png"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  write_bytes(dir.file("cut.png"), bytes.substr(0, bytes.size() / 2));
  const std::string cut = error_of(dir.file("cut.png"));
  EXPECT_NE(cut.find("cut.png: PNG: "), std::string::npos) << cut;

  // A camera frame that is not a JPEG (no start-of-image marker) or stops after its header.
  const std::vector<std::uint8_t> garbage(64, 0x5A);
  Image out;
  std::string error;
  EXPECT_FALSE(decode_jpeg_grey(garbage.data(), garbage.size(), out, &error));
  EXPECT_NE(error.find("start-of-image"), std::string::npos) << error;
  const std::vector<std::uint8_t> jpeg = encode_jpeg_grey(image, 90);
  EXPECT_FALSE(decode_jpeg_grey(jpeg.data(), 20, out, &error));
  EXPECT_FALSE(error.empty());

  const std::uint8_t two[] = {1, 2, 3, 4};
  EXPECT_THROW(encode_png({1, 1, 2, 8, two, 2}), std::invalid_argument);  // grey + alpha: not a layout
  EXPECT_THROW(encode_png({1, 1, 3, 16, two, 6}), std::invalid_argument);
}

}  // namespace
}  // namespace panoptes
