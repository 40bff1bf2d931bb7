// SPDX-License-Identifier: Apache-2.0
// `type: chain` entries of the bodies file (issue 21, docs/articulated.md).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "panoptes/calibration_file.h"
#include "panoptes/errors.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

constexpr const char* kBodiesWithChain =
    "bodies:\n"
    "  - name: wand\n"
    "    markers: [[0, 0, 0], [0.1, 0, 0], [0, 0.05, 0]]\n"
    "  - name: index\n"
    "    type: chain\n"
    "    links: [0.025, 0.030, 0.045]\n"
    "    joint_limits: [[-0.2, 1.7], [-0.3, 1.8]]\n"
    "    base: last\n"
    "    tip_offset: [0.012, 0.004, 0]\n";

TEST(ChainFile, ChainsBesideBodies) {
  testing::TempDir dir;
  const auto path = dir.write("bodies.yaml", kBodiesWithChain);
  const std::vector<BodyDefinition> bodies = load_bodies(path);
  ASSERT_EQ(bodies.size(), 1U);
  EXPECT_EQ(bodies[0].name, "wand");
  const std::vector<ChainDefinition> chains = load_chains(path);
  ASSERT_EQ(chains.size(), 1U);
  EXPECT_EQ(chains[0].name, "index");
  // `base: last`: stored base first.
  EXPECT_EQ(chains[0].link_lengths_m, (std::vector<double>{0.045, 0.030, 0.025}));
  ASSERT_EQ(chains[0].joint_limits.size(), 2U);
  EXPECT_EQ(chains[0].joint_limits[0].min_rad, -0.3);
  EXPECT_EQ(chains[0].joint_limits[1].max_rad, 1.7);
  EXPECT_EQ(chains[0].tip_offset_m, Eigen::Vector3d(0.012, 0.004, 0));
}

std::string load_error(const testing::TempDir& dir, const std::string& chain_lines) {
  const auto path = dir.write("bodies.yaml", "bodies:\n  - name: index\n    type: chain\n" + chain_lines);
  try {
    load_chains(path);
  } catch (const ConfigError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind(path.string() + ": bodies[0].", 0), 0U) << message;
    return message.substr(path.string().size() + 2);
  }
  return "no error";
}

TEST(ChainFile, ImpossibleChainsNameFileAndEntry) {
  testing::TempDir dir;
  EXPECT_EQ(load_error(dir, "    links: [0.04, -0.03, 0.02]\n    joint_limits: [[0, 1], [0, 1]]\n"),
            "bodies[0].links: chain 'index': links[1]: a link length must lie in [0.005000, 0.500000] m; got "
            "-0.030000");
  EXPECT_EQ(
      load_error(dir, "    links: [0.04, 0.03, 0.02]\n    joint_limits: [[0, 1], [1.5, 1]]\n"),
      "bodies[0].joint_limits: chain 'index': joint_limits[1]: expected min < max within ±2.97 rad; got "
      "[1.500000, 1.000000]");
  EXPECT_NE(load_error(dir, "    links: [0.04, 0.03, 0.02]\n    joint_limits: [[0, 1]]\n")
                .find("expected 2 [min, max]"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "    links: [0.04]\n    joint_limits: []\n").find("3 to 5 markers"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "    links: [0.04, 0.03]\n    joint_limits: [[0, 1]]\n    base: middle\n")
                .find("bodies[0].base"),
            std::string::npos);
  EXPECT_NE(load_error(dir, "    links: [0.04, 0.03]\n    joint_limits: [[0, 1]]\n    markers: []\n")
                .find("markers"),
            std::string::npos);
}

}  // namespace
}  // namespace panoptes
