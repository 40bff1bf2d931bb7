// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "panoptes/console/command_gate.h"

namespace panoptes::console {
namespace {

using nlohmann::json;
const std::optional<std::pair<int, int>> kVga = std::make_pair(640, 480);

Rejection rejected(const json& message, bool known = true) {
  const GateResult result = check_command(message, known, kVga);
  EXPECT_TRUE(std::holds_alternative<Rejection>(result)) << message.dump();
  return std::holds_alternative<Rejection>(result) ? std::get<Rejection>(result) : Rejection{};
}

CameraCommandRequest accepted(const json& message) {
  const GateResult result = check_command(message, true, kVga);
  EXPECT_TRUE(std::holds_alternative<CameraCommandRequest>(result))
      << message.dump() << ": "
      << (std::holds_alternative<Rejection>(result) ? std::get<Rejection>(result).reason : "");
  return std::holds_alternative<CameraCommandRequest>(result) ? std::get<CameraCommandRequest>(result)
                                                              : CameraCommandRequest{};
}

TEST(CommandGate, ForwardsValidCommandsWithCanonicalArguments) {
  const auto threshold =
      accepted({{"id", 7}, {"camera", "cam0"}, {"command", "set_threshold"}, {"args", {"255"}}});
  EXPECT_EQ(threshold.request, 7);
  EXPECT_EQ(threshold.camera, "cam0");
  EXPECT_EQ(threshold.arguments, std::vector<std::string>({"255"}));
  EXPECT_EQ(accepted({{"camera", "cam0"}, {"command", "set_exposure"}, {"args", {1500.5}}}).arguments,
            std::vector<std::string>({"1500.5"}));
  EXPECT_EQ(
      accepted({{"camera", "cam0"}, {"command", "add_mask"}, {"args", {"rect", 0, 0, 320.4, 480}}}).arguments,
      std::vector<std::string>({"rect", "0", "0", "320", "480"}));
  EXPECT_TRUE(accepted({{"camera", "cam0"}, {"command", "clear_masks"}}).arguments.empty());
  EXPECT_EQ(accepted({{"camera", "cam0"}, {"command", "add_mask"}, {"args", {"poly", 0, 0, 10, 0, 5, 9}}})
                .arguments.size(),
            7u);
  EXPECT_EQ(accepted({{"camera", "cam0"}, {"command", "preview"}, {"args", {640}}}).arguments,
            std::vector<std::string>({"640"}));
  EXPECT_TRUE(accepted({{"camera", "cam0"}, {"command", "preview"}}).arguments.empty());
}

TEST(CommandGate, RejectsWithAReasonAndACounter) {
  EXPECT_EQ(rejected({{"camera", "cam0"}}).counter, "bad_message");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "set_threshold"}, {"args", "12"}}).counter,
            "bad_message");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "format_disk"}}).counter, "unknown_command");
  EXPECT_EQ(rejected({{"camera", "cam9"}, {"command", "restart"}}, false).counter, "unknown_camera");
  const Rejection range = rejected({{"camera", "cam0"}, {"command", "set_threshold"}, {"args", {70000}}});
  EXPECT_EQ(range.counter, "out_of_range");
  EXPECT_NE(range.reason.find("70000"), std::string::npos) << range.reason;
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "set_threshold"}, {"args", {12.5}}}).counter,
            "bad_arguments");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "set_threshold"}, {"args", {"12; rm"}}}).counter,
            "bad_arguments");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "set_threshold"}}).counter, "bad_arguments");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "set_gain"}, {"args", {-1}}}).counter, "out_of_range");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "restart"}, {"args", {1}}}).counter, "bad_arguments");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "preview"}, {"args", {100000}}}).counter,
            "out_of_range");
  EXPECT_EQ(
      rejected({{"camera", "cam0"}, {"command", "add_mask"}, {"args", {"rect", 600, 400, 100, 100}}}).counter,
      "out_of_range");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "add_mask"}, {"args", {"circle", 1, 2}}}).counter,
            "bad_arguments");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "add_mask"}, {"args", {"poly", 0, 0, 1, 1}}}).counter,
            "bad_arguments");
  EXPECT_EQ(rejected({{"camera", "cam0"}, {"command", "set_exposure"}, {"args", {"nan"}}}).counter,
            "bad_arguments");
}

