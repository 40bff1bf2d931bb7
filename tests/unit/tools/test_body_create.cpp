// SPDX-License-Identifier: Apache-2.0
// panoptes_ctl body create's pure parts (panoptes/ctl_actions/body_create.h; issue 34 item 3):
// tracks chosen by id or by radius, the layout about the centroid or a pivot track, refusals that
// name what is wrong, and the bodies file appended so that the estimator's reader accepts it.
#include <filesystem>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../common/temp_dir.h"
#include "panoptes/calibration_file.h"
#include "panoptes/ctl_actions/body_create.h"
#include "panoptes/errors.h"

namespace panoptes::ctl {
namespace {

TrackPositions volume() {
  return {{3, {1.0, 2.0, 1.0}},
          {5, {1.1, 2.0, 1.0}},
          {7, {1.0, 2.2, 1.0}},
          {9, {1.0, 2.0, 1.05}},
          {12, {-1.0, 0.0, 1.5}}};
}

std::string refusal(const BodyRequest& request, const TrackPositions& seen) {
  try {
    make_body(request, select_tracks(request, seen), seen);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(BodyCreate, LayoutIsTheTracksAboutTheirCentroidInTheGivenOrder) {
  BodyRequest request;
  request.name = "wand";
  request.tracks = {7, 3, 5};
  const auto ids = select_tracks(request, volume());
  const BodyDefinition body = make_body(request, ids, volume());
  ASSERT_EQ(body.markers.size(), 3U);
  const Eigen::Vector3d centroid = (volume()[7] + volume()[3] + volume()[5]) / 3.0;
  EXPECT_LT((body.markers[0] - (volume()[7] - centroid)).norm(), 1e-15);
  EXPECT_LT((body.markers[2] - (volume()[5] - centroid)).norm(), 1e-15);
  EXPECT_LT((body.markers[0] + body.markers[1] + body.markers[2]).norm(), 1e-15);
  request.pivot = 3;
  const BodyDefinition pivoted = make_body(request, ids, volume());
  EXPECT_EQ(pivoted.markers[1], Eigen::Vector3d::Zero());
  EXPECT_LT((pivoted.markers[0] - Eigen::Vector3d(0, 0.2, 0)).norm(), 1e-12);
}

TEST(BodyCreate, NearSelectsTheTracksWithinTheRadiusNearestFirst) {
  BodyRequest request;
  request.name = "cluster";
  request.near = Eigen::Vector3d(1.0, 2.0, 1.0);
  request.radius_m = 0.15;
  EXPECT_EQ(select_tracks(request, volume()), (std::vector<std::int64_t>{3, 9, 5}));
  request.radius_m = 0.3;
  EXPECT_EQ(select_tracks(request, volume()).size(), 4U);
}

TEST(BodyCreate, RefusalsNameTheTracksAndTheReason) {
  BodyRequest request;
  request.name = "x";
  request.tracks = {3, 5, 40};
  EXPECT_NE(refusal(request, volume()).find("no confirmed track 40 on the bus (tracks seen: 3,5,7,9,12)"),
            std::string::npos)
      << refusal(request, volume());
  request.tracks = {3, 5};
  EXPECT_NE(refusal(request, volume()).find("at least 3 markers, got 2"), std::string::npos);
  request.tracks = {3, 5, 3};
  EXPECT_NE(refusal(request, volume()).find("track 3 is given twice"), std::string::npos);
  request.tracks = {3, 5, 7};
  request.pivot = 12;
  EXPECT_NE(refusal(request, volume()).find("--pivot"), std::string::npos);
  request.pivot.reset();
  TrackPositions line = volume();
  line[7] = {1.2, 2.0, 1.0};  // on the line through 3 and 5
  EXPECT_NE(refusal(request, line).find("body 'x'"), std::string::npos) << refusal(request, line);
  request.tracks.clear();
  request.near = Eigen::Vector3d(5, 5, 5);
  EXPECT_NE(refusal(request, volume()).find("--near"), std::string::npos);
}

TEST(BodyCreate, AppendKeepsTheOtherBodiesAndRefusesADuplicateName) {
  const testing::TempDir dir;
  const auto file = dir.write(
      "bodies.yaml", "bodies:\n  - name: head\n    markers: [[0, 0, 0], [0.16, 0, 0.02], [0.05, 0.19, 0]]\n");
  BodyRequest request;
  request.name = "wand";
  request.tracks = {3, 5, 7, 9};
  const BodyDefinition body = make_body(request, select_tracks(request, volume()), volume());
  append_body(file, body);
  const auto bodies = load_bodies(file);
  ASSERT_EQ(bodies.size(), 2U);
  EXPECT_EQ(bodies[0].name, "head");
  EXPECT_EQ(bodies[1].name, "wand");
  for (std::size_t i = 0; i < body.markers.size(); ++i)
    EXPECT_EQ(bodies[1].markers[i], body.markers[i]) << i;  // written with every digit
  try {
    append_body(file, body);
    FAIL() << "no refusal";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("a body named 'wand' is already defined"), std::string::npos);
  }
  const auto created = dir.file("new.yaml");  // a missing file is created
  append_body(created, body);
  EXPECT_EQ(load_bodies(created).size(), 1U);
  EXPECT_FALSE(std::filesystem::exists(dir.file("new.yaml.new")));
}

// Creations at the same moment (the CLI and a console, two consoles) each keep their body: without
// the lock, two writers read the same file and the later rename drops the other's body.
TEST(BodyCreate, AppendsAtTheSameMomentEachKeepTheirBody) {
  const testing::TempDir dir;
  const auto file = dir.write(
      "bodies.yaml", "bodies:\n  - name: head\n    markers: [[0, 0, 0], [0.16, 0, 0.02], [0.05, 0.19, 0]]\n");
  BodyRequest request;
  request.name = "template";
  request.tracks = {3, 5, 7, 9};
  const BodyDefinition body = make_body(request, select_tracks(request, volume()), volume());
  constexpr int kWriters = 8;
  constexpr int kEach = 5;
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w) {
    writers.emplace_back([&, w] {
      for (int k = 0; k < kEach; ++k) {
        BodyDefinition named = body;
        named.name = "body_" + std::to_string(w) + "_" + std::to_string(k);
        append_body(file, named);
      }
    });
  }
  for (auto& writer : writers) writer.join();
  const auto bodies = load_bodies(file);
  EXPECT_EQ(bodies.size(), 1U + kWriters * kEach);
  std::set<std::string> names;
  for (const auto& entry : bodies) names.insert(entry.name);
  EXPECT_EQ(names.size(), bodies.size());
}

}  // namespace
}  // namespace panoptes::ctl
