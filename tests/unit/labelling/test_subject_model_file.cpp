// SPDX-License-Identifier: Apache-2.0
// The subject model file: a model built from synthetic samples saves and reads back, and a
// hand-edited file that breaks the model's rules is refused naming the file and the entry.
#include <string>

#include <gtest/gtest.h>

#include "labelling_test_support.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace panoptes::labelling {
namespace {

using test::error_of;
using test::scratch_file;

// Two segments of a rigid toy standing still for 10 frames.
SubjectModel toy_model() {
  MarkerSet set;
  set.name = "toy";
  set.markers = {{"A"}, {"B"}, {"C"}, {"D"}, {"E", true}};
  set.segments = {{"Root", "", {"A", "B", "C"}}, {"Leaf", "Root", {"D", "E"}}};
  set.joints = {{"J", "Leaf", {"D", "E"}}};
  MarkerSamples samples;
  samples.source = "toy.trc";
  samples.rate_hz = 100.0;
  samples.names = {"A", "B", "C", "D", "E"};
  const Eigen::Vector3d layout[] = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, -0.3}, {0.05, 0, -0.3}};
  for (int f = 0; f < 10; ++f) {
    for (const auto& p : layout) samples.positions.push_back(p + Eigen::Vector3d(0.001 * f, 0, 0));
  }
  samples.valid.assign(samples.positions.size(), 1);
  return build_subject_model(set, samples, "toy");
}

TEST(SubjectModelFile, AToyModelReadsBack) {
  const SubjectModel model = toy_model();
  ASSERT_FALSE(find_subject_model_problem(model)) << find_subject_model_problem(model)->reason;
  const auto path = scratch_file("toy.yaml");
  save_subject_model(model, path);
  const SubjectModel back = load_subject_model(path);
  EXPECT_EQ(back.marker_count(), 5U);
  EXPECT_EQ(back.joints.size(), 1U);
  EXPECT_EQ(back.segment("Leaf")->parent, "Root");
  EXPECT_NEAR(back.segment("Root")->distances[0].mean_m, 0.1, 1e-6);
  // The static origin (the labeller's tree search starts from it): the leaf's one tracked marker, D.
  EXPECT_LT((model.segment("Leaf")->origin_m - Eigen::Vector3d(0.0045, 0, -0.3)).norm(), 1e-9);
  EXPECT_LT((back.segment("Leaf")->origin_m - model.segment("Leaf")->origin_m).norm(), 1e-5);
  EXPECT_LT((back.segment("Root")->origin_m - model.segment("Root")->origin_m).norm(), 1e-5);
}

struct BadModel {
  const char* what;
  std::string from;
  std::string to;
  std::string entry;
  std::string reason;
};

TEST(SubjectModelFile, EveryBadModelNamesTheFileAndTheEntry) {
  const std::string good = subject_model_to_yaml(toy_model());
  const BadModel cases[] = {
      {"format version", "subject_model: 1", "subject_model: 2", "subject_model", "format version 1"},
      {"duplicate segment", "name: Leaf", "name: Root", "segments[1].name", "duplicate segment 'Root'"},
      {"unknown parent", "parent: Root", "parent: Rot", "segments[1].parent", "unknown parent segment 'Rot'"},
      {"marker in two segments", "{name: D,", "{name: A,", "segments[1].markers[0]",
       "already in segment 'Root'"},
      {"distance across segments", "markers: [D, E]", "markers: [D, A]", "segments[1].distances[0].markers",
       "'A' is not in segment 'Leaf'"},
      {"zero tolerance", ", tolerance_m: 0.002000", ", tolerance_m: 0", "segments[0].distances[0]",
       "positive tolerance"},
      {"joint on the wrong parent", "parent: Root, child: Leaf", "parent: Leaf, child: Root", "joints[0]",
       "not a segment whose parent is 'Leaf'"},
      {"unknown flag kind", "flags:\n  []", "flags: [{kind: wobbly, marker: A, reason: x}]", "flags[0].kind",
       "expected absent"},
      {"typo", "has_pose: true", "has_poses: true", "segments[0].has_poses", "unknown key"},
  };
  for (const auto& bad : cases) {
    std::string text = good;
    const auto at = text.find(bad.from);
    ASSERT_NE(at, std::string::npos) << bad.what << ": '" << bad.from << "' not in\n" << good;
    text.replace(at, bad.from.size(), bad.to);
    const auto path = scratch_file("bad.yaml", text);
    const std::string message = error_of<ConfigError>([&] { load_subject_model(path); });
    EXPECT_NE(message.find(path.string() + ": " + bad.entry + ": "), std::string::npos)
        << bad.what << ": " << message;
    EXPECT_NE(message.find(bad.reason), std::string::npos) << bad.what << ": " << message;
  }
}

}  // namespace
}  // namespace panoptes::labelling
