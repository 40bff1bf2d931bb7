// SPDX-License-Identifier: Apache-2.0
// Scene `chains:` (issue 21, docs/simulator.md): the hand scene's finger follows the chain model
// with its scripted grab/release bends, its markers are scene markers, and bad entries name the key.
#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/config.h"
#include "panoptes/simulator.h"

namespace panoptes {
namespace {

namespace fs = std::filesystem;

const fs::path kHandScene = fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "scenes" / "hand.yaml";

// Signed angle from link a to link b about the chain's bend axis `axis`.
double bend_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& axis) {
  return std::atan2(a.cross(b).dot(axis), a.dot(b));
}

TEST(ChainScene, HandFingerFollowsTheChainModelAndTheScript) {
  const Scene scene = Scene::load(kHandScene);
  const double links[] = {0.045, 0.030, 0.025};
  double peak_rate = 0.0;
  double previous_angle = 0.15;
  bool closed_seen = false;
  for (TimeNs t = 0; t <= 6 * kNsPerSecond; t += 5 * kNsPerMillisecond) {
    const auto chains = scene.chains_at(t);
    ASSERT_EQ(chains.size(), 1U);
    const ChainTruth& finger = chains[0];
    ASSERT_EQ(finger.markers.size(), 4U);
    ASSERT_EQ(finger.angles.size(), 2U);
    EXPECT_NEAR(finger.angles[0], finger.angles[1], 1e-12);  // both joints follow the same script
    EXPECT_GE(finger.angles[0], 0.15 - 1e-12);
    EXPECT_LE(finger.angles[0], 1.35 + 1e-12);
    closed_seen = closed_seen || std::abs(finger.angles[0] - 1.35) < 1e-9;
    const Eigen::Vector3d axis = finger.T_world_base.q * Eigen::Vector3d::UnitZ();
    EXPECT_TRUE(finger.markers[0].isApprox(finger.T_world_base.t, 1e-12));
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR((finger.markers[k + 1] - finger.markers[k]).norm(), links[k], 1e-12);
    for (int j = 0; j < 2; ++j) {
      EXPECT_NEAR(bend_between(finger.markers[j + 1] - finger.markers[j],
                               finger.markers[j + 2] - finger.markers[j + 1], axis),
                  finger.angles[j], 1e-9);
      EXPECT_NEAR((finger.markers[j + 1] - finger.markers[j]).dot(axis), 0.0, 1e-12);  // planar
    }
    // The tip: 12 mm beyond the last marker along the last link.
    const Eigen::Vector3d last_link = (finger.markers[3] - finger.markers[2]).normalized();
    EXPECT_TRUE(finger.tip.isApprox(finger.markers[3] + 0.012 * last_link, 1e-12));
    // The same markers are scene markers named index/<k>, after the two static ones.
    const auto markers = scene.markers_at(t);
    ASSERT_EQ(markers.size(), 6U);
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(markers[2 + k].name, "index/" + std::to_string(k));
      EXPECT_TRUE(markers[2 + k].p.isApprox(finger.markers[k], 1e-12));
    }
    if (t > 0) peak_rate = std::max(peak_rate, std::abs(finger.angles[0] - previous_angle) / 0.005);
    previous_angle = finger.angles[0];
  }
  EXPECT_TRUE(closed_seen);
  EXPECT_GT(peak_rate, 2.8);  // 1.2 rad over a 0.63 s raised cosine: π/2 · 1.2 / 0.63 ≈ 2.99 rad/s
  EXPECT_LE(peak_rate, 3.0);
}

std::string chain_scene(const std::string& chain_lines) {
  return "cameras:\n"
         "  - {id: c0, width: 640, height: 480, K: [600, 600, 319.5, 239.5],\n"
         "     look_at: {eye: [0, -2, 1], target: [0, 0, 1]}}\n"
         "chains:\n  - name: index\n    path: {type: static, position: [0, 0, 1]}\n" +
         chain_lines;
}

TEST(ChainScene, BadEntriesNameTheKey) {
  const auto error_of = [](const std::string& yaml) -> std::string {
    try {
      Scene::from_yaml_string(yaml, ".", "hand.yaml");
    } catch (const ConfigError& error) {
      return error.what();
    }
    return "no error";
  };
  const std::string bend = "    bend: {open: [0.1, 0.1], closed: [1.2, 1.2]}\n";
  const std::string good = "    links: [0.045, 0.03, 0.025]\n    joint_limits: [[-0.3, 1.8], [-0.3, 1.8]]\n";
  EXPECT_EQ(error_of(chain_scene(good + bend)), "no error");
  const std::string short_link = error_of(
      chain_scene("    links: [0.045, 0.001, 0.025]\n    joint_limits: [[-0.3, 1.8], [-0.3, 1.8]]\n" + bend));
  EXPECT_NE(short_link.find("chains[0].links"), std::string::npos) << short_link;
  EXPECT_NE(short_link.find("chain 'index'"), std::string::npos) << short_link;
  const std::string wrong_count =
      error_of(chain_scene(good + "    bend: {open: [0.1], closed: [1.2, 1.2]}\n"));
  EXPECT_NE(wrong_count.find("chains[0].bend.open"), std::string::npos) << wrong_count;
  const std::string typo =
      error_of(chain_scene(good + "    bend: {open: [0.1, 0.1], closed: [1.2, 1.2], hold: 1}\n"));
  EXPECT_NE(typo.find("hold"), std::string::npos) << typo;
}

}  // namespace
}  // namespace panoptes
