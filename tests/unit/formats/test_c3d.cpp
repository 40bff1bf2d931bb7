// SPDX-License-Identifier: Apache-2.0
// C3D: the real sample files of ../shared/data/c3d, round trips of our own files, the three
// processor types, and the defects a reader must name instead of crashing on.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "c3d_test_support.h"
#include "panoptes/errors.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/trc.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;
using test::HandBuiltC3d;

const fs::path kWalk = fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc";

struct SampleFile {
  const char* name;
  std::size_t points;
  double rate_hz;
  std::size_t frames;
  std::vector<std::string> labels;
};

// Expected values: point counts and rates from ../shared/data/README.md where it gives them
// (Sample_Jump2 51 points at 120 Hz; vicon_zerowire 55 points, 39 labelled, at 100 Hz); every
// label, the other counts and the frame counts from the independent JavaScript reader
// tests/c3d/read_c3d.js (`node tests/c3d/read_c3d.js <file>`), not from the reader under test.
const std::vector<SampleFile> kSamples = {
    {"Sample_Jump2.c3d", 51, 120, 264, {"THEA", "FHEA", "RHEA", "RSHO", "ROFF", "RELB", "RWRI", "LSHO",
                                        "LELB", "LWRI", "RASI", "LASI", "VSAC", "RTHI", "RKNE", "RKNE",
                                        "RSHA", "RANK", "RANK", "RHEE", "R.TO", "LTHI", "LKNE", "LKNE",
                                        "LSHA", "LANK", "LANK", "LHEE", "L.TO", "VMID", "VPEL", "VRHI",
                                        "VLHI", "VRKN", "VLKN", "VRAN", "VLAN", "VRKN", "VLKN", "VRAN",
                                        "VLAN", "VMID", "VMID", "VRHA", "VLHA", "VRTO", "VLTO", "VRTO",
                                        "VLTO", "VRAN", "VRHE"}},
    {"Walk1.c3d", 49, 60, 151, {"THEA", "FHEA", "RHEA", "RSHO", "ROFF", "RELB", "RWRI", "LSHO", "LELB",
                                "LWRI", "RASI", "LASI", "VSAC", "RTHI", "RKNE", "RSHA", "RANK", "RHEE",
                                "R.TO", "LTHI", "LKNE", "LSHA", "LANK", "LHEE", "L.TO", "RKNE", "RANK",
                                "LKNE", "LANK", "VMID", "VPEL", "VRHI", "VLHI", "VRKN", "VLKN", "VRAN",
                                "VLAN", "VRKN", "VLKN", "VRAN", "VLAN", "VMID", "VMID", "VRHA", "VLHA",
                                "VRTO", "VLTO", "VRTO", "VLTO"}},
    {"vicon_zerowire.c3d", 55, 100, 306, {"LKNE", "LWRB", "LFIN", "LWRA", "LTHI", "RWRA", "RFIN", "RFRM",
                                          "RWRB", "RUPA", "LTOE", "RSHO", "RELB", "LANK", "LASI", "LTIB",
                                          "LBHD", "RBAK", "RBHD", "LFRM", "C7",   "RKNE", "RTHI", "LSHO",
                                          "T10",  "LUPA", "RPSI", "LELB", "RASI", "RTIB", "LPSI", "RFHD",
                                          "RTOE", "CLAV", "STRN", "RANK", "LHEE", "RHEE", "LFHD", "*39",
                                          "*40",  "*41",  "*42",  "*43",  "*44",  "*45",  "*46",  "*47",
                                          "*48",  "*49",  "*50",  "*51",  "*52",  "*53",  "*54"}},
    {"Facial-Sing.c3d",
     38,
     100,
     3000,
     {"root-1",      "root-2",      "root-3",      "root-4",      "root-5",      "root-6",      "section1-1",
      "section1-2",  "section2-1",  "section2-2",  "section3-1",  "section3-2",  "section4-1",  "section4-2",
      "section5-1",  "section5-2",  "section6-1",  "section6-2",  "section7-1",  "section7-2",  "section8-1",
      "section8-2",  "section9-1",  "section9-2",  "section10-1", "section10-2", "section10-3", "section11-1",
      "section11-2", "section12-1", "section12-2", "section13-1", "section13-2", "section13-3", "section14-1",
      "section14-2", "section14-3", "Unlabeled1"}},
};

