// SPDX-License-Identifier: Apache-2.0
// Marker set files: the two shipped sets load as designed, and every malformed set is refused
// with an error naming the file and the entry (docs/marker_sets.md, "File formats").
#include <string>

#include <gtest/gtest.h>

#include "labelling_test_support.h"
#include "panoptes/labelling_files/marker_set_file.h"

namespace panoptes::labelling {
namespace {

using test::error_of;
using test::marker_set_path;
using test::scratch_file;

std::size_t calibration_only(const MarkerSet& set) {
  std::size_t count = 0;
  for (const auto& marker : set.markers) count += marker.calibration_only ? 1 : 0;
  return count;
}

TEST(MarkerSetFile, Gait2392HasTheStaticTrialsMarkersInATree) {
  const MarkerSet set = load_marker_set(marker_set_path("gait2392"));
  EXPECT_EQ(set.name, "gait2392");
  EXPECT_EQ(set.markers.size(), 49U);
  EXPECT_EQ(set.segments.size(), 13U);
  EXPECT_EQ(calibration_only(set), 8U);  // lateral and medial knee and ankle markers, not in walk1
  EXPECT_TRUE(set.markers[*set.marker_index("R.Knee.Med")].calibration_only);
  EXPECT_FALSE(set.markers[*set.marker_index("R.Thigh.Front")].calibration_only);
  EXPECT_EQ(set.segments[*set.segment_of("R.Knee.Med")].name, "R.Thigh");
  EXPECT_EQ(set.segments[*set.segment_index("R.Shank")].parent, "R.Thigh");
  EXPECT_EQ(set.joints.size(), 4U);
  EXPECT_GT(set.sticks.size(), 40U);
}

TEST(MarkerSetFile, RajagopalHas47PhysicalMarkers) {
  const MarkerSet set = load_marker_set(marker_set_path("rajagopal"));
  EXPECT_EQ(set.markers.size(), 47U);
  EXPECT_EQ(set.segments.size(), 12U);
  EXPECT_EQ(calibration_only(set), 6U);  // medial elbow, knee and ankle
  EXPECT_FALSE(set.marker_index("R_HJC").has_value());
  EXPECT_EQ(set.joints.size(), 8U);
}

const char* const kGood = R"(name: tiny
markers: [A, B, C, D, {name: E, calibration_only: true}]
segments:
  - {name: Root, markers: [A, B, C]}
  - {name: Leaf, parent: Root, markers: [D, E]}
sticks: [[A, B]]
joints: [{name: J, child: Leaf, midpoint: [D, E]}]
)";

// `kGood` with `from` replaced by `to`.
std::string variant(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

struct BadSet {
  const char* what;
  std::string text;
  std::string entry;   // the entry the message must name
  std::string reason;  // and a word of the reason
};

TEST(MarkerSetFile, TheGoodVariantLoads) {
  const MarkerSet set = load_marker_set(scratch_file("good.yaml", kGood));
  EXPECT_EQ(set.segments.size(), 2U);
  EXPECT_EQ(set.joints[0].points.size(), 2U);
}

TEST(MarkerSetFile, EveryBadSetNamesTheFileAndTheEntry) {
  const BadSet cases[] = {
      {"duplicate marker", variant("C, D,", "C, C, D,"), "markers[3]", "duplicate marker 'C'"},
      {"unknown parent", variant("parent: Root", "parent: Rot"), "segments[1].parent",
       "unknown parent segment 'Rot'"},
      {"cycle", variant("{name: Root, markers", "{name: Root, parent: Leaf, markers"), "segments[0].parent",
       "cycle in the segment tree: Root -> Leaf -> Root"},
      {"self parent", variant("parent: Root", "parent: Leaf"), "segments[1].parent", "cycle"},
      {"marker twice in a segment", variant("[A, B, C]", "[A, B, C, B]"), "segments[0].markers[3]",
       "'B' listed twice in segment 'Root'"},
      {"marker in two segments", variant("[D, E]", "[D, E, A]"), "segments[1].markers[2]",
       "already in segment 'Root'"},
      {"marker in no segment", variant("[D, E]", "[D]"), "markers[4]", "'E' belongs to no segment"},
      {"unknown marker in a segment", variant("[D, E]", "[D, E, F]"), "segments[1].markers[2]",
       "unknown marker 'F'"},
      {"duplicate segment", variant("name: Leaf", "name: Root"), "segments[1].name",
       "duplicate segment 'Root'"},
      {"two roots", variant("parent: Root, ", ""), "segments", "exactly one segment without a parent"},
      {"unknown stick marker", variant("[[A, B]]", "[[A, Q]]"), "sticks[0][1]", "unknown marker 'Q'"},
      {"joint on the root", variant("child: Leaf", "child: Root"), "joints[0].child", "root"},
      {"joint on an unknown segment", variant("child: Leaf", "child: Lef"), "joints[0].child",
       "unknown segment"},
      {"typo in a key", variant("parent: Root", "parnet: Root"), "segments[1].parnet", "unknown key"},
      {"both kinds of joint", variant("midpoint: [D, E]", "midpoint: [D, E], point: X"), "joints[0]",
       "one of"},
  };
  for (const auto& bad : cases) {
    const auto path = scratch_file("bad.yaml", bad.text);
    const std::string message = error_of<ConfigError>([&] { load_marker_set(path); });
    EXPECT_NE(message.find(path.string() + ": " + bad.entry + ": "), std::string::npos)
        << bad.what << ": " << message;
    EXPECT_NE(message.find(bad.reason), std::string::npos) << bad.what << ": " << message;
  }
}

TEST(MarkerSetFile, MissingFileAndBadYamlNameTheFile) {
  const auto missing = scratch_file("missing.yaml");
  EXPECT_NE(error_of<ConfigError>([&] { load_marker_set(missing); }).find(missing.string()),
            std::string::npos);
  const auto broken = scratch_file("broken.yaml", "markers: [A, B\n");
  EXPECT_NE(error_of<ConfigError>([&] { load_marker_set(broken); }).find("YAML syntax error"),
            std::string::npos);
}

}  // namespace
}  // namespace panoptes::labelling
