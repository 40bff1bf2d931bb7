// SPDX-License-Identifier: Apache-2.0
// PTZ guidance (docs/ptz.md): geometry, the simulated head's limits, prediction against latency,
// and the model file's errors.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "panoptes/errors.h"
#include "panoptes/ptz/ptz.h"
#include "panoptes/ptz/ptz_file.h"

namespace panoptes::ptz {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr TimeNs kMs = 1'000'000;

PtzModel side_camera() {
  PtzModel model;
  model.position = {0.0, -5.0, 1.6};
  model.base_yaw_rad = 90.0 * kDeg;
  model.pan = {-170 * kDeg, 170 * kDeg, 60 * kDeg, 120 * kDeg};
  model.tilt = {-30 * kDeg, 60 * kDeg, 60 * kDeg, 120 * kDeg};
  model.command_latency_s = 0.1;
  return model;
}

TEST(Ptz, AimedPointIsAtTheImageCentreAndAxesAreRightAndDown) {
  const PtzModel model = side_camera();
  const Eigen::Vector3d target(1.0, 0.5, 1.9);
  PtzPose pose = aim_at(model, target);
  pose.fov = 10 * kDeg;
  const auto centre = image_point(model, pose, target);
  ASSERT_TRUE(centre);
  EXPECT_NEAR(centre->x(), 960.0, 1e-9);
  EXPECT_NEAR(centre->y(), 540.0, 1e-9);
  // Looking along +y: world +x is to the right in the image, world +z up (smaller y).
  const auto right = image_point(model, pose, target + Eigen::Vector3d(0.1, 0, 0));
  const auto up = image_point(model, pose, target + Eigen::Vector3d(0, 0, 0.1));
  ASSERT_TRUE(right && up);
  EXPECT_GT(right->x(), 960.0);
  EXPECT_LT(up->y(), 540.0);
  // The horizontal field of view spans the image width.
  const double half_width_m = 0.5 * (target - model.position).norm() * 2.0 * std::tan(5 * kDeg) / 2.0;
  const Eigen::Vector3d heading = (target - model.position).normalized();
  const Eigen::Vector3d side = Eigen::Vector3d(heading.y(), -heading.x(), 0).normalized();  // image right
  const auto edge = image_point(model, pose, target + side * 2.0 * half_width_m);
  ASSERT_TRUE(edge);
  EXPECT_NEAR(edge->x(), 1920.0, 5.0);
  EXPECT_FALSE(image_point(model, pose, model.position - (target - model.position)));  // behind
}

TEST(Ptz, HeadObeysSpeedAccelerationLatencyAndLimits) {
  const PtzModel model = side_camera();
  PtzSimulator head(model, PtzPose{0.0, 0.0, 0.5}, 0);
  PtzCommand command;
  command.issued_ns = 0;
  command.pan = 90 * kDeg;
  command.fov = 0.5;
  head.send(command);
  head.advance_to(99 * kMs);
  EXPECT_EQ(head.pose().pan, 0.0);  // the command has not arrived
  double previous_rate = 0.0, top_speed = 0.0;
  for (TimeNs t = 100 * kMs; t <= 3000 * kMs; t += kMs) {
    head.advance_to(t);
    EXPECT_LE(std::abs(head.pan_rate() - previous_rate), 120 * kDeg * 1e-3 + 1e-12);
    top_speed = std::max(top_speed, std::abs(head.pan_rate()));
    previous_rate = head.pan_rate();
  }
  EXPECT_LE(top_speed, 60 * kDeg + 1e-12);
  EXPECT_GT(top_speed, 59 * kDeg);                // a 90° move reaches full speed
  EXPECT_NEAR(head.pose().pan, 90 * kDeg, 1e-3);  // and stops on the target without overshoot
  // A target beyond the limit: the head stops at the limit.
  command.issued_ns = 3000 * kMs;
  command.pan = 179 * kDeg;
  head.send(command);
  head.advance_to(8000 * kMs);
  EXPECT_NEAR(head.pose().pan, 170 * kDeg, 1e-9);
}

// A target walking past at 1.5 m/s, 5 m away, seen with 100 ms of command latency: with
// prediction the head keeps it near the centre, without it lags by ~latency x speed.
TEST(Ptz, PredictionCompensatesTheCommandLatency) {
  const PtzModel model = side_camera();
  const auto truth = [](TimeNs t) { return Eigen::Vector3d(-2.0 + 1.5 * ns_to_seconds(t), 0.0, 1.7); };
  const Eigen::Vector3d velocity(1.5, 0.0, 0.0);
  double error_with = 0, error_without = 0;
  for (const bool predict : {true, false}) {
    GuideOptions guide;
    guide.predict = predict;
    PtzPose start = aim_at(model, truth(0));
    start.fov = 6 * kDeg;
    PtzSimulator head(model, start, 0);
    double worst = 0;
    for (TimeNs t = 0; t <= 2500 * kMs; t += kMs) {
      if (t % (33 * kMs) == 0)
        head.send(guide_command(model, guide, t, t - 2 * kMs, truth(t - 2 * kMs), velocity));
      head.advance_to(t);
      if (t < 500 * kMs) continue;
      const auto pixel = image_point(model, head.pose(), truth(t));
      ASSERT_TRUE(pixel);
      worst = std::max(worst, std::abs(pixel->x() - 960.0));
    }
    (predict ? error_with : error_without) = worst;
  }
  EXPECT_LT(error_with, 20.0);      // pixels of 1920
  EXPECT_GT(error_without, 200.0);  // 0.15 m of lag at 5 m in a ~0.5 m view
}

TEST(Ptz, ModelFileErrorsNameTheKey) {
  const auto dir = std::filesystem::temp_directory_path() / "panoptes_ptz_test";
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& text) {
    std::ofstream(dir / "ptz.yaml") << text;
    return dir / "ptz.yaml";
  };
  const PtzModel good =
      load_ptz_model(write("ptz:\n  position: [0, -5, 1.6]\n  base_yaw_deg: 90\n  pan: {max_speed_dps: 60}\n "
                           " command_latency_ms: 100\n"));
  EXPECT_NEAR(good.base_yaw_rad, 90 * kDeg, 1e-12);
  EXPECT_NEAR(good.pan.max_speed_radps, 60 * kDeg, 1e-12);
  EXPECT_NEAR(good.command_latency_s, 0.1, 1e-12);
  const auto message = [&](const std::string& text) {
    try {
      load_ptz_model(write(text));
    } catch (const ConfigError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("ptz:\n  position: [0, 0, 1]\n  pan: {min_deg: 10, max_deg: -10}\n").find("pan"),
            std::string::npos);
  EXPECT_NE(message("ptz:\n  position: [0, 0, 1]\n  tilt: {max_speed_dps: 0}\n").find("max_speed"),
            std::string::npos);
  EXPECT_NE(message("ptz:\n  position: [0, 0, 1]\n  zoom: {fov_min_deg: 30, fov_max_deg: 10}\n").find("zoom"),
            std::string::npos);
  EXPECT_NE(message("ptz:\n  position: [0, 0]\n").find("position"), std::string::npos);
  EXPECT_NE(message("ptz:\n  position: [0, 0, 1]\n  speed: 3\n").find("speed"), std::string::npos);
  EXPECT_NE(message("ptz:\n  position: [0, 0, 1]\n  command_latency_ms: -5\n").find("command_latency"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Ptz, CommandLinesRoundTripAndBadOnesAreRefused) {
  PtzCommand command;
  command.issued_ns = 1'700'000'000'123'456'789;
  command.pan = 0.25;
  command.tilt = -0.125;
  command.pan_rate = 0.5;
  command.tilt_rate = 0.0625;
  command.fov = 0.1;
  std::string error;
  const auto back = command_from_json(command_to_json(command), error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->issued_ns, command.issued_ns);
  EXPECT_EQ(back->pan, command.pan);
  EXPECT_EQ(back->fov, command.fov);
  EXPECT_FALSE(command_from_json("{\"issued_ns\": 1, \"pan\": 0}", error));
  EXPECT_NE(error.find("tilt"), std::string::npos);
  EXPECT_FALSE(command_from_json("not json", error));
  EXPECT_FALSE(command_from_json("{\"issued_ns\": 1.5}", error));
}

}  // namespace
}  // namespace panoptes::ptz