TEST(C3dSamples, MarkerCountsLabelsAndRatesMatchTheIndependentReader) {
  for (const SampleFile& sample : kSamples) {
    const fs::path path = test::shared_c3d(sample.name);
    PANOPTES_REQUIRE_SHARED(path);
    SCOPED_TRACE(sample.name);
    const C3dFile file = read_c3d(path);
    EXPECT_EQ(file.processor, C3dProcessor::kIntel);
    EXPECT_EQ(file.points.marker_count(), sample.points);
    EXPECT_EQ(file.points.marker_names, sample.labels);
    EXPECT_DOUBLE_EQ(file.points.data_rate_hz, sample.rate_hz);
    EXPECT_EQ(file.points.frame_count(), sample.frames);
    // Real point data: most samples of a take are valid, finite and within a 20 m room.
    std::size_t valid = 0;
    for (std::size_t i = 0; i < file.points.positions.size(); ++i) {
      if (file.points.valid[i] == 0) continue;
      ++valid;
      ASSERT_TRUE(file.points.positions[i].allFinite());
      ASSERT_LT(file.points.positions[i].norm(), 20.0);
    }
    EXPECT_GT(valid, file.points.positions.size() / 4);
  }
}

TEST(C3dSamples, ViconLabelsThirtyNineMarkersAndFacialSingHasNoAnalogGroup) {
  const fs::path vicon = test::shared_c3d("vicon_zerowire.c3d");
  const fs::path facial = test::shared_c3d("Facial-Sing.c3d");
  PANOPTES_REQUIRE_SHARED(vicon);
  PANOPTES_REQUIRE_SHARED(facial);
  const C3dFile file = read_c3d(vicon);
  const auto& names = file.points.marker_names;
  EXPECT_EQ(std::count_if(names.begin(), names.end(), [](const std::string& n) { return n.front() != '*'; }),
            39);
  EXPECT_GT(file.analog_per_frame, 0);  // its analog samples sit between the frames' points
  const C3dFile sing = read_c3d(facial);
  EXPECT_EQ(std::count(sing.groups.begin(), sing.groups.end(), "ANALOG"), 0);
  EXPECT_EQ(std::count(sing.groups.begin(), sing.groups.end(), "FORCE_PLATFORM"), 0);
}

double max_difference(const MarkerTrajectories& a, const MarkerTrajectories& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.positions.size(); ++i) {
    if (a.valid[i] != 0) worst = std::max(worst, (a.positions[i] - b.positions[i]).cwiseAbs().maxCoeff());
  }
  return worst;
}

TEST(C3dRoundTrip, WalkingDataReReadsWithinAMicrometre) {
  const MarkerTrajectories walk = load_trc(kWalk);
  for (const std::string units : {"mm", "m"}) {
    SCOPED_TRACE(units);
    const fs::path path = fs::temp_directory_path() / ("panoptes_walk_" + units + ".c3d");
    write_c3d(path, walk, C3dWriteOptions{units, "test"});
    const C3dFile file = read_c3d(path);
    fs::remove(path);
    EXPECT_EQ(file.points.marker_names, walk.marker_names);
    EXPECT_DOUBLE_EQ(file.points.data_rate_hz, walk.data_rate_hz);
    ASSERT_EQ(file.points.frame_count(), walk.frame_count());
    EXPECT_EQ(file.points.valid, walk.valid);
    EXPECT_TRUE(file.float_storage);
    EXPECT_LE(max_difference(walk, file.points), 1e-6);
    const C3dParameter* used = file.find("ANALOG", "USED");
    ASSERT_NE(used, nullptr);
    EXPECT_EQ(used->numbers, std::vector<double>{0.0});
  }
}

TEST(C3dRoundTrip, WalkingDataThroughTrcReReadsWithinAMicrometre) {
  const MarkerTrajectories walk = load_trc(kWalk);
  const fs::path path = fs::temp_directory_path() / "panoptes_walk_roundtrip.trc";
  write_trc(path, walk);
  const MarkerTrajectories again = load_trc(path);
  fs::remove(path);
  EXPECT_EQ(again.marker_names, walk.marker_names);
  EXPECT_EQ(again.valid, walk.valid);
  ASSERT_EQ(again.times_s.size(), walk.times_s.size());
  for (std::size_t f = 0; f < walk.times_s.size(); ++f) EXPECT_NEAR(again.times_s[f], walk.times_s[f], 1e-6);
  EXPECT_LE(max_difference(walk, again), 1e-6);
}