TEST(RecorderGate, ForwardsStartAndStopWithABareFileName) {
  const json start = {
      {"type", "recorder"}, {"id", 9}, {"recorder", "studio"}, {"command", "start"}, {"name", "take_1.mcap"}};
  const auto accepted = check_recorder_command(start, true);
  ASSERT_TRUE(std::holds_alternative<RecorderCommandRequest>(accepted));
  EXPECT_EQ(std::get<RecorderCommandRequest>(accepted).path, "take_1.mcap");
  EXPECT_EQ(std::get<RecorderCommandRequest>(accepted).request, 9);
  const auto stop =
      check_recorder_command({{"recorder", "studio"}, {"command", "stop"}, {"name", "x"}}, true);
  ASSERT_TRUE(std::holds_alternative<RecorderCommandRequest>(stop));
  EXPECT_TRUE(std::get<RecorderCommandRequest>(stop).path.empty());  // stop takes no name
  const auto counter_of = [](const json& message, bool known = true) {
    const auto result = check_recorder_command(message, known);
    return std::holds_alternative<Rejection>(result) ? std::get<Rejection>(result).counter
                                                     : std::string("accepted");
  };
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "start"}, {"name", "../etc/x.mcap"}}),
            "bad_arguments");
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "start"}, {"name", "/tmp/x.mcap"}}),
            "bad_arguments");
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "start"}, {"name", "take.txt"}}),
            "bad_arguments");
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "start"}, {"name", ".mcap"}}), "bad_arguments");
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "quit"}}), "unknown_command");
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "start"}}, false), "unknown_recorder");
  EXPECT_EQ(counter_of({{"recorder", 5}, {"command", "start"}}), "bad_message");
  EXPECT_EQ(counter_of({{"recorder", "studio"}, {"command", "start"}, {"name", 3}}), "bad_message");
}

TEST(BodyGate, ForwardsANameTracksAndAPivot) {
  const BodyGateResult result =
      check_body_request({{"id", 4}, {"name", "wand_2"}, {"tracks", {12, 15, 19, 23}}, {"pivot", 15}});
  ASSERT_TRUE(std::holds_alternative<BodyCreateRequest>(result));
  const auto& body = std::get<BodyCreateRequest>(result);
  EXPECT_EQ(body.request, 4);
  EXPECT_EQ(body.name, "wand_2");
  EXPECT_EQ(body.tracks, std::vector<std::int64_t>({12, 15, 19, 23}));
  EXPECT_EQ(body.pivot, std::optional<std::int64_t>(15));
  const BodyGateResult centroid =
      check_body_request({{"name", "a.b-c"}, {"tracks", {1, 2, 3}}, {"pivot", nullptr}});
  ASSERT_TRUE(std::holds_alternative<BodyCreateRequest>(centroid));
  EXPECT_FALSE(std::get<BodyCreateRequest>(centroid).pivot);
}

