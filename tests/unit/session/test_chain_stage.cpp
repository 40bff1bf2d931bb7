// SPDX-License-Identifier: Apache-2.0
// Chains in the offline session (issue 21, docs/articulated.md "Offline estimator"): the hand
// scene's features through run_offline with a ChainStage give Chain JSONL records (status, angles,
// markers with valid flags, tip), one grab and one release event, and the summary's counts
// (the file complete when run_offline returns).
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "panoptes/calibration_file.h"
#include "panoptes/session/offline_replay.h"
#include "panoptes/simulator.h"

namespace panoptes::session {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "scenes";

TEST(ChainStage, HandSceneThroughTheOfflineSession) {
  const Scene scene = Scene::load(kScenes / "hand.yaml");
  FeatureFiles input;
  for (const auto& camera : scene.cameras()) {
    const CameraSimulator simulator(scene, camera.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < 3 * kNsPerSecond; ++k)
      input.frames.push_back(simulator.features(k));
  }

  const fs::path out = fs::path(::testing::TempDir()) / "chain_stage_test.jsonl";
  EstimatorSession session(EstimatorConfig{});
  session.tracker().set_calibration(scene.calibration());
  ChainStage chains(load_chains(kScenes / "hand_bodies.yaml"), scene.calibration(), out.string());
  chains.set_prediction_horizon(0.08);
  OfflineReplayOptions options{false, false};
  options.chains = &chains;
  ASSERT_EQ(run_offline(session, std::move(input), options, "", ""), 0);

  std::ifstream file(out);
  std::string line;
  std::vector<std::string> events;
  int tracking = 0;
  int records = 0;
  int predicted_apart = 0;
  while (std::getline(file, line)) {
    const auto record = nlohmann::json::parse(line);
    ASSERT_EQ(record["chain"], "index") << line;
    if (record["type"] != "chain") {
      events.push_back(record["type"]);
      EXPECT_EQ(record["tip"].size(), 3U) << line;
      continue;
    }
    ++records;
    if (records == 1) {
      EXPECT_EQ(record["status"], "not_identified") << "no confirmed tracks yet";
    }
    if (record["status"] != "tracking") {
      EXPECT_FALSE(record.contains("tip")) << line;
      continue;
    }
    ++tracking;
    EXPECT_EQ(record["angles"].size(), 2U) << line;
    EXPECT_EQ(record["markers"].size(), 4U) << line;
    EXPECT_EQ(record["marker_valid"].size(), 4U) << line;
    EXPECT_EQ(record["tip"].size(), 3U) << line;
    EXPECT_EQ(record["prediction_horizon_ns"], 80'000'000) << line;
    ASSERT_EQ(record["predicted_tip"].size(), 3U) << line;
    predicted_apart += record["predicted_tip"] != record["tip"];
  }
  // The finger moves all the time: the tip 80 ms ahead is somewhere else.
  EXPECT_GT(predicted_apart, tracking * 9 / 10);
  EXPECT_EQ(events, (std::vector<std::string>{"grab", "release"}));
  EXPECT_GT(tracking, records * 9 / 10);
  const std::string summary = chains.summary();
  EXPECT_NE(summary.find("index tracking " + std::to_string(tracking) + ","), std::string::npos)
      << tracking << " in " << summary;
  EXPECT_NE(summary.find("1 grabs, 1 releases"), std::string::npos) << summary;
  fs::remove(out);
}

}  // namespace
}  // namespace panoptes::session
