// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "console_test_records.h"
#include "panoptes/console/console_state.h"

namespace panoptes::console {
namespace {

using nlohmann::json;
constexpr TimeNs kT0 = 1'700'000'000'000'000'000;

using test::vga_info;

TEST(CameraHealth, NamesTheReason) {
  StateOptions options;
  HealthInputs in;
  EXPECT_EQ(camera_health(in, options).light, Light::kRed);
  in.has_frames = true;
  in.since_frame_ns = 2 * kNsPerSecond;
  EXPECT_EQ(camera_health(in, options).reason, "no frames for 2.0 s");
  in.since_frame_ns = 0;
  in.has_status = true;
  in.camera_fps = 100;
  in.nominal_rate_hz = 100;
  EXPECT_EQ(camera_health(in, options).light, Light::kGreen);
  in.camera_fps = 70;
  EXPECT_EQ(camera_health(in, options).light, Light::kAmber);
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

TEST(ConsoleState, SnapshotCarriesThePredictedWindowsWhileFresh) {
  ConsoleState state;
  state.on_info("cam0", vga_info(), kT0);
  state.on_predictions("cam0", {{100.04F, 200.0F, 6.0F, 7.5F}, {320.0F, 240.0F, 10.0F, 10.0F}},
                       kT0 + 1'000'000);
  const nlohmann::json live = state.snapshot(kT0 + 20'000'000, false);
  ASSERT_EQ(live["cameras"][0]["windows"].size(), 2u);
  EXPECT_EQ(live["cameras"][0]["windows"][0], json::parse("[100.0, 200.0, 6.0, 7.5]"));
  // Windows of an estimator that stopped predicting are not drawn.
  EXPECT_TRUE(state.snapshot(kT0 + 3 * kNsPerSecond, false)["cameras"][0]["windows"].empty());
}

TEST(ConsoleState, ThePreviewIsServedAsPgmAndAMismatchedOneDropped) {
  ConsoleState state;
  EXPECT_FALSE(state.preview_pgm("cam0"));
  state.on_preview("cam0", kT0, 3, 2, std::string("\x00\x10\x20\x30\x40\xff", 6));
  const auto pgm = state.preview_pgm("cam0");
  ASSERT_TRUE(pgm);
  EXPECT_EQ(*pgm, std::string("P5\n3 2\n255\n\x00\x10\x20\x30\x40\xff", 17));
  EXPECT_EQ(state.snapshot(kT0, false)["cameras"][0]["preview_stamp_ns"], kT0);
  state.on_preview("cam0", kT0 + 1, 4, 4, std::string(6, '\x01'));  // 6 pixels claimed as 16: dropped
  EXPECT_EQ(*state.preview_pgm("cam0"), *pgm);
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
  EXPECT_EQ(outcomes[0].result, CommandResult::kApplied);
  EXPECT_EQ(outcomes[1].request, 11);
  EXPECT_EQ(outcomes[1].result, CommandResult::kRejected);
  EXPECT_EQ(outcomes[1].reason, "set_gain: gain is not supported");
  const auto timed_out = state.take_outcomes(kT0 + 4 * kNsPerSecond);
  ASSERT_EQ(timed_out.size(), 1u);
  EXPECT_EQ(timed_out[0].client, 2u);
  EXPECT_EQ(timed_out[0].result, CommandResult::kNoAck);
}

TEST(ConsoleState, RecordingsAreListedWhenTheirRecorderStopsAndCommandsResolveFromItsStatus) {
  ConsoleState state;
  RecorderRecord idle;
  state.on_recorder_status("studio", idle, kT0);
  EXPECT_TRUE(state.knows_recorder("studio"));
  state.on_recorder_command_sent({1, 5, "studio", true, kT0});
  RecorderRecord recording{true, "/data/take_1.mcap", 3, 100, 4096, 50, "", {}};
  state.on_recorder_status("studio", recording, kT0 + kNsPerSecond);
  recording.messages = 250;
  state.on_recorder_status("studio", recording, kT0 + 2 * kNsPerSecond);
  auto outcomes = state.take_outcomes(kT0 + 2 * kNsPerSecond);
  ASSERT_EQ(outcomes.size(), 1u);
  EXPECT_EQ(outcomes[0].request, 5);
  EXPECT_EQ(outcomes[0].result, CommandResult::kApplied);
  EXPECT_TRUE(state.snapshot(kT0 + 2 * kNsPerSecond, true)["recordings"].empty());
  state.on_recorder_command_sent({1, 6, "studio", false, kT0 + 3 * kNsPerSecond});
  RecorderRecord stopped{false, "/data/take_1.mcap", 3, 300, 8192, 0, "", {{"id_outside_partition", 7}}};
  state.on_recorder_status("studio", stopped, kT0 + 4 * kNsPerSecond);
  const json snapshot = state.snapshot(kT0 + 4 * kNsPerSecond, true);
  ASSERT_EQ(snapshot["recordings"].size(), 1u);
  EXPECT_EQ(snapshot["recordings"][0]["path"], "/data/take_1.mcap");
  EXPECT_EQ(snapshot["recordings"][0]["messages"], 300);  // the figures of the closing status
  EXPECT_DOUBLE_EQ(snapshot["recordings"][0]["seconds"].get<double>(), 3.0);
  EXPECT_EQ(snapshot["recorders"][0]["recording"], false);
  EXPECT_EQ(snapshot["recorders"][0]["rejections"]["id_outside_partition"], 7);  // the recorder's drops
  EXPECT_EQ(state.take_outcomes(kT0 + 4 * kNsPerSecond).at(0).request, 6);
  // A start that no status confirms ends as no_ack.
  state.on_recorder_command_sent({1, 7, "studio", true, kT0 + 5 * kNsPerSecond});
  outcomes = state.take_outcomes(kT0 + 9 * kNsPerSecond);
  ASSERT_EQ(outcomes.size(), 1u);
  EXPECT_EQ(outcomes[0].result, CommandResult::kNoAck);
  // A recorder silent for 5 s is no longer listed; its recordings stay.
  const json later = state.snapshot(kT0 + 10 * kNsPerSecond, true);
  EXPECT_TRUE(later["recorders"].empty());
  EXPECT_EQ(later["recordings"].size(), 1u);
}

TEST(ConsoleState, DetailsOfATrackAndABody) {
  ConsoleState state;
  TrackPoint track;
  track.id = 42;
  track.position = {1, 2, 3};
  track.velocity = {0.3, 0.4, 0};
  track.covariance = {4e-6, 0, 0, 9e-6, 0, 1e-6};
  track.cameras = 3;
  track.status = TrackStatus::kConfirmed;
  state.on_tracks({track}, kT0);
  state.on_tracks({track}, kT0 + kNsPerSecond / 4);
  json figures = state.details("track", "42", kT0 + kNsPerSecond / 4);
  EXPECT_EQ(figures["cameras"], 3);
  EXPECT_EQ(figures["status"], "confirmed");
  EXPECT_DOUBLE_EQ(figures["speed_m_s"].get<double>(), 0.5);
  EXPECT_EQ(figures["sigma_mm"], json({2.0, 3.0, 1.0}));
  EXPECT_DOUBLE_EQ(figures["age_s"].get<double>(), 0.25);
  EXPECT_TRUE(state.details("track", "43", kT0 + kNsPerSecond / 4).is_null());
  EXPECT_TRUE(state.details("track", "42", kT0 + 2 * kNsPerSecond).is_null());  // no longer live
  BodyRecord body;
  body.name = "wand";
  body.pose.position = {0.5, 0, 1};
  body.sigma = {1e-3, 1e-3, 2e-3, M_PI / 180, 0, 0};
  body.quality = 0.9F;
  body.stamp_ns = kT0 - 7;
  state.on_body(body, kT0);
  figures = state.details("body", "wand", kT0 + kNsPerSecond / 10);
  EXPECT_EQ(figures["stamp_ns"].get<std::int64_t>(), kT0 - 7);  // the pose's own stamp, not the receive time
  EXPECT_EQ(figures["position_m"], json({0.5, 0.0, 1.0}));
  EXPECT_EQ(figures["sigma_position_mm"], json({1.0, 1.0, 2.0}));
  EXPECT_DOUBLE_EQ(figures["sigma_rotation_deg"][0].get<double>(), 1.0);
  EXPECT_TRUE(state.details("body", "other", kT0).is_null());
}

ChainRecord tracking_finger() {
  ChainRecord chain;
  chain.name = "index";
  chain.chain_id = 1;
  chain.status = ChainStatus::kTracking;
  chain.stamp_ns = kT0;
  chain.angles = {0.5, 1.0};
  chain.markers = {{0, 0, 1}, {0.045, 0, 1}, {0.075, 0, 0.99}, {0.09, 0, 0.97}};
  chain.marker_valid = {true, true, false, true};
  chain.tip = {0.1, 0.00004, 0.96};
  chain.predicted_tip = {0.11, 0.01, 0.95};
  chain.prediction_horizon_ns = 80'000'000;
  chain.grabbing = true;
  return chain;
}

TEST(ConsoleState, ChainsInTheSnapshotAndTheirDetails) {
  ConsoleState state;
  ChainRecord lost;
  lost.name = "thumb";
  lost.chain_id = 2;
  lost.status = ChainStatus::kAmbiguous;
  ChainFrameRecord frame{
      kT0, {tracking_finger(), lost}, {{"index", ChainEventKind::kGrab, kT0, {0.1, 0, 0.96}, 1.7}}};
  ASSERT_TRUE(state.on_chains(frame, kT0));
  const json live = state.snapshot(kT0 + kNsPerSecond / 10, false);
  ASSERT_EQ(live["chains"].size(), 2u);
  const json& index = live["chains"][0];
  EXPECT_EQ(index["name"], "index");
  EXPECT_EQ(index["status"], "tracking");
  EXPECT_EQ(index["grabbing"], true);
  EXPECT_EQ(index["grabs"], 1);
  EXPECT_EQ(index["markers"].size(), 4u);
  EXPECT_EQ(index["valid"], json({true, true, false, true}));
  EXPECT_EQ(index["tip"], json({0.1, 0.0, 0.96}));  // 0.1 mm steps
  EXPECT_EQ(index["predicted_tip"], json({0.11, 0.01, 0.95}));
  EXPECT_DOUBLE_EQ(index["horizon_ms"].get<double>(), 80.0);
  EXPECT_FALSE(live.contains("chain_samples"));
  // Not tracking: name and status only, no shape.
  EXPECT_EQ(live["chains"][1]["status"], "ambiguous");
  EXPECT_FALSE(live["chains"][1].contains("markers"));
  const json figures = state.details("chain", "index", kT0 + kNsPerSecond / 10);
  EXPECT_EQ(figures["joint_angles_deg"], json({28.65, 57.3}));
  EXPECT_EQ(figures["markers_valid"], "3 of 4");
  EXPECT_EQ(figures["last_event"], "grab at [0.1,0.0,0.96], bend 97°");
  EXPECT_TRUE(state.details("chain", "index", kT0 + kNsPerSecond).is_null());  // no longer live
  EXPECT_TRUE(state.snapshot(kT0 + kNsPerSecond, false)["chains"].empty());
}

TEST(ConsoleState, AMalformedChainSampleIsCountedAndDropped) {
  ConsoleState state;
  ASSERT_TRUE(state.on_chains({kT0, {tracking_finger()}, {}}, kT0));
  ChainRecord short_of_angles = tracking_finger();
  short_of_angles.angles.pop_back();
  ChainRecord not_finite = tracking_finger();
  not_finite.predicted_tip[1] = std::nan("");
  ChainRecord bad_status = tracking_finger();
  bad_status.status = static_cast<ChainStatus>(7);  // as a message may carry it
  for (const ChainRecord& bad : {short_of_angles, not_finite, bad_status})
    EXPECT_FALSE(state.on_chains({kT0, {bad}, {}}, kT0 + 1));
  EXPECT_FALSE(state.on_chains(
      {kT0, {tracking_finger()}, {{"index", static_cast<ChainEventKind>(3), kT0, {}, 0}}}, kT0 + 1));
  EXPECT_EQ(
      chain_frame_error({kT0, {short_of_angles}, {}}),
      "chain 'index': markers: 4 markers, 4 valid flags and 1 angles (wants 3..5 markers, one flag each, "
      "markers - 2 angles)");
  EXPECT_EQ(chain_frame_error({kT0, {not_finite}, {}}), "chain 'index': tip or predicted_tip: not finite");
  const json full = state.snapshot(kT0 + 2, true);
  EXPECT_EQ(full["chain_samples"]["received"], 5);
  EXPECT_EQ(full["chain_samples"]["dropped"], 4);
  EXPECT_EQ(full["chain_samples"]["last_error"], "events[0]: kind 3 is not grab (0) or release (1)");
  // The dropped samples changed nothing: the chain shown is the good one, with no event counted.
  ASSERT_EQ(full["chains"].size(), 1u);
  EXPECT_EQ(full["chains"][0]["grabs"], 0);
  EXPECT_EQ(full["chains"][0]["markers"].size(), 4u);
  // More chain names than the state keeps: dropped, named.
  StateOptions options;
  options.max_chains = 1;
  ConsoleState small(options);
  ChainRecord other = tracking_finger();
  other.name = "middle";
  EXPECT_TRUE(small.on_chains({kT0, {tracking_finger()}, {}}, kT0));
  EXPECT_FALSE(small.on_chains({kT0, {tracking_finger(), other}, {}}, kT0));
  EXPECT_EQ(small.snapshot(kT0, true)["chain_samples"]["last_error"], "chains: more than 1 chain names");
}

TEST(ConsoleState, CaptureCoverageOnTheCamerasImageGrid) {
  ConsoleState state;
  state.on_info("cam0", vga_info(), kT0);
  state.start_coverage(kT0);
  state.add_coverage_frame("cam0", {{0, 0, 3}, {639, 479, 3}});
  state.add_coverage_frame("cam0", {});
  const json calibration = state.snapshot(kT0 + kNsPerSecond, true)["calibration"];
  EXPECT_EQ(calibration["capturing"], true);
  ASSERT_EQ(calibration["cameras"].size(), 1u);
  const json& camera = calibration["cameras"][0];
  EXPECT_EQ(camera["frames"], 2);
  EXPECT_EQ(camera["frames_with_blobs"], 1);
  EXPECT_EQ(camera["coverage_percent"], 3);  // 2 of 64 cells
  const std::string cells = camera["cells"];
  EXPECT_EQ(cells.front(), '1');  // top left
  EXPECT_EQ(cells.back(), '1');   // bottom right
  EXPECT_EQ(std::count(cells.begin(), cells.end(), '1'), 2);
  state.stop_coverage();
  EXPECT_EQ(state.snapshot(kT0 + kNsPerSecond, true)["calibration"]["capturing"], false);
}

}  // namespace
}  // namespace panoptes::console