TEST(BodyGate, RejectsBadNamesTooFewTracksAndBadIds) {
  const auto reason = [](const json& message) {
    const BodyGateResult result = check_body_request(message);
    EXPECT_TRUE(std::holds_alternative<Rejection>(result)) << message.dump();
    return std::holds_alternative<Rejection>(result) ? std::get<Rejection>(result) : Rejection{};
  };
  EXPECT_EQ(reason({{"tracks", {1, 2, 3}}}).counter, "bad_message");
  EXPECT_EQ(reason({{"name", ""}, {"tracks", {1, 2, 3}}}).counter, "bad_arguments");
  EXPECT_EQ(reason({{"name", "a/../b"}, {"tracks", {1, 2, 3}}}).counter, "bad_arguments");
  EXPECT_EQ(reason({{"name", std::string(65, 'a')}, {"tracks", {1, 2, 3}}}).counter, "bad_arguments");
  EXPECT_EQ(reason({{"name", "x"}, {"tracks", 3}}).counter, "bad_message");
  const Rejection two = reason({{"id", 9}, {"name", "x"}, {"tracks", {1, 2}}});
  EXPECT_EQ(two.request, 9);
  EXPECT_EQ(two.counter, "bad_arguments");
  EXPECT_NE(two.reason.find("3 to 64 markers, got 2"), std::string::npos) << two.reason;
  EXPECT_EQ(reason({{"name", "x"}, {"tracks", json::array({1, 2, "3"})}}).counter, "bad_arguments");
  EXPECT_EQ(reason({{"name", "x"}, {"tracks", {1, 2, -3}}}).counter, "bad_arguments");
  EXPECT_EQ(reason({{"name", "x"}, {"tracks", {1, 2, 3}}, {"pivot", "2"}}).counter, "bad_arguments");
  EXPECT_EQ(reason({{"name", "x"}, {"tracks", std::vector<int>(65, 1)}}).counter, "bad_arguments");
}

// Accepting or reverting a version of the estimator's calibration file (docs/console.md, "Versions
// of the calibration").
TEST(CalibrationGate, ForwardsAcceptAndRevertWithAVersion) {
  const CalibrationGateResult revert =
      check_calibration_request({{"id", 7}, {"action", "revert"}, {"version", 3}});
  ASSERT_TRUE(std::holds_alternative<CalibrationRequest>(revert));
  EXPECT_EQ(std::get<CalibrationRequest>(revert).request, 7);
  EXPECT_EQ(std::get<CalibrationRequest>(revert).action, "revert");
  EXPECT_EQ(std::get<CalibrationRequest>(revert).version, 3);
  const CalibrationGateResult accept = check_calibration_request({{"action", "accept"}, {"version", 1}});
  ASSERT_TRUE(std::holds_alternative<CalibrationRequest>(accept));
  EXPECT_EQ(std::get<CalibrationRequest>(accept).version, 1);
  const auto counter = [](const json& message) {
    const CalibrationGateResult result = check_calibration_request(message);
    EXPECT_TRUE(std::holds_alternative<Rejection>(result)) << message.dump();
    return std::holds_alternative<Rejection>(result) ? std::get<Rejection>(result).counter : "";
  };
  EXPECT_EQ(counter({{"action", "revert"}}), "bad_arguments");
  EXPECT_EQ(counter({{"action", "revert"}, {"version", "3"}}), "bad_arguments");
  EXPECT_EQ(counter({{"action", "revert"}, {"version", 2.5}}), "bad_arguments");
  EXPECT_EQ(counter({{"action", "accept"}, {"version", 0}}), "out_of_range");
  EXPECT_EQ(counter({{"action", "accept"}, {"version", 1000001}}), "out_of_range");
  EXPECT_EQ(counter({{"action", "delete"}, {"version", 1}}), "unknown_command");
}

TEST(RateLimiter, AllowsTheBurstThenTheRate) {
  RateLimiter limiter(10, 20);
  const TimeNs start = 1'000'000'000;
  int allowed = 0;
  for (int i = 0; i < 40; ++i) allowed += limiter.allow(start) ? 1 : 0;
  EXPECT_EQ(allowed, 20);
  // One second later: ten more tokens.
  allowed = 0;
  for (int i = 0; i < 40; ++i) allowed += limiter.allow(start + kNsPerSecond) ? 1 : 0;
  EXPECT_EQ(allowed, 10);
}

}  // namespace
}  // namespace panoptes::console
