// SPDX-License-Identifier: Apache-2.0
// The console's models one by one (camera_model.h, estimator_model.h, scene_model.h,
// recorder_model.h, calibration_model.h, command_model.h): their state transitions, their to_json,
// the enums' JSON names, and bad samples counted; then ConsoleState's locks under threads.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "console_test_records.h"
#include "panoptes/console/console_state.h"

namespace panoptes::console {
namespace {

using nlohmann::json;
constexpr TimeNs kT0 = 1'700'000'000'000'000'000;
constexpr TimeNs kMs = 1'000'000;

TEST(ConsoleEnums, WriteTheNamesThePageReads) {
  EXPECT_EQ(json(Light::kGreen), "green");
  EXPECT_EQ(json(Light::kAmber), "amber");
  EXPECT_EQ(json(Light::kRed), "red");
  EXPECT_EQ(json(CommandResult::kApplied), "applied");
  EXPECT_EQ(json(CommandResult::kRejected), "rejected");
  EXPECT_EQ(json(CommandResult::kNoAck), "no_ack");
  EXPECT_EQ(json(ChainStatus::kTracking), "tracking");
  EXPECT_EQ(json(ChainStatus::kAmbiguous), "ambiguous");
  EXPECT_EQ(json(ChainStatus::kNotIdentified), "not_identified");
  EXPECT_EQ(json(ChainEventKind::kGrab), "grab");
  EXPECT_EQ(json(ChainEventKind::kRelease), "release");
  EXPECT_EQ(to_string(TrackStatus::kTentative), "tentative");
  EXPECT_EQ(to_string(TrackStatus::kConfirmed), "confirmed");
  EXPECT_EQ(to_string(TrackStatus::kCoasting), "coasting");
}

TEST(ConsoleEnums, KeepTheMessagesNumbersAndCheckUnknownOnes) {
  // The bus's octets map straight onto the enums (idl/panoptes.idl, idl/chains.idl).
  EXPECT_EQ(static_cast<int>(TrackStatus::kCoasting), 2);
  EXPECT_EQ(static_cast<int>(ChainStatus::kNotIdentified), 2);
  EXPECT_EQ(static_cast<int>(ChainEventKind::kRelease), 1);
  EXPECT_TRUE(known(ChainStatus::kAmbiguous));
  EXPECT_FALSE(known(static_cast<ChainStatus>(3)));
  EXPECT_FALSE(known(static_cast<ChainEventKind>(2)));
  // A track's octet outside 0..2 reads as coasting, as the page always read it.
  EXPECT_EQ(track_status_of(0), TrackStatus::kTentative);
  EXPECT_EQ(track_status_of(1), TrackStatus::kConfirmed);
  EXPECT_EQ(track_status_of(2), TrackStatus::kCoasting);
  EXPECT_EQ(track_status_of(9), TrackStatus::kCoasting);
  EXPECT_EQ(to_string(track_status_of(255)), "coasting");
}

TEST(ConsoleEnums, ACommandOutcomeIsThePagesCommandResult) {
  const json message = CommandOutcome{3, 17, CommandResult::kRejected, "gain is not supported"};
  EXPECT_EQ(message.dump(),
            R"({"id":17,"reason":"gain is not supported","result":"rejected","type":"command_result"})");
}

using test::vga_info;

TEST(CameraModel, HealthGoesFromRedToGreenAsFramesAndStatusArrive) {
  CameraModel cameras{StateOptions{}};
  EXPECT_FALSE(cameras.knows("cam0"));
  EXPECT_EQ(cameras.health("cam0", kT0).light, Light::kRed);
  cameras.on_info("cam0", vga_info());
  EXPECT_EQ(cameras.health("cam0", kT0).reason, "no frames received");
  cameras.on_features("cam0", {1, kT0, {}}, kT0);
  EXPECT_EQ(cameras.health("cam0", kT0).light, Light::kAmber);
  EXPECT_EQ(cameras.health("cam0", kT0).reason, "no camera_status yet");
  CameraStatusRecord status;
  status.fps = 100;
  cameras.on_status("cam0", status, kT0);
  EXPECT_EQ(cameras.health("cam0", kT0).light, Light::kGreen);
  // Drops count between two statuses: the first sets the baseline.
  status.drops_queue = 4;
  cameras.on_status("cam0", status, kT0 + 1000 * kMs);
  EXPECT_EQ(cameras.health("cam0", kT0 + 1000 * kMs).reason, "4 frames dropped in the last second");
  cameras.on_status("cam0", status, kT0 + 2000 * kMs);
  EXPECT_EQ(cameras.health("cam0", kT0 + 2000 * kMs).light, Light::kRed) << "frames stopped 2 s ago";
  cameras.on_features("cam0", {2, kT0 + 2000 * kMs, {}}, kT0 + 2000 * kMs);
  EXPECT_EQ(cameras.health("cam0", kT0 + 2000 * kMs).light, Light::kGreen);
}

TEST(CameraModel, ToJsonAddsTheSlowPartsAndTheUsageWhenFull) {
  CameraModel cameras{StateOptions{}};
  cameras.on_info("cam0", vga_info());
  cameras.on_features("cam0", {7, kT0, {{1.234F, 5.678F, 9.99F}}}, kT0 + 3 * kMs);
  const std::map<std::string, CameraUsageRecord> usage = {{"cam0", {0.91234, 1.005}}};
  const json live = cameras.to_json(kT0 + 3 * kMs, false, usage);
  ASSERT_EQ(live.size(), 1U);
  EXPECT_EQ(live[0]["blobs"], json::parse("[[1.23, 5.68, 10.0]]"));
  EXPECT_EQ(live[0]["health"]["light"], "amber");
  EXPECT_DOUBLE_EQ(live[0]["latency_ms"].get<double>(), 3.0);
  EXPECT_FALSE(live[0].contains("usage"));
  const json full = cameras.to_json(kT0 + 3 * kMs, true, usage);
  EXPECT_DOUBLE_EQ(full[0]["usage"]["utilisation"].get<double>(), 0.912);
  EXPECT_EQ(full[0]["geometry"]["width"], 640);
  EXPECT_FALSE(full[0].contains("status"));
  EXPECT_FALSE(cameras.to_json(kT0, true, {})[0].contains("usage"));
  // A calibration replaces camera_info's geometry.
  CameraGeometry calibrated;
  calibrated.width = 320;
  cameras.on_calibration({{"cam0", calibrated}});
  EXPECT_EQ(cameras.to_json(kT0, true, {})[0]["geometry"]["width"], 320);
}

TEST(CameraModel, ReceivedRateFallsToZeroWhenFramesStopAndStatusHasAnAge) {
  CameraModel cameras{StateOptions{}};
  cameras.on_info("cam0", vga_info());
  TimeNs t = kT0;
  for (std::int64_t frame = 0; frame <= 120; ++frame, t += 10 * kMs)
    cameras.on_features("cam0", {frame, t, {}}, t);
  const TimeNs last = t - 10 * kMs;
  EXPECT_NEAR(cameras.to_json(last, false, {})[0]["rx_fps"].get<double>(), 100.0, 0.5);
  CameraStatusRecord status;
  status.fps = 100;
  cameras.on_status("cam0", status, last);
  EXPECT_DOUBLE_EQ(cameras.to_json(last + 400 * kMs, true, {})[0]["status_age_s"].get<double>(), 0.4);
  // Frames stopped: the last whole second's 100 fps is no longer what is received.
  EXPECT_EQ(cameras.to_json(last + 1500 * kMs, false, {})[0]["rx_fps"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(cameras.to_json(last + 16000 * kMs, true, {})[0]["status_age_s"].get<double>(), 16.0);
  // A slow camera: the window its first frame opened is still open after 1.5 s with one more
  // frame in it, and says so before a frame closes it.
  cameras.on_features("cam1", {1, kT0, {}}, kT0);
  cameras.on_features("cam1", {2, kT0 + 900 * kMs, {}}, kT0 + 900 * kMs);
  EXPECT_NEAR(cameras.to_json(kT0 + 1500 * kMs, false, {})[1]["rx_fps"].get<double>(), 0.7, 0.05);
  EXPECT_EQ(cameras.to_json(kT0 + 1950 * kMs, false, {})[1]["rx_fps"].get<double>(), 0.0);
}

TEST(CameraModel, ABadPreviewIsRefusedAndKeepsThePreviousOne) {
  CameraModel cameras{StateOptions{}};
  EXPECT_TRUE(cameras.on_preview("cam0", kT0, 2, 1, "ab"));
  EXPECT_FALSE(cameras.on_preview("cam0", kT0 + 1, 2, 2, "ab"));
  EXPECT_FALSE(cameras.on_preview("cam0", kT0 + 1, 0, 0, ""));
  EXPECT_EQ(*cameras.preview_pgm("cam0"), "P5\n2 1\n255\nab");
  EXPECT_FALSE(cameras.preview_pgm("cam1"));
}

TEST(EstimatorModel, NullUntilAStatusThenItsFiguresAndAge) {
  EstimatorModel estimator;
  EXPECT_TRUE(estimator.to_json(kT0).is_null());
  EXPECT_TRUE(estimator.usage().empty());
  estimator.on_status({3, 1, 12.345, 0.67891, {{"cam0", {0.5, 2}}}}, kT0);
  EXPECT_EQ(estimator.to_json(kT0 + 1500 * kMs).dump(),
            R"({"age_s":1.5,"cameras_live":0,"cameras_lost":0,"cpu_percent":12.3,"lost":[],"refused":[],)"
            R"("tracks_coasting":0,"tracks_confirmed":3,"tracks_tentative":1,"tracks_unobserved":0,)"
            R"("update_p99_ms":0.679})");
  EXPECT_EQ(estimator.usage().count("cam0"), 1U);
}

// Issue 34: a camera the estimator lost is named with its silence; a second writer's refusals too.
TEST(EstimatorModel, NamesLostCamerasAndRefusedSecondWriters) {
  EstimatorModel estimator;
  EstimatorRecord status;
  status.tracks_confirmed = 3;
  status.cameras_live = 3;
  status.cameras_lost = 1;
  status.cameras = {{"c0", {1.0, 2, "live", 0.01, 812}},
                    {"c1", {1.0, 2, "live", 0.01, 0}},
                    {"c2", {1.0, 2, "live", 0.0, 0}},
                    {"c3", {0.0, 2, "lost", 1.234, 0}}};
  estimator.on_status(status, kT0);
  const json j = estimator.to_json(kT0);
  EXPECT_EQ(j["cameras_live"], 3);
  EXPECT_EQ(j["cameras_lost"], 1);
  EXPECT_EQ(j["lost"].dump(), R"([{"id":"c3","since_s":1.2}])");
  EXPECT_EQ(j["refused"].dump(), R"([{"frames":812,"id":"c0"}])");
  // The camera card gets the estimator's view of its camera.
  CameraModel cameras{StateOptions{}};
  cameras.on_info("c3", vga_info());
  const json card = cameras.to_json(kT0, true, estimator.usage())[0];
  EXPECT_EQ(card["usage"]["state"], "lost");
  EXPECT_DOUBLE_EQ(card["usage"]["since_last_frame_s"].get<double>(), 1.2);
}

TrackPoint track(std::int64_t id, TrackStatus status) {
  TrackPoint point;
  point.id = id;
  point.position = {1.00004, 2, 3};
  point.status = status;
  return point;
}

TEST(SceneModel, TracksCarryTheirStatusNumberAndAgeFromFirstSeen) {
  SceneModel scene{StateOptions{}};
  scene.on_tracks({track(4, TrackStatus::kTentative)}, kT0);
  scene.on_tracks({track(4, TrackStatus::kCoasting), track(5, TrackStatus::kConfirmed)}, kT0 + 100 * kMs);
  const json out = scene.to_json(kT0 + 100 * kMs, false);
  EXPECT_EQ(out["tracks"].dump(), "[[4,1.0,2.0,3.0,2],[5,1.0,2.0,3.0,1]]");
  EXPECT_EQ(scene.details("track", "4", kT0 + 100 * kMs)["status"], "coasting");
  EXPECT_DOUBLE_EQ(scene.details("track", "4", kT0 + 100 * kMs)["age_s"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(scene.details("track", "5", kT0 + 100 * kMs)["age_s"].get<double>(), 0.0);
  EXPECT_TRUE(scene.to_json(kT0 + 700 * kMs, false)["tracks"].empty()) << "stale tracks are not shown";
  EXPECT_TRUE(scene.details("planet", "4", kT0).is_null());
  EXPECT_FALSE(out.contains("chain_samples"));
}

TEST(SceneModel, ABodyAbsentLongerThanItsTimeoutStartsAgainAtAgeZero) {
  SceneModel scene{StateOptions{}};
  BodyRecord body;
  body.name = "wand";
  scene.on_body(body, kT0);
  scene.on_body(body, kT0 + 400 * kMs);
  EXPECT_DOUBLE_EQ(scene.details("body", "wand", kT0 + 400 * kMs)["age_s"].get<double>(), 0.4);
  EXPECT_TRUE(scene.details("body", "wand", kT0 + 1000 * kMs).is_null());
  EXPECT_TRUE(scene.to_json(kT0 + 1000 * kMs, false)["bodies"].empty());
  scene.on_body(body, kT0 + 2000 * kMs);
  EXPECT_DOUBLE_EQ(scene.details("body", "wand", kT0 + 2000 * kMs)["age_s"].get<double>(), 0.0);
}

TEST(SceneModel, BadChainSamplesAreCountedWithTheirReason) {
  SceneModel scene{StateOptions{}};
  ChainRecord chain;
  chain.name = "index";
  chain.chain_id = 1;
  chain.status = ChainStatus::kAmbiguous;
  EXPECT_TRUE(scene.on_chains({kT0, {chain}, {}}, kT0));
  chain.status = static_cast<ChainStatus>(5);
  EXPECT_FALSE(scene.on_chains({kT0, {chain}, {}}, kT0));
  chain.status = ChainStatus::kAmbiguous;
  chain.chain_id = 0;
  EXPECT_FALSE(scene.on_chains({kT0, {chain}, {}}, kT0));
  EXPECT_EQ(scene.chain_samples().received, 3U);
  EXPECT_EQ(scene.chain_samples().dropped, 2U);
  const json full = scene.to_json(kT0, true);
  EXPECT_EQ(full["chain_samples"]["last_error"],
            "chain 'index': name: empty or longer than 128 characters, or chain_id 0");
  ASSERT_EQ(full["chains"].size(), 1U);
  EXPECT_EQ(full["chains"][0]["status"], "ambiguous");
}

TEST(SceneModel, GrabsAndReleasesAreCountedPerChain) {
  SceneModel scene{StateOptions{}};
  ChainRecord chain;
  chain.name = "index";
  chain.chain_id = 1;
  const ChainEventRecord grab{"index", ChainEventKind::kGrab, kT0, {}, 0};
  const ChainEventRecord release{"index", ChainEventKind::kRelease, kT0, {}, 0};
  const ChainEventRecord elsewhere{"thumb", ChainEventKind::kGrab, kT0, {}, 0};
  ASSERT_TRUE(scene.on_chains({kT0, {chain}, {grab, elsewhere}}, kT0));
  ASSERT_TRUE(scene.on_chains({kT0, {chain}, {release, grab}}, kT0));
  const json chains = scene.to_json(kT0, false)["chains"];
  EXPECT_EQ(chains[0]["grabs"], 2);
  EXPECT_EQ(chains[0]["releases"], 1);
  EXPECT_EQ(scene.details("chain", "index", kT0)["last_event"], "grab at [0.0,0.0,0.0], bend 0°");
}

TEST(RecorderModel, KeepsTheNewestRecordingsAndRestartsTheClockOnANewFile) {
  StateOptions options;
  options.max_recordings = 2;
  RecorderModel recorders(options);
  EXPECT_FALSE(recorders.knows("studio"));
  for (int take = 1; take <= 3; ++take) {
    RecorderRecord status{true, "take_" + std::to_string(take) + ".mcap", 1, 10, 100, 0, "", {}};
    recorders.on_status("studio", status, kT0 + static_cast<TimeNs>(take) * 1000 * kMs);
  }
  // Each new file closed the previous one; the third is still open.
  ASSERT_EQ(recorders.recordings().size(), 2U);
  EXPECT_EQ(recorders.recordings()[0].path, "take_1.mcap");
  recorders.on_status("studio", {}, kT0 + 4500 * kMs);
  ASSERT_EQ(recorders.recordings().size(), 2U) << "max_recordings keeps the newest";
  EXPECT_EQ(recorders.recordings()[0].path, "take_2.mcap");
  EXPECT_EQ(recorders.recordings()[1].path, "take_3.mcap");
  const json out = recorders.to_json(kT0 + 4500 * kMs);
  EXPECT_DOUBLE_EQ(out["recordings"][1]["seconds"].get<double>(), 1.5);
  EXPECT_EQ(out["recorders"][0]["recording"], false);
  EXPECT_TRUE(recorders.to_json(kT0 + 20'000 * kMs)["recorders"].empty())
      << "a silent recorder is not listed";
}

TEST(CalibrationModel, CoverageStartsClearedAndItsClockStopsAtStop) {
  CalibrationModel calibration;
  EXPECT_EQ(calibration.to_json(kT0)["seconds"], 0.0);
  calibration.start_coverage(kT0);
  calibration.add_coverage_frame("cam0", {{639, 0, 1}}, std::make_pair(640, 480));
  EXPECT_TRUE(calibration.capturing());
  calibration.stop_coverage(kT0 + 2500 * kMs);
  const json out = calibration.to_json(kT0 + 9000 * kMs);
  EXPECT_EQ(out["capturing"], false);
  EXPECT_DOUBLE_EQ(out["seconds"].get<double>(), 2.5);
  EXPECT_EQ(out["cameras"][0]["cells"].get<std::string>().substr(0, 8), "00000001");  // top right
  calibration.start_coverage(kT0 + 10'000 * kMs);
  EXPECT_TRUE(calibration.to_json(kT0 + 10'000 * kMs)["cameras"].empty());
  calibration.set_job(R"({"step":"solve"})", R"({"step":"solve","report":{}})");
  EXPECT_EQ(calibration.to_json(kT0)["job"]["step"], "solve");
  EXPECT_EQ(calibration.job(), R"({"step":"solve","report":{}})");
}

TEST(CommandModel, CountsGoToTheCommandsInTheOrderSent) {
  CommandModel commands{StateOptions{}};
  CameraStatusRecord status;
  status.counters["command_set_gain"] = 5;
  commands.on_command_sent({1, 1, "cam0", "set_gain", 0, 0, kT0}, &status);
  commands.on_command_sent({1, 2, "cam0", "set_gain", 0, 0, kT0}, &status);
  commands.on_command_sent({1, 3, "cam1", "set_gain", 0, 0, kT0}, nullptr);
  EXPECT_EQ(commands.pending(), 3U);
  status.counters["command_set_gain"] = 6;  // one of the two applied so far
  commands.on_camera_status("cam0", status);
  auto outcomes = commands.take_outcomes(kT0);
  ASSERT_EQ(outcomes.size(), 1U);
  EXPECT_EQ(outcomes[0].request, 1);
  EXPECT_EQ(outcomes[0].result, CommandResult::kApplied);
  EXPECT_TRUE(commands.take_outcomes(kT0).empty()) << "an outcome is handed over once";
  outcomes = commands.take_outcomes(kT0 + 3001 * kMs);
  ASSERT_EQ(outcomes.size(), 2U);
  EXPECT_EQ(outcomes[0].result, CommandResult::kNoAck);
  EXPECT_EQ(outcomes[0].reason, "the camera's status did not count the command");
  EXPECT_EQ(commands.pending(), 0U);
}

TEST(CommandModel, ARecorderStatusWithAnErrorRejectsTheCommand) {
  CommandModel commands{StateOptions{}};
  commands.on_recorder_command_sent({1, 8, "studio", true, kT0});
  commands.on_recorder_status("studio", RecorderRecord{});  // not recording yet: still waiting
  EXPECT_EQ(commands.pending(), 1U);
  commands.on_recorder_status("studio", RecorderRecord{true, "", 0, 0, 0, 0, "disk full", {}});
  const auto outcomes = commands.take_outcomes(kT0);
  ASSERT_EQ(outcomes.size(), 1U);
  EXPECT_EQ(outcomes[0].result, CommandResult::kRejected);
  EXPECT_EQ(outcomes[0].reason, "disk full");
}

// Listener threads write every model while the server thread takes snapshots; run under
// ThreadSanitizer (docs/console.md, "Tests") this shows the locks cover every model.
TEST(ConsoleState, WritersOfEveryModelAndSnapshotsRunTogether) {
  ConsoleState state;
  std::atomic<bool> stop{false};
  // Per writer: under a parallel build a writer thread may not run at all in the few milliseconds
  // the others need (once the tracks and recorder writers had not started when the loop ended).
  std::array<std::atomic<int>, 4> writes{};
  std::size_t next_writer = 0;
  const auto writer = [&](auto write) {
    std::atomic<int>& count = writes.at(next_writer++);
    return std::thread([&stop, &count, write] {
      for (TimeNs i = 1; !stop; ++i) {
        write(kT0 + i * kMs);
        ++count;
      }
    });
  };
  const auto fewest_writes = [&] {
    int fewest = writes[0];
    for (const auto& count : writes) fewest = std::min(fewest, count.load());
    return fewest;
  };
  std::vector<std::thread> writers;
  writers.push_back(writer([&](TimeNs now) { state.on_features("cam0", {1, now, {{1, 2, 3}}}, now); }));
  writers.push_back(writer([&](TimeNs now) {
    state.on_status("cam0", {}, now);
    state.on_command_sent({1, 1, "cam0", "set_gain", 0, 0, now});
  }));
  writers.push_back(writer([&](TimeNs now) {
    state.on_tracks({track(1, TrackStatus::kConfirmed)}, now);
    state.on_estimator({}, now);
  }));
  writers.push_back(writer([&](TimeNs now) {
    state.on_recorder_status("studio", {}, now);
    state.add_coverage_frame("cam0", {{1, 1, 1}});
  }));
  // Snapshots while the writers write (at least 200 snapshots and 200 writes of each writer,
  // bounded in time).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  int snapshots = 0;
  while ((snapshots < 200 || fewest_writes() < 200) && std::chrono::steady_clock::now() < deadline) {
    const json full = state.snapshot(kT0, snapshots % 2 == 0);
    EXPECT_LE(full["cameras"].size(), 1U);
    state.take_outcomes(kT0);
    ++snapshots;
  }
  stop = true;
  for (std::thread& thread : writers) thread.join();
  EXPECT_GE(fewest_writes(), 200);
  const json last = state.snapshot(kT0, true);
  EXPECT_EQ(last["cameras"].size(), 1U);
  EXPECT_EQ(last["tracks"].size(), 1U);
  EXPECT_EQ(last["recorders"].size(), 1U);
  EXPECT_EQ(last["calibration"]["cameras"].size(), 1U);
}

}  // namespace
}  // namespace panoptes::console
