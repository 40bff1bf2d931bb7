// SPDX-License-Identifier: Apache-2.0
// panoptes_ctl's library (tools/ctl): reading scripts, their pause lines, and the status line.
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "panoptes/ctl_actions/ctl_actions.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::ctl {
namespace {

using Words = std::vector<std::string>;

TEST(CtlScript, LinesKeepTheirNumberingAndDropComments) {
  std::istringstream script("cam0 set_exposure 500\n\n# a comment\n  *   restart  # every camera\nsleep 0.5");
  const std::vector<Words> lines = read_script_lines(script);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0], (Words{"cam0", "set_exposure", "500"}));
  EXPECT_TRUE(lines[1].empty());
  EXPECT_TRUE(lines[2].empty());
  EXPECT_EQ(lines[3], (Words{"*", "restart"}));
  EXPECT_EQ(lines[4], (Words{"sleep", "0.5"}));
}

TEST(CtlScript, PausesParsed) {
  EXPECT_TRUE(is_pause({"sleep", "1"}));
  EXPECT_TRUE(is_pause({"wait_nodes"}));
  EXPECT_FALSE(is_pause({"cam0", "sleep"}));
  EXPECT_FALSE(is_pause({}));

  const auto sleep = parse_pause({"sleep", "0.25"});
  ASSERT_TRUE(sleep);
  EXPECT_FALSE(sleep->wait_nodes);
  EXPECT_DOUBLE_EQ(sleep->seconds, 0.25);

  const auto wait = parse_pause({"wait_nodes", "3", "10"});
  ASSERT_TRUE(wait);
  EXPECT_TRUE(wait->wait_nodes);
  EXPECT_EQ(wait->nodes, 3);
  EXPECT_DOUBLE_EQ(wait->seconds, 10.0);
}

TEST(CtlScript, MalformedPausesRefused) {
  for (const Words& words :
       {Words{"sleep"}, Words{"sleep", "x"}, Words{"sleep", "-1"}, Words{"sleep", "1", "2"},
        Words{"wait_nodes", "2"}, Words{"wait_nodes", "0", "5"}, Words{"wait_nodes", "a", "5"},
        Words{"wait_nodes", "2", "nan"}, Words{"cam0", "restart"}})
    EXPECT_FALSE(parse_pause(words)) << words.size() << " words from '" << words[0] << "'";
  EXPECT_EQ(pause_usage({"sleep", "x"}), "sleep <seconds>");
  EXPECT_EQ(pause_usage({"wait_nodes"}), "wait_nodes <nodes >= 1> <seconds>");
}

TEST(CtlStatus, JsonCarriesEveryFieldAndCounter) {
  msg::CameraStatus status;
  status.camera_id("cam2");
  status.stamp_ns(123456789);
  status.fps(99.5);
  status.frames(4000);
  status.drops_queue(2);
  status.threshold(40);
  status.last_error("none");
  msg::Counter counter;
  counter.name("spots_rejected");
  counter.value(17);
  status.counters({counter});
  const nlohmann::json json = status_json(status);
  EXPECT_EQ(json.at("camera_id"), "cam2");
  EXPECT_EQ(json.at("stamp_ns"), 123456789);
  EXPECT_DOUBLE_EQ(json.at("fps").get<double>(), 99.5);
  EXPECT_EQ(json.at("frames"), 4000);
  EXPECT_EQ(json.at("drops_queue"), 2);
  EXPECT_EQ(json.at("last_error"), "none");
  EXPECT_EQ(json.at("counters").at("spots_rejected"), 17);
  // Every field of the message, plus the counters.
  EXPECT_EQ(json.size(), 16u);
  EXPECT_TRUE(json.contains("clock_drift_ppm"));
}

}  // namespace
}  // namespace panoptes::ctl