TEST(C3dRoundTrip, ResidualsCameraMasksGapsAndManyLabels) {
  // 300 points (labels continue in POINT:LABELS2), gaps, residuals and masks.
  MarkerTrajectories data;
  data.data_rate_hz = 240.0;
  data.units = "m";
  const std::size_t points = 300;
  const std::size_t frames = 5;
  for (std::size_t m = 0; m < points; ++m)
    data.marker_names.push_back("marker_with_a_long_name_" + std::to_string(m));
  for (std::size_t f = 0; f < frames; ++f) {
    data.times_s.push_back(static_cast<double>(f) / data.data_rate_hz);
    for (std::size_t m = 0; m < points; ++m) {
      data.positions.emplace_back(0.001 * static_cast<double>(m), 1.0 + 0.01 * static_cast<double>(f), -2.0);
      data.valid.push_back((f + m) % 7 == 0 ? 0 : 1);
      data.residuals_m.push_back(m % 2 == 0 ? 0.0F : 0.0005F);
      data.camera_masks.push_back(static_cast<std::uint8_t>(m % 128));
    }
  }
  const C3dFile file = parse_c3d(encode_c3d(data, {}), "memory.c3d");
  EXPECT_EQ(file.points.marker_names, data.marker_names);
  EXPECT_NE(file.find("POINT", "LABELS2"), nullptr);
  EXPECT_EQ(file.points.valid, data.valid);
  EXPECT_LE(max_difference(data, file.points), 1e-6);
  const double step = std::abs(file.point_scale) * 1e-3;  // one residual step, metres
  for (std::size_t i = 0; i < data.positions.size(); ++i) {
    if (data.valid[i] == 0) continue;
    EXPECT_EQ(file.points.camera_masks[i], data.camera_masks[i]);
    if (data.residuals_m[i] == 0.0F) {
      EXPECT_EQ(file.points.residuals_m[i], 0.0F);  // computed, not measured, stays so
    } else {
      EXPECT_NEAR(file.points.residuals_m[i], data.residuals_m[i], step / 2 + 1e-9);
    }
  }
}

TEST(C3dRoundTrip, MoreThan65535FramesUseTheTrialRange) {
  MarkerTrajectories data;
  data.data_rate_hz = 120.0;
  data.marker_names = {"a"};
  const std::size_t frames = 70000;
  for (std::size_t f = 0; f < frames; ++f) {
    data.times_s.push_back(static_cast<double>(f) / 120.0);
    data.positions.emplace_back(static_cast<double>(f) * 1e-5, 0.0, 0.0);
    data.valid.push_back(1);
  }
  const C3dFile file = parse_c3d(encode_c3d(data, {}), "long.c3d");
  ASSERT_EQ(file.points.frame_count(), frames);
  EXPECT_NEAR(file.points.position(frames - 1, 0).x(), static_cast<double>(frames - 1) * 1e-5, 1e-6);
}

TEST(C3dProcessors, IntelDecAndMipsInFloatAndIntegerStorage) {
  for (const int processor : {84, 85, 86}) {
    for (const bool float_storage : {true, false}) {
      SCOPED_TRACE(std::to_string(processor) + (float_storage ? " float" : " integer"));
      HandBuiltC3d builder;
      builder.processor = processor;
      builder.float_storage = float_storage;
      builder.points = 3;
      builder.frames = 4;
      builder.analog_per_frame = 2;
      const C3dFile file = parse_c3d(builder.build(), "hand.c3d");
      EXPECT_EQ(static_cast<int>(file.processor), processor);
      EXPECT_EQ(file.points.marker_names, (std::vector<std::string>{"M0", "M1", "M2"}));
      EXPECT_FLOAT_EQ(static_cast<float>(file.points.data_rate_hz), 50.0F);
      ASSERT_EQ(file.points.frame_count(), 4U);
      for (int f = 0; f < 4; ++f) {
        for (int m = 0; m < 3; ++m) {
          ASSERT_EQ(file.points.is_valid(f, m), HandBuiltC3d::valid(f, m)) << f << "," << m;
          if (!HandBuiltC3d::valid(f, m)) continue;
          for (int axis = 0; axis < 3; ++axis) {
            EXPECT_NEAR(file.points.position(f, m)[axis], HandBuiltC3d::coordinate(f, m, axis) * 1e-3, 1e-7);
          }
          EXPECT_EQ(file.points.camera_masks[f * 3 + m], 0x05);
          EXPECT_NEAR(file.points.residuals_m[f * 3 + m], 3 * 0.1 * 1e-3, 1e-9);
        }
      }
    }
  }
}

