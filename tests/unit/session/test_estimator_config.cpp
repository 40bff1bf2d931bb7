// SPDX-License-Identifier: Apache-2.0
// EstimatorConfig YAML: printed configurations load back equal; errors name the file and key.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/config.h"
#include "panoptes/session/estimator_config.h"

namespace panoptes::session {
namespace {

std::filesystem::path write_file(const std::string& name, const std::string& text) {
  auto path = std::filesystem::temp_directory_path() / ("panoptes_session_" + name);
  std::ofstream(path) << text;
  return path;
}

// "<file>: <key path>: <reason>" of loading `text`, or "" if it loads.
std::string load_error(const std::string& name, const std::string& text) {
  const auto path = write_file(name, text);
  try {
    load_estimator_config(path);
  } catch (const ConfigError& error) {
    std::filesystem::remove(path);
    return error.what();
  }
  std::filesystem::remove(path);
  return "";
}

EstimatorConfig unusual_config() {
  EstimatorConfig config;
  config.node.inbox_capacity = 123;
  config.node.latency_window_ms = 0.1;  // not exact in binary: must still read back exactly
  config.node.predictions = false;
  config.node.prediction_horizon_ms = 1.0 / 3.0;
  config.screen.max_blobs = 77;
  config.screen.max_future_ns = 123'456'789;
  config.tracker.process_noise = 12.345678901234567;
  config.tracker.init.window_ns = 17'000'001;
  config.tracker.init.epipolar_px = 2.5e-7;
  config.tracker.confirm_cameras = 4;
  config.tracker.max_unmatched_per_frame = 99;
  config.tracker.bodies.noise.jerk = 3e10;
  config.tracker.bodies.identification.min_markers = 4;
  config.tracker.bodies.identification.max_clique_steps = 5'000'000'000ULL;
  config.tracker.bodies.led_marker.retry_extra_cluster = false;
  config.tracker.bodies.led_marker.seed = 42;
  config.ros2.enabled = false;
  config.ros2.frame_id = "odom:#\"1\\'";    // YAML's special characters must survive the round trip
  config.ros2.child_frame_prefix = "true";  // a string, not a boolean
  config.ros2.tf_rate_hz = 0;
  config.ros2.topic_namespace = "/site_a/lab1";
  config.subjects.models = {"/data/s1.yaml", "/data/subject two, \"B\".yaml"};
  config.subjects.soft_segments = {"Torso", "true"};
  config.subjects.rate_hz = 0.0;
  config.subjects.min_track_age = 7;
  return config;
}

TEST(EstimatorConfig, PrintedConfigurationLoadsBackEqual) {
  for (const EstimatorConfig& config : {EstimatorConfig{}, unusual_config()}) {
    const auto path = write_file("round_trip.yaml", estimator_config_to_yaml(config));
    const EstimatorConfig loaded = load_estimator_config(path);
    std::filesystem::remove(path);
    EXPECT_TRUE(loaded == config) << estimator_config_to_yaml(loaded);
  }
  const auto path = write_file("round_trip2.yaml", estimator_config_to_yaml(unusual_config()));
  const EstimatorConfig loaded = load_estimator_config(path);
  std::filesystem::remove(path);
  EXPECT_EQ(loaded.node.latency_window_ms, 0.1);
  EXPECT_EQ(loaded.node.prediction_horizon_ms, 1.0 / 3.0);
  EXPECT_FALSE(loaded.node.predictions);
  EXPECT_EQ(loaded.tracker.process_noise, 12.345678901234567);
  EXPECT_EQ(loaded.tracker.init.window_ns, 17'000'001);
  EXPECT_EQ(loaded.tracker.bodies.identification.max_clique_steps, 5'000'000'000ULL);
  EXPECT_FALSE(loaded.tracker.bodies.led_marker.retry_extra_cluster);
  EXPECT_FALSE(loaded.ros2.enabled);
  EXPECT_EQ(loaded.ros2.frame_id, "odom:#\"1\\'");
  EXPECT_EQ(loaded.ros2.child_frame_prefix, "true");
  EXPECT_EQ(loaded.ros2.tf_rate_hz, 0);
  EXPECT_EQ(loaded.ros2.topic_namespace, "/site_a/lab1");
  EXPECT_EQ(loaded.subjects.models,
            (std::vector<std::string>{"/data/s1.yaml", "/data/subject two, \"B\".yaml"}));
  EXPECT_EQ(loaded.subjects.soft_segments, (std::vector<std::string>{"Torso", "true"}));
  EXPECT_EQ(loaded.subjects.rate_hz, 0.0);
  EXPECT_EQ(loaded.subjects.min_track_age, 7);
  EXPECT_FALSE(loaded == EstimatorConfig{});
}

TEST(EstimatorConfig, KeysLeftOutKeepTheirDefaults) {
  const auto path = write_file("partial.yaml", "tracker:\n  gate_chi2: 9.5\n  bodies:\n    max_nis: 3\n");
  const EstimatorConfig loaded = load_estimator_config(path);
  std::filesystem::remove(path);
  EstimatorConfig expected;
  expected.tracker.gate_chi2 = 9.5;
  expected.tracker.bodies.max_nis = 3;
  EXPECT_TRUE(loaded == expected);
  EXPECT_TRUE(load_error("empty.yaml", "").empty());
}

TEST(EstimatorConfig, UnknownKeysAreNamedWithTheirPath) {
  const std::string error = load_error("unknown.yaml", "tracker:\n  init:\n    windw_ns: 5\n");
  EXPECT_NE(error.find("panoptes_session_unknown.yaml: tracker.init.windw_ns: unknown key"),
            std::string::npos)
      << error;
  EXPECT_NE(load_error("top.yaml", "trackers: {}\n").find("top.yaml: trackers: unknown key"),
            std::string::npos);
}

TEST(EstimatorConfig, OutOfRangeValuesAreNamedWithTheirPath) {
  std::string error = load_error("range.yaml", "tracker:\n  confirm_cameras: 1\n");
  EXPECT_NE(error.find("range.yaml: tracker.confirm_cameras: must be an integer in [2, 64]"),
            std::string::npos)
      << error;
  error = load_error("negative.yaml", "tracker:\n  bodies:\n    noise:\n      jerk: -1\n");
  EXPECT_NE(error.find("negative.yaml: tracker.bodies.noise.jerk: must be a finite number > 0"),
            std::string::npos)
      << error;
  error = load_error("window.yaml", "node:\n  latency_window_ms: 20000\n");
  EXPECT_NE(error.find("window.yaml: node.latency_window_ms: must be a number in [0, 10000]"),
            std::string::npos)
      << error;
  error = load_error("nan.yaml", "tracker:\n  process_noise: .nan\n");
  EXPECT_NE(error.find("nan.yaml: tracker.process_noise:"), std::string::npos) << error;
}

TEST(EstimatorConfig, BadRos2FrameIdsAreNamedWithTheirPath) {
  std::string error = load_error("ros2.yaml", "ros2:\n  frame_id: /world\n");
  EXPECT_NE(error.find("ros2.yaml: ros2.frame_id: must not start with '/'"), std::string::npos) << error;
  error = load_error("ros2_empty.yaml", "ros2:\n  frame_id: \"\"\n");
  EXPECT_NE(error.find("ros2_empty.yaml: ros2.frame_id: must not be empty"), std::string::npos) << error;
  error = load_error("ros2_space.yaml", "ros2:\n  child_frame_prefix: \"a b\"\n");
  EXPECT_NE(error.find("ros2_space.yaml: ros2.child_frame_prefix: must not contain spaces"),
            std::string::npos)
      << error;
  EXPECT_TRUE(
      load_error("ros2_ok.yaml", "ros2:\n  enabled: false\n  frame_id: map\n  child_frame_prefix: \"\"\n")
          .empty());
}

TEST(EstimatorConfig, BadRos2RatesAndNamespacesAreNamedWithTheirPath) {
  std::string error = load_error("tf_rate.yaml", "ros2:\n  tf_rate_hz: 10001\n");
  EXPECT_NE(error.find("tf_rate.yaml: ros2.tf_rate_hz: must be an integer in [0, 10000]"), std::string::npos)
      << error;
  error = load_error("tf_rate_neg.yaml", "ros2:\n  tf_rate_hz: -1\n");
  EXPECT_NE(error.find("tf_rate_neg.yaml: ros2.tf_rate_hz:"), std::string::npos) << error;
  error = load_error("ns.yaml", "ros2:\n  namespace: /lab-1\n");
  EXPECT_NE(error.find("ns.yaml: ros2.namespace: '/lab-1': ROS 2 names hold only"), std::string::npos)
      << error;
  error = load_error("ns_slash.yaml", "ros2:\n  namespace: /lab1/\n");
  EXPECT_NE(error.find("ns_slash.yaml: ros2.namespace: '/lab1/': must not end with '/'"), std::string::npos)
      << error;
  EXPECT_TRUE(load_error("ns_ok.yaml", "ros2:\n  tf_rate_hz: 50\n  namespace: lab1\n").empty());
  EXPECT_EQ(EstimatorConfig{}.ros2.tf_rate_hz, 120);  // docs/ros2.md, "Options"
  EXPECT_EQ(EstimatorConfig{}.ros2.topic_namespace, "");
}

TEST(EstimatorConfig, WrongTypesAreNamedWithTheirPath) {
  std::string error = load_error("type.yaml", "screen:\n  max_blobs: many\n");
  EXPECT_NE(error.find("type.yaml: screen.max_blobs: expected an integer"), std::string::npos) << error;
  error = load_error("map.yaml", "node: 5\n");
  EXPECT_NE(error.find("map.yaml: node"), std::string::npos) << error;
  EXPECT_NE(error.find("expected a map"), std::string::npos) << error;
  error = load_error("flag.yaml", "node:\n  predictions: perhaps\n");
  EXPECT_NE(error.find("flag.yaml: node.predictions: expected true or false"), std::string::npos) << error;
}

// `subjects:` (docs/marker_sets.md, "Live labelling"): models relative to the settings file's folder,
// a single name as a list of one; bad entries named with their index.
TEST(EstimatorConfig, SubjectModelsAreReadRelativeToTheSettingsFile) {
  const auto path = write_file("subjects.yaml",
                               "subjects:\n  models: [s1.yaml, /abs/s2.yaml, ../up/s3.yaml]\n"
                               "  soft_segments: Torso\n  rate_hz: 60\n");
  const EstimatorConfig loaded = load_estimator_config(path);
  std::filesystem::remove(path);
  const std::filesystem::path folder = path.parent_path();
  EXPECT_EQ(loaded.subjects.models,
            (std::vector<std::string>{(folder / "s1.yaml").string(), "/abs/s2.yaml",
                                      (folder / "../up/s3.yaml").lexically_normal().string()}));
  EXPECT_EQ(loaded.subjects.soft_segments, std::vector<std::string>{"Torso"});
  EXPECT_EQ(loaded.subjects.rate_hz, 60.0);
  EXPECT_EQ(loaded.subjects.min_track_age, EstimatorConfig{}.subjects.min_track_age);
  EXPECT_TRUE(EstimatorConfig{}.subjects.models.empty());  // no labelling unless asked

  std::string error = load_error("subjects_empty.yaml", "subjects:\n  models: [s1.yaml, \"\"]\n");
  EXPECT_NE(error.find("subjects_empty.yaml: subjects.models[1]: must be a non-empty string"),
            std::string::npos)
      << error;
  error = load_error("subjects_map.yaml", "subjects:\n  models: [{a: 1}]\n");
  EXPECT_NE(error.find("subjects_map.yaml: subjects.models[0]: must be a non-empty string"),
            std::string::npos)
      << error;
  error = load_error("subjects_rate.yaml", "subjects:\n  rate_hz: -1\n");
  EXPECT_NE(error.find("subjects_rate.yaml: subjects.rate_hz: must be a number in [0, 1e+05]"),
            std::string::npos)
      << error;
  error = load_error("subjects_key.yaml", "subjects:\n  model: s1.yaml\n");
  EXPECT_NE(error.find("subjects_key.yaml: subjects.model: unknown key"), std::string::npos) << error;
}

TEST(EstimatorConfig, AMissingFileIsNamed) {
  try {
    load_estimator_config("/nonexistent/estimator.yaml");
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/estimator.yaml"), std::string::npos);
  }
}

}  // namespace
}  // namespace panoptes::session
