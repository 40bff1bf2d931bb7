// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "panoptes/console/console_state.h"

namespace panoptes::console {
namespace {

constexpr TimeNs kT0 = 1'700'000'000'000'000'000;

CameraInfoRecord vga_info() {
  CameraInfoRecord info;
  info.nominal_rate_hz = 100;
  info.geometry.width = 640;
  info.geometry.height = 480;
  return info;
}

TEST(CameraHealth, NamesTheReason) {
  StateOptions options;
  HealthInputs in;
  EXPECT_EQ(camera_health(in, options).light, "red");
  in.has_frames = true;
  in.since_frame_ns = 2 * kNsPerSecond;
  EXPECT_EQ(camera_health(in, options).reason, "no frames for 2.0 s");
  in.since_frame_ns = 0;
  in.has_status = true;
  in.camera_fps = 100;
  in.nominal_rate_hz = 100;
  EXPECT_EQ(camera_health(in, options).light, "green");
  in.camera_fps = 70;
  EXPECT_EQ(camera_health(in, options).light, "amber");
  EXPECT_EQ(camera_health(in, options).reason, "70.0 fps, nominal 100.0");
  in.camera_fps = 100;
  in.drops_last_period = 3;
  EXPECT_EQ(camera_health(in, options).reason, "3 frames dropped in the last second");
  in.last_error = "set_gain: not supported";
  EXPECT_EQ(camera_health(in, options).reason, "last error: set_gain: not supported");
}

TEST(ConsoleState, SnapshotCarriesTheLatestBlobsAndFullPartsOnRequest) {
  ConsoleState state;
  state.on_info("cam0", vga_info(), kT0);
  state.on_features("cam0", {1, kT0, {{10, 20, 5}}}, kT0 + 1'000'000);
  state.on_features("cam0", {2, kT0 + 10'000'000, {{11.004, 21, 5}, {300, 200, 7}}}, kT0 + 12'000'000);
  const nlohmann::json live = state.snapshot(kT0 + 20'000'000, false);
  ASSERT_EQ(live["cameras"].size(), 1u);
  EXPECT_EQ(live["cameras"][0]["frame"], 2);
  ASSERT_EQ(live["cameras"][0]["blobs"].size(), 2u);
  EXPECT_DOUBLE_EQ(live["cameras"][0]["blobs"][0][0].get<double>(), 11.0);
  // Receive time minus stamp, smoothed (1 ms, then 2 ms with weight 0.1).
  EXPECT_NEAR(live["cameras"][0]["latency_ms"].get<double>(), 1.1, 1e-9);
  EXPECT_FALSE(live["cameras"][0].contains("geometry"));
  const nlohmann::json full = state.snapshot(kT0 + 20'000'000, true);
  EXPECT_EQ(full["cameras"][0]["geometry"]["width"], 640);
  // Stale blobs are not shown: a camera that stopped shows none, and a red light.
  const nlohmann::json later = state.snapshot(kT0 + 3 * kNsPerSecond, false);
  EXPECT_TRUE(later["cameras"][0]["blobs"].empty());
  EXPECT_EQ(later["cameras"][0]["health"]["light"], "red");
}

TEST(ConsoleState, CommandOutcomesFromTheCamerasCounters) {
  ConsoleState state;
  CameraStatusRecord status;
  status.counters["command_set_threshold"] = 1;
  state.on_status("cam0", status, kT0);
  state.on_command_sent({1, 10, "cam0", "set_threshold", 0, 0, kT0});
  state.on_command_sent({1, 11, "cam0", "set_gain", 0, 0, kT0});
  state.on_command_sent({2, 12, "cam0", "restart", 0, 0, kT0});
  EXPECT_TRUE(state.take_outcomes(kT0).empty());
  status.counters["command_set_threshold"] = 2;
  status.counters["bad_command"] = 1;
  status.last_error = "set_gain: gain is not supported";
  state.on_status("cam0", status, kT0 + kNsPerSecond);
  const auto outcomes = state.take_outcomes(kT0 + kNsPerSecond);
  ASSERT_EQ(outcomes.size(), 2u);
  EXPECT_EQ(outcomes[0].request, 10);
  EXPECT_EQ(outcomes[0].result, "applied");
  EXPECT_EQ(outcomes[1].request, 11);
  EXPECT_EQ(outcomes[1].result, "rejected");
  EXPECT_EQ(outcomes[1].reason, "set_gain: gain is not supported");
  const auto timed_out = state.take_outcomes(kT0 + 4 * kNsPerSecond);
  ASSERT_EQ(timed_out.size(), 1u);
  EXPECT_EQ(timed_out[0].client, 2u);
  EXPECT_EQ(timed_out[0].result, "no_ack");
}

}  // namespace
}  // namespace panoptes::console