TEST(C3dProcessors, DecEncodingOfOneIsTheVaxConstant) {
  // VAX F_floating 1.0 is the word 0x4080 then 0x0000, little-endian: 80 40 00 00. Checks the
  // test's own DEC encoder, which the previous test relies on, against the format itself.
  HandBuiltC3d builder;
  builder.processor = 85;
  std::vector<std::uint8_t> bytes(4, 0);
  builder.putf(bytes, 0, 1.0F);
  EXPECT_EQ(bytes, (std::vector<std::uint8_t>{0x80, 0x40, 0x00, 0x00}));
}

std::string error_of(const std::vector<std::uint8_t>& bytes) {
  try {
    parse_c3d(bytes, "bad.c3d");
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

TEST(C3dBadInput, EachDefectIsNamedWithFileAndOffset) {
  HandBuiltC3d good;
  ASSERT_EQ(error_of(good.build()), "");

  HandBuiltC3d no_point = good;
  no_point.point_group = false;
  EXPECT_EQ(error_of(no_point.build()), "bad.c3d: offset 512: no POINT group in the parameter section");

  HandBuiltC3d no_used = good;
  no_used.used_parameter = false;
  EXPECT_EQ(error_of(no_used.build()), "bad.c3d: offset 512: POINT group has no USED parameter");

  HandBuiltC3d zero = good;
  zero.points = 0;
  EXPECT_EQ(error_of(zero.build()), "bad.c3d: offset 512: POINT:USED is 0: the file has no markers");

  std::vector<std::uint8_t> processor = good.build();
  processor[512 + 3] = 0x41;
  EXPECT_EQ(error_of(processor),
            "bad.c3d: offset 515: unknown processor type 65 (84 Intel, 85 DEC, 86 MIPS): cannot tell the "
            "byte order");

  std::vector<std::uint8_t> key = good.build();
  key[1] = 0x51;
  EXPECT_EQ(error_of(key), "bad.c3d: offset 1: not a C3D file: byte 2 is 81, expected 80 (0x50)");

  // 3 frames of 2 points x 16 bytes from offset 1024; cut inside the third frame.
  std::vector<std::uint8_t> truncated = good.build();
  truncated.resize(1024 + 2 * 32 + 10);
  EXPECT_EQ(
      error_of(truncated),
      "bad.c3d: offset 1088: data section truncated: 3 frames of 32 bytes need 96 bytes from offset 1024, "
      "the file has 74");

  // Issue 32: files from several vendors hold 0 or 1 in POINT:DATA_START and the right block in
  // the header; an impossible value yields to the other one, and only two impossible ones fail.
  const C3dFile right = parse_c3d(good.build(), "good.c3d");
  for (const auto& [header_block, parameter_block] :
       std::vector<std::pair<int, int>>{{3, 0}, {3, 1}, {3, 2}, {3, 40}, {0, 3}, {2, 3}}) {
    HandBuiltC3d vendor = good;
    vendor.header_data_start = header_block;
    vendor.parameter_data_start = parameter_block;
    const std::string what =
        "header " + std::to_string(header_block) + ", DATA_START " + std::to_string(parameter_block);
    ASSERT_EQ(error_of(vendor.build()), "") << what;
    const C3dFile read = parse_c3d(vendor.build(), "vendor.c3d");
    ASSERT_EQ(read.points.positions.size(), right.points.positions.size()) << what;
    for (std::size_t i = 0; i < right.points.positions.size(); ++i)
      EXPECT_EQ(read.points.positions[i], right.points.positions[i]) << what << ", sample " << i;
  }
  HandBuiltC3d neither = good;
  neither.header_data_start = 8;  // past the end of this 1120-byte file
  neither.parameter_data_start = 1;
  EXPECT_EQ(error_of(neither.build()),
            "bad.c3d: offset 16: the header puts the data section at block 8 and POINT:DATA_START at block "
            "1; neither can be: it must be a block from 3 (after the parameters) to the end of the file");

  EXPECT_EQ(error_of({}),
            "bad.c3d: offset 0: file ends inside the header block (a C3D file starts with a 512-byte "
            "header) (0 bytes, 512 needed here)");
  EXPECT_THROW(read_c3d("/nonexistent/missing.c3d"), ConfigError);
}

}  // namespace
}  // namespace panoptes
