// SPDX-License-Identifier: Apache-2.0
// Seeded fuzzing of the C3D reader: random truncations and bit flips of the real sample files and
// of our own export. Every damaged file must either read or fail with a ConfigError naming the
// file and an offset; nothing else may escape (and under the sanitizers nothing may crash).
#include <algorithm>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "c3d_test_support.h"
#include "panoptes/errors.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/trc.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct FuzzCounts {
  int read = 0;
  int rejected = 0;
};

// Damages `original` `rounds` times: half truncations (anywhere, biased to the header and
// parameters), half 1-8 bit flips (half of them inside the first 2 KiB, where the structure is).
FuzzCounts fuzz(const std::vector<std::uint8_t>& original, const std::string& name, std::uint32_t seed,
                int rounds) {
  std::mt19937 rng(seed);
  FuzzCounts counts;
  for (int round = 0; round < rounds; ++round) {
    std::vector<std::uint8_t> bytes = original;
    const std::size_t structure = std::min<std::size_t>(bytes.size(), 2048);
    if (round % 2 == 0) {
      const std::size_t limit = round % 4 == 0 ? structure : bytes.size();
      bytes.resize(std::uniform_int_distribution<std::size_t>(0, limit - 1)(rng));
    } else {
      const int flips = std::uniform_int_distribution<int>(1, 8)(rng);
      for (int i = 0; i < flips; ++i) {
        const std::size_t limit = round % 4 == 1 ? structure : bytes.size();
        const std::size_t at = std::uniform_int_distribution<std::size_t>(0, limit - 1)(rng);
        bytes[at] ^= static_cast<std::uint8_t>(1U << std::uniform_int_distribution<int>(0, 7)(rng));
      }
    }
    try {
      const C3dFile file = parse_c3d(bytes, name);
      EXPECT_EQ(file.points.positions.size(), file.points.frame_count() * file.points.marker_count());
      ++counts.read;
    } catch (const ConfigError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.rfind(name + ": offset ", 0), 0U) << message;
      ++counts.rejected;
    }
  }
  return counts;
}

TEST(C3dFuzz, TruncationsAndBitFlipsOfRealFilesReadOrFailNamingTheOffset) {
  int total_read = 0;
  int total_rejected = 0;
  std::uint32_t seed = 17;
  for (const char* name : {"Sample_Jump2.c3d", "Walk1.c3d", "vicon_zerowire.c3d", "Facial-Sing.c3d"}) {
    const fs::path path = test::shared_c3d(name);
    PANOPTES_REQUIRE_SHARED(path);
    const std::vector<std::uint8_t> original = read_bytes(path);
    ASSERT_NO_THROW(parse_c3d(original, name));
    const FuzzCounts counts = fuzz(original, name, seed++, 200);
    total_read += counts.read;
    total_rejected += counts.rejected;
  }
  // Both outcomes occur: flips in point data still read, truncations are refused.
  EXPECT_GT(total_read, 50);
  EXPECT_GT(total_rejected, 300);
}

TEST(C3dFuzz, TruncationsAndBitFlipsOfOurExport) {
  const MarkerTrajectories walk =
      load_trc(fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc");
  const std::vector<std::uint8_t> bytes = encode_c3d(walk, {});
  const FuzzCounts counts = fuzz(bytes, "walk.c3d", 4242, 400);
  EXPECT_GT(counts.read, 20);
  EXPECT_GT(counts.rejected, 200);
}

}  // namespace
}  // namespace panoptes
