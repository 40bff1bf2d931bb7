// SPDX-License-Identifier: Apache-2.0
// Continuous calibration (issue 36 items 1 and 2, docs/continuous_calibration.md): the residual
// statistics and their test, and on the seeded walk8 scene (eight cameras, clutter, merging,
// self-occlusion) a camera bumped by 0.5° and 5 mm at t = 10 s is quarantined within 2 s with the
// marker RMSE at most 1.2 times its value before, while unbumped runs raise no alarm.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>

#include <Eigen/Geometry>

#include "panoptes/errors.h"
#include "panoptes/estimator/calibration_health.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/eval/evaluation.h"
#include "panoptes/simulator.h"
#include "walk8_scene.h"

namespace panoptes::estimator {
namespace {

constexpr TimeNs kEpoch = 1'700'000'000'000'000'000;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

TEST(CalibrationHealth, HotellingPValueMatchesTheFDistribution) {
  // n residuals with mean m and sample covariance C: T² = n mᵀ C⁻¹ m.
  const std::size_t n = 50;
  const Eigen::Vector2d mean(0.2, -0.1);
  const Eigen::Matrix2d covariance = Eigen::Vector2d(0.25, 0.16).asDiagonal();
  const Eigen::Vector2d sum = static_cast<double>(n) * mean;
  const Eigen::Matrix2d outer = (n - 1.0) * covariance + static_cast<double>(n) * mean * mean.transpose();
  const ResidualStats s = residual_stats(n, sum, outer, 0.0);
  EXPECT_NEAR(s.bias.x(), 0.2, 1e-12);
  const double t2 = 50.0 * (0.04 / 0.25 + 0.01 / 0.16);
  EXPECT_NEAR(s.t2, t2, 1e-9);
  EXPECT_NEAR(s.p_value, std::pow(1.0 + t2 / 49.0, -24.0), 1e-12);
  EXPECT_NEAR(s.spread_px, std::sqrt(0.41), 1e-9);
}

TEST(CalibrationHealth, FalseAlarmRateOfTheTestIsAsStated) {
  // Unbiased Gaussian residuals: P(p < α) = α. 20000 windows of 40 at α = 0.01.
  std::mt19937_64 random(36);
  std::normal_distribution<double> normal(0.0, 0.7);
  int rejected = 0;
  const int windows = 20000;
  for (int w = 0; w < windows; ++w) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
    for (int i = 0; i < 40; ++i) {
      const Eigen::Vector2d r(normal(random), normal(random));
      sum += r;
      outer += r * r.transpose();
    }
    if (residual_stats(40, sum, outer, 0.0).p_value < 0.01) ++rejected;
  }
  EXPECT_NEAR(static_cast<double>(rejected) / windows, 0.01, 0.002);
}

TEST(CalibrationHealth, MonitorQuarantinesABiasAndReleasesWhenItGoes) {
  CalibrationHealthOptions options;
  CalibrationMonitor monitor(options, 0.5);
  monitor.set_cameras({"c0"}, {Eigen::Vector2d(1280, 1024)});
  std::mt19937_64 random(7);
  std::normal_distribution<double> normal(0.0, 0.4);
  std::uniform_real_distribution<double> where(0.0, 1000.0);
  const auto feed = [&](TimeNs from, TimeNs to, Eigen::Vector2d bias) {
    std::int64_t id = 0;
    for (TimeNs t = from; t < to; t += 10'000'000) {
      for (int k = 0; k < 4; ++k)
        monitor.add(0, ++id, t, {where(random), where(random)},
                    bias + Eigen::Vector2d(normal(random), normal(random)));
      monitor.judge(0, t);
    }
  };
  feed(kEpoch, kEpoch + 2'000'000'000, Eigen::Vector2d::Zero());
  EXPECT_EQ(monitor.health(0).state, CalibrationState::kOk) << monitor.health(0).reason;
  feed(kEpoch + 2'000'000'000, kEpoch + 3'000'000'000, Eigen::Vector2d(3.0, -1.0));
  ASSERT_TRUE(monitor.quarantined(0));
  EXPECT_LT(monitor.health(0).quarantined_since_ns, kEpoch + 2'500'000'000);
  EXPECT_NE(monitor.health(0).reason.find("quarantined"), std::string::npos);
  // A correction that was not applied says why, once (the last reason replaces the one before).
  monitor.note_correction(0, "only 3 blobs could be paired with tracks");
  monitor.note_correction(0, "only 5 blobs could be paired with tracks");
  const std::string reason = monitor.health(0).reason;
  EXPECT_NE(reason.find("quarantined: "), std::string::npos) << reason;
  EXPECT_NE(reason.find("; not corrected: only 5 blobs"), std::string::npos) << reason;
  EXPECT_EQ(reason.find("only 3 blobs"), std::string::npos) << reason;
  feed(kEpoch + 3'000'000'000, kEpoch + 6'000'000'000, Eigen::Vector2d::Zero());
  EXPECT_FALSE(monitor.quarantined(0)) << monitor.health(0).reason;
  EXPECT_EQ(monitor.health(0).quarantines, 1u);
  EXPECT_EQ(monitor.health(0).releases, 1u);
}

// "Its blobs miss the tracks": few predictions with a blob in their gate quarantine a camera only
// when its own blobs are unexplained too. The ring of 4 in the planner validation predicted 105
// qualified tracks in one camera and saw 5 (the body hid them from it; they qualify because the
// other cameras see them), while 293 of its 340 blobs lay on tracks: no bump (issue 35).
TEST(CalibrationHealth, BlindCameraNeedsUnexplainedBlobs) {
  const auto run = [](std::size_t explained_of_ten) {
    CalibrationMonitor monitor(CalibrationHealthOptions{}, 0.5);
    monitor.set_cameras({"c0"}, {Eigen::Vector2d(1280, 1024)});
    std::int64_t id = 0;
    for (TimeNs t = kEpoch; t < kEpoch + 2'000'000'000; t += 10'000'000) {
      for (int k = 0; k < 4; ++k) {
        ++id;
        monitor.add_prediction(0, id, t, k == 0 && id % 40 == 1);
      }
      monitor.add_blobs(0, t, 10, explained_of_ten);
      monitor.judge(0, t);
    }
    return monitor.health(0);
  };
  const auto hidden = run(9);  // occluded: its blobs sit on the tracks it does see
  EXPECT_NE(hidden.state, CalibrationState::kQuarantined) << hidden.reason;
  EXPECT_GT(hidden.predicted, 100u);
  EXPECT_LT(hidden.seen * 20, hidden.predicted);
  const auto bumped = run(4);  // 4 of 10 near some track by chance (a 2 degree bump of walk8: 41 %)
  EXPECT_EQ(bumped.state, CalibrationState::kQuarantined);
  EXPECT_NE(bumped.reason.find("its blobs miss the tracks"), std::string::npos) << bumped.reason;
  EXPECT_NE(bumped.reason.find("blobs lay near a track"), std::string::npos) << bumped.reason;
}

TEST(CalibrationHealth, ModeIsParsed) {
  EXPECT_EQ(parse_calibration_mode("off"), CalibrationMode::kOff);
  EXPECT_EQ(parse_calibration_mode("detect"), CalibrationMode::kDetect);
  EXPECT_EQ(parse_calibration_mode("correct"), CalibrationMode::kCorrect);
  EXPECT_THROW(parse_calibration_mode("on"), ConfigError);
  TrackerOptions options;
  options.calibration.mode = "sometimes";
  EXPECT_THROW(Tracker{options}, ConfigError);
}

std::vector<FeatureFrame> frames_of(const Scene& scene) {
  std::vector<FeatureFrame> frames;
  for (const auto& camera : scene.cameras()) {
    const CameraSimulator simulator(scene, camera.calibration.id);
    for (std::int64_t k = 0; simulator.frame_time_ns(k) < scene.duration_ns(); ++k) {
      frames.push_back(simulator.features(k));
      frames.back().stamp_ns += kEpoch;
    }
  }
  std::stable_sort(frames.begin(), frames.end(),
                   [](const FeatureFrame& a, const FeatureFrame& b) { return a.stamp_ns < b.stamp_ns; });
  return frames;
}

struct BumpRun {
  double rmse_before_mm = 0;  // scene time 1-10 s
  double rmse_after_mm = 0;   // 10-end
  double rmse_last_mm = 0;    // the last 10 s (a 30-s scene: 10 s after the bump's 20 s of motion)
  double rmse_quarantined_mm =
      0;  // from the first quarantine to the end (the acceptance's "while quarantined")
  double coverage_after = 0;
  std::vector<CameraCalibrationHealth> health;
  std::uint64_t quarantines = 0;
  TimeNs first_quarantine_ns = 0;  // scene time; 0: none
  std::string first_camera;
  double process_s = 0;                               // time in Tracker::process
  std::vector<CalibrationCorrection> corrections;     // mode correct
  std::map<std::string, RigidTransform> final_poses;  // the tracker's camera poses at the end
};

double rmse_mm(const Scene& scene, const std::vector<TrackRecord>& records, double& coverage) {
  EvaluationOptions options;
  options.epoch_ns = kEpoch;
  const Evaluation evaluation = evaluate(scene, records, options);
  coverage = evaluation.trackable == 0
                 ? 0.0
                 : static_cast<double>(evaluation.tracked_trackable) / evaluation.trackable;
  return evaluation.rmse_m * 1e3;
}

// The scene's landmarks, as anchors for the tracker (mode correct).
std::vector<Eigen::Vector3d> anchors_of(const Scene& scene) {
  std::vector<Eigen::Vector3d> anchors;
  for (const auto& group : scene.landmarks())
    anchors.insert(anchors.end(), group.points.begin(), group.points.end());
  return anchors;
}

BumpRun track(const Scene& scene, const std::string& mode, TimeNs split_ns = 10 * kNsPerSecond,
              bool anchored = false) {
  TrackerOptions options;
  options.calibration.mode = mode;
  if (anchored) options.calibration.anchors = anchors_of(scene);
  Tracker tracker(options);
  tracker.set_calibration(scene.calibration());
  std::vector<TrackRecord> before;
  std::vector<TrackRecord> after;
  std::vector<TrackRecord> quarantined;
  std::vector<TrackRecord> last;
  BumpRun run;
  for (const auto& frame : frames_of(scene)) {
    const auto start = std::chrono::steady_clock::now();
    const FrameOutcome outcome = tracker.process(frame);
    run.process_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (outcome != FrameOutcome::kProcessed) continue;
    auto& records = frame.stamp_ns - kEpoch < split_ns ? before : after;
    for (const auto& record : tracker.current_tracks()) {
      records.push_back(record);
      if (run.first_quarantine_ns != 0) quarantined.push_back(record);
      if (frame.stamp_ns - kEpoch >= scene.duration_ns() - 10 * kNsPerSecond) last.push_back(record);
    }
    for (auto& correction : tracker.take_calibration_corrections()) {
      if (correction.kind == CalibrationCorrection::Kind::kDrift) {  // counted, not printed (hundreds)
        run.corrections.push_back(std::move(correction));
        continue;
      }
      std::printf(
          "%s %s at %.3f s: turned %.3f deg, moved %.1f mm (%zu pairs, %.3f px)\n",
          correction.camera_id.c_str(),
          correction.kind == CalibrationCorrection::Kind::kSettle ? "refined after its bump" : "corrected",
          ns_to_seconds(correction.stamp_ns - kEpoch), correction.result.rotation_change_deg,
          correction.result.translation_change_mm, correction.result.inliers, correction.result.rms_px);
      run.corrections.push_back(std::move(correction));
    }
    for (const auto& health : tracker.calibration_health()) {
      if (run.first_quarantine_ns == 0 && health.quarantines > 0) {
        run.first_quarantine_ns = health.quarantined_since_ns - kEpoch;
        run.first_camera = health.camera_id;
        std::printf("%s at %.3f s: %s\n", health.camera_id.c_str(), ns_to_seconds(run.first_quarantine_ns),
                    health.reason.c_str());
      }
    }
  }
  double coverage = 0;
  run.rmse_before_mm = rmse_mm(scene, before, coverage);
  if (!after.empty()) run.rmse_after_mm = rmse_mm(scene, after, run.coverage_after);
  if (!quarantined.empty()) run.rmse_quarantined_mm = rmse_mm(scene, quarantined, coverage);
  if (!last.empty()) run.rmse_last_mm = rmse_mm(scene, last, coverage);
  run.health = tracker.calibration_health();
  for (const auto& health : run.health) run.quarantines += health.quarantines;
  for (const auto& camera : scene.cameras())
    run.final_poses[camera.calibration.id] = tracker.camera_model(camera.calibration.id)->T_world_cam();
  return run;
}

// Six anchor markers on stands around walk8's walk (x from -1.75 to 1.75 m), in every camera's view.
std::string walk8_anchors() {
  return "landmarks:\n"
         "  - {name: a0, position: [2.6, 1.4, 0.4]}\n  - {name: a1, position: [-2.6, 1.4, 0.6]}\n"
         "  - {name: a2, position: [2.6, -1.4, 0.6]}\n  - {name: a3, position: [-2.6, -1.4, 0.4]}\n"
         "  - {name: a4, position: [0.0, 1.9, 1.4]}\n  - {name: a5, position: [0.0, -1.9, 1.6]}\n";
}

void print(const char* what, const BumpRun& run) {
  std::printf(
      "%s: RMSE before %.3f mm, after %.3f mm (coverage after %.3f), quarantines %llu, tracker %.3f s\n",
      what, run.rmse_before_mm, run.rmse_after_mm, run.coverage_after,
      static_cast<unsigned long long>(run.quarantines), run.process_s);
  for (const auto& h : run.health) {
    std::printf(
        "  %s seen %4zu/%4zu %-11s residuals %7llu window %4zu bias (%+.3f, %+.3f) spread %.3f p %.1e "
        "withheld %llu\n",
        h.camera_id.c_str(), h.seen, h.predicted, to_string(h.state),
        static_cast<unsigned long long>(h.residuals), h.whole.samples, h.whole.bias.x(), h.whole.bias.y(),
        h.whole.spread_px, h.whole.p_value, static_cast<unsigned long long>(h.blobs_withheld));
  }
}

// A turn of 0.5° about an axis in the image plane and across it, and 5 mm, in the camera frame.
RigidTransform bump_of(double degrees, double millimetres) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, 0.5).normalized();
  return {Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kDegree, axis)),
          millimetres * 1e-3 * Eigen::Vector3d(0.6, -0.8, 0.0)};
}

// One row of issue 36's bump table (docs/continuous_calibration.md, "Measurements"): a bump at 10 s
// tracked with the monitor (detect) and without it (off).
void print_table_row(const char* name, const BumpRun& detect, const BumpRun& off) {
  std::string quarantined;
  for (const auto& h : detect.health)
    if (h.quarantines > 0) quarantined += " " + h.camera_id;
  std::printf(
      "TABLE %-18s detection %s s, quarantined:%s | RMSE before %.3f mm, after: detect %.3f mm "
      "(x%.3f, coverage %.3f), off %.3f mm (x%.3f, coverage %.3f)\n",
      name,
      detect.first_quarantine_ns == 0
          ? "never"
          : std::to_string(ns_to_seconds(detect.first_quarantine_ns - 10 * kNsPerSecond)).c_str(),
      quarantined.empty() ? " none" : quarantined.c_str(), detect.rmse_before_mm, detect.rmse_after_mm,
      detect.rmse_after_mm / detect.rmse_before_mm, detect.coverage_after, off.rmse_after_mm,
      off.rmse_after_mm / off.rmse_before_mm, off.coverage_after);
}

TEST(CalibrationHealth, BumpedCameraIsQuarantinedWithinTwoSecondsAndTrackingHolds) {
  Scene scene = walk8_scene(20.0, 8);
  const BumpRun clean = track(scene, "detect");
  print("walk8 unbumped, detect", clean);
  EXPECT_EQ(clean.quarantines, 0u);
  scene.set_camera_bump(3, 10 * kNsPerSecond, bump_of(0.5, 5.0));
  const BumpRun off = track(scene, "off");
  print("walk8 cam3 bumped 0.5 deg 5 mm at 10 s, off", off);
  const BumpRun detect = track(scene, "detect");
  print("walk8 cam3 bumped 0.5 deg 5 mm at 10 s, detect", detect);
  ASSERT_GT(detect.quarantines, 0u);
  EXPECT_EQ(detect.first_camera, "cam3");
  EXPECT_GE(detect.first_quarantine_ns, 10 * kNsPerSecond);
  EXPECT_LE(detect.first_quarantine_ns, 12 * kNsPerSecond);
  EXPECT_EQ(detect.quarantines, 1u);
  // While quarantined the issue asks <= 1.2x: measured 1.07x (1.11x from the bump on) with the
  // default tracker; with issue 35's fast-motion settings 1.23x (docs/continuous_calibration.md).
  EXPECT_LE(detect.rmse_quarantined_mm, 1.2 * detect.rmse_before_mm);
  EXPECT_LE(detect.rmse_after_mm, 1.4 * detect.rmse_before_mm);
  std::printf("RMSE while quarantined %.3f mm (%.3fx the RMSE before the bump)\n", detect.rmse_quarantined_mm,
              detect.rmse_quarantined_mm / detect.rmse_before_mm);
  print_table_row("0.5 deg cam3", detect, off);  // the table's row (BumpTable has the others)
}

// Mode correct (issue 36 item 3): cam3 bumped by 2 degrees and 5 mm at 10 s is quarantined, its
// pose estimated again from the tracks the other seven determine, applied, and the camera brought
// back; the corrected pose is the bumped truth within 0.05 degrees and 5 mm.
TEST(CalibrationHealth, CorrectModeBringsABumpedCameraBack) {
  Scene scene = walk8_scene(20.0, 8);
  const CameraCalibration cam3 = scene.calibration().cameras.at(3);  // a copy: calibration() returns by value
  ASSERT_TRUE(cam3.T_world_cam.has_value());
  const RigidTransform bump = bump_of(2.0, 5.0);
  const RigidTransform truth = *cam3.T_world_cam * bump;  // the simulator's T_world_cam · bump
  scene.set_camera_bump(3, 10 * kNsPerSecond, bump);
  const BumpRun run = track(scene, "correct");
  print("walk8 cam3 bumped 2 deg 5 mm at 10 s, correct", run);
  ASSERT_FALSE(run.corrections.empty()) << "no correction applied";
  const CalibrationCorrection& c = run.corrections.front();
  EXPECT_EQ(c.camera_id, cam3.id);
  const double angle_deg = Eigen::AngleAxisd(c.after.q * truth.q.conjugate()).angle() * 180.0 / M_PI;
  const double moved_mm = 1e3 * (c.after.t - truth.t).norm();
  // The position error in the true camera's frame (x, y across the image, z along the axis).
  const Eigen::Vector3d error_cam = truth.q.conjugate() * (c.after.t - truth.t);
  std::printf(
      "corrected pose against the bumped truth: %.4f deg, %.2f mm (camera frame: %+.2f %+.2f %+.2f mm)\n",
      angle_deg, moved_mm, 1e3 * error_cam.x(), 1e3 * error_cam.y(), 1e3 * error_cam.z());
  EXPECT_LT(angle_deg, 0.05);
  EXPECT_LT(moved_mm, 5.0);
  const auto& health = run.health.at(3);
  EXPECT_GE(health.releases, 1U) << health.reason;
  EXPECT_NE(health.state, CalibrationState::kQuarantined) << health.reason;
  EXPECT_LE(run.rmse_after_mm, 1.2 * run.rmse_before_mm);
}

// The acceptance's single bump with anchor markers (six, walk8_anchors()): 0.5° and 5 mm at 10 s,
// 20 s of motion after it; the camera corrected and refined to within 0.02° and 0.5 mm of its true
// new pose, and the RMSE of the last 10 s within 5 % of the RMSE before the bump.
TEST(CalibrationHealth, CorrectModeWithAnchorsReachesTheTruePose) {
  Scene scene = walk8_scene(30.0, 8, walk8_anchors());
  scene.set_camera_bump(3, 10 * kNsPerSecond, bump_of(0.5, 5.0));
  const BumpRun run = track(scene, "correct", 10 * kNsPerSecond, true);
  const RigidTransform truth = scene.camera_pose_at(3, scene.duration_ns());
  const RigidTransform& used = run.final_poses.at("cam3");
  const double angle_deg = Eigen::AngleAxisd(used.q * truth.q.conjugate()).angle() / kDegree;
  const double moved_mm = 1e3 * (used.t - truth.t).norm();
  std::size_t bumps = 0;
  for (const auto& c : run.corrections) bumps += c.kind == CalibrationCorrection::Kind::kBump ? 1 : 0;
  std::printf(
      "cam3 at the end: %.4f deg, %.2f mm from its true pose; %zu bump corrections, %zu in all; RMSE "
      "before %.3f mm, last 10 s %.3f mm (x%.3f)\n",
      angle_deg, moved_mm, bumps, run.corrections.size(), run.rmse_before_mm, run.rmse_last_mm,
      run.rmse_last_mm / run.rmse_before_mm);
  ASSERT_GE(bumps, 1u);
  EXPECT_GE(run.first_quarantine_ns, 10 * kNsPerSecond);
  EXPECT_LE(run.first_quarantine_ns, 12 * kNsPerSecond);
  EXPECT_LT(angle_deg, 0.02);
  EXPECT_LT(moved_mm, 0.5);
  EXPECT_NE(run.health.at(3).state, CalibrationState::kQuarantined) << run.health.at(3).reason;
  EXPECT_LE(run.rmse_last_mm, 1.05 * run.rmse_before_mm);
}

// The acceptance's single bump without anchor markers: 0.5° and 5 mm at 10 s, 20 s of motion after
// it. The bump's correction leaves the camera ~1 mm from its true pose (the tracks' errors over
// its one-second window, mostly along the camera's axis); the settling refinement over the 12.5 s
// after it (every monitored frame, no centre prior) brings it within 0.5 mm.
TEST(CalibrationHealth, CorrectModeWithoutAnchorsReachesTheTruePose) {
  Scene scene = walk8_scene(30.0, 8);
  scene.set_camera_bump(3, 10 * kNsPerSecond, bump_of(0.5, 5.0));
  const BumpRun run = track(scene, "correct");
  const RigidTransform truth = scene.camera_pose_at(3, scene.duration_ns());
  const RigidTransform& used = run.final_poses.at("cam3");
  const double angle_deg = Eigen::AngleAxisd(used.q * truth.q.conjugate()).angle() / kDegree;
  const Eigen::Vector3d error_cam = truth.q.conjugate() * (used.t - truth.t);
  std::size_t bumps = 0;
  std::size_t settles = 0;
  TimeNs settled_ns = 0;
  for (const auto& c : run.corrections) {
    bumps += c.kind == CalibrationCorrection::Kind::kBump ? 1 : 0;
    if (c.kind != CalibrationCorrection::Kind::kSettle) continue;
    ++settles;
    settled_ns = c.stamp_ns - kEpoch;
  }
  std::printf(
      "cam3 at the end, no anchors: %.4f deg, %.2f mm from its true pose (camera frame %+.2f %+.2f %+.2f "
      "mm); "
      "%zu bump corrections, %zu settling refinements (the last at %.1f s); RMSE before %.3f mm, last 10 s "
      "%.3f mm (x%.3f)\n",
      angle_deg, 1e3 * error_cam.norm(), 1e3 * error_cam.x(), 1e3 * error_cam.y(), 1e3 * error_cam.z(), bumps,
      settles, ns_to_seconds(settled_ns), run.rmse_before_mm, run.rmse_last_mm,
      run.rmse_last_mm / run.rmse_before_mm);
  ASSERT_GE(bumps, 1u);
  EXPECT_EQ(settles, 1u);
  EXPECT_LE(settled_ns, 30 * kNsPerSecond);  // within 20 s of the bump
  EXPECT_LT(angle_deg, 0.02);
  EXPECT_LT(error_cam.norm(), 0.5e-3);
  EXPECT_NE(run.health.at(3).state, CalibrationState::kQuarantined) << run.health.at(3).reason;
  EXPECT_LE(run.rmse_last_mm, 1.05 * run.rmse_before_mm);
}

// The false-alarm measurement: PANOPTES_CALHEALTH_SECONDS of unbumped walk8 per seed (default 60)
// over PANOPTES_CALHEALTH_SEEDS seeds (default 2).
TEST(CalibrationHealth, NoFalseAlarmsOnNormalTrackingWithClutter) {
  const char* seconds_text = std::getenv("PANOPTES_CALHEALTH_SECONDS");
  const char* seeds_text = std::getenv("PANOPTES_CALHEALTH_SEEDS");
  const double seconds = seconds_text != nullptr ? std::atof(seconds_text) : 40.0;
  const int seeds = seeds_text != nullptr ? std::atoi(seeds_text) : 2;
  std::uint64_t quarantines = 0;
  std::uint64_t residuals = 0;
  for (int seed = 100; seed < 100 + seeds; ++seed) {
    const BumpRun run = track(walk8_scene(seconds, seed), "detect", kNsPerSecond * 3600);
    print(("walk8 seed " + std::to_string(seed)).c_str(), run);
    quarantines += run.quarantines;
    for (const auto& h : run.health) residuals += h.residuals;
  }
  std::printf("%d seeds x %.0f s x 8 cameras: %llu quarantines, %llu residuals\n", seeds, seconds,
              static_cast<unsigned long long>(quarantines), static_cast<unsigned long long>(residuals));
  EXPECT_EQ(quarantines, 0u);
}

}  // namespace
}  // namespace panoptes::estimator

namespace panoptes::estimator {
namespace {

// Issue 36's table (docs/continuous_calibration.md): bumps of 0.1°, 2° and 5° (with 5 mm) of cam3
// at 10 s, and cam3 and cam6 bumped by 0.5° at once; the 0.5° row of cam3 alone is
// BumpedCameraIsQuarantinedWithinTwoSecondsAndTrackingHolds's. Each row asserts what the table
// shows: the bumped cameras and no other quarantined within 1.5 s of the bump (measured 0.42-0.96
// s), the monitor's tracks more accurate after the bump than without it (x1.07-1.59 against
// x1.19-5.56 of the RMSE before) and coverage >= 0.99 (0.996-1.000). With
// PANOPTES_BUMP_TABLE_CORRECT set, also the 0.5° row of cam3 and mode correct over 30 s without
// and with anchors for every row (printed).
TEST(CalibrationHealth, BumpTable) {
  struct Case {
    const char* name;
    double degrees;
    std::vector<std::size_t> cameras;
  };
  const bool correct_too = std::getenv("PANOPTES_BUMP_TABLE_CORRECT") != nullptr;  // 50 s more: by hand
  std::vector<Case> cases = {{"0.1 deg cam3", 0.1, {3}},
                             {"2 deg cam3", 2.0, {3}},
                             {"5 deg cam3", 5.0, {3}},
                             {"0.5 deg cam3+cam6", 0.5, {3, 6}}};
  if (correct_too) cases.insert(cases.begin() + 1, {"0.5 deg cam3", 0.5, {3}});  // its correct rows
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    Scene scene = walk8_scene(20.0, 8);
    for (const std::size_t camera : c.cameras)
      scene.set_camera_bump(camera, 10 * kNsPerSecond, bump_of(c.degrees, 5.0));
    const BumpRun off = track(scene, "off");
    const BumpRun detect = track(scene, "detect");
    print_table_row(c.name, detect, off);
    std::vector<std::string> bumped;
    for (const std::size_t camera : c.cameras) bumped.push_back(scene.cameras()[camera].calibration.id);
    std::vector<std::string> quarantined;
    for (const auto& h : detect.health)
      if (h.quarantines > 0) quarantined.push_back(h.camera_id);
    EXPECT_EQ(quarantined, bumped);
    EXPECT_GE(detect.first_quarantine_ns, 10 * kNsPerSecond);
    EXPECT_LE(detect.first_quarantine_ns, 10 * kNsPerSecond + kNsPerSecond * 3 / 2);
    EXPECT_LT(detect.rmse_after_mm, off.rmse_after_mm);
    EXPECT_GE(detect.coverage_after, 0.99);
    // Mode correct over 30 s (20 s of motion after the bump), without and with anchors: when each
    // bumped camera was first corrected, and its pose in use at the end against its true pose.
    if (!correct_too) continue;
    for (const bool anchored : {false, true}) {
      Scene longer = walk8_scene(30.0, 8, anchored ? walk8_anchors() : std::string());
      for (const std::size_t camera : c.cameras)
        longer.set_camera_bump(camera, 10 * kNsPerSecond, bump_of(c.degrees, 5.0));
      const BumpRun correct = track(longer, "correct", 10 * kNsPerSecond, anchored);
      std::string cameras;
      for (const std::size_t camera : c.cameras) {
        const std::string id = longer.cameras()[camera].calibration.id;
        double first_s = -1.0;
        for (const auto& k : correct.corrections)
          if (k.camera_id == id && k.kind == CalibrationCorrection::Kind::kBump && first_s < 0.0)
            first_s = ns_to_seconds(k.stamp_ns - kEpoch) - 10.0;
        const RigidTransform truth = longer.camera_pose_at(camera, longer.duration_ns());
        const RigidTransform& used = correct.final_poses.at(id);
        char text[160];
        std::snprintf(text, sizeof text, " %s corrected %s, at the end %.4f deg %.2f mm;", id.c_str(),
                      first_s < 0.0 ? "never" : (std::to_string(first_s) + " s after").c_str(),
                      Eigen::AngleAxisd(used.q * truth.q.conjugate()).angle() / kDegree,
                      1e3 * (used.t - truth.t).norm());
        cameras += text;
      }
      std::printf("TABLE %-18s correct%s:%s RMSE after x%.3f (coverage %.3f)\n", c.name,
                  anchored ? " with anchors" : "", cameras.c_str(),
                  correct.rmse_after_mm / correct.rmse_before_mm, correct.coverage_after);
    }
  }
}

}  // namespace
}  // namespace panoptes::estimator

namespace panoptes::estimator {
namespace {

// Issue 36 item 4: every camera of walk8 drifts, turning about its own random axis (drawn from
// the seed); mode correct follows it from the tracks, with and without six anchor markers.
// PANOPTES_DRIFT_SECONDS of scene (default 40; 60 until stop 71, 35 s of the suite's CPU against
// 21 s, the same margins) at PANOPTES_DRIFT_DEG_PER_MIN (default 0.15, three times the acceptance's
// rate; its 10 minutes at 0.05: PANOPTES_DRIFT_SECONDS=600 PANOPTES_DRIFT_DEG_PER_MIN=0.05).
struct DriftRun {
  double rmse_mm = 0;  // over the second half of the scene
  double coverage = 0;
  std::size_t corrections = 0;
  std::uint64_t quarantines = 0;
  double worst_rotation_deg = 0;  // a camera's pose in use at the end against its true pose
  double worst_centre_mm = 0;
  double frame_moved_mm = 0;  // the rigid motion of the cameras in use against the truth, at (0, 0, 1)
};

DriftRun drift_run(const Scene& scene, const std::string& mode, bool anchored = false) {
  const BumpRun bump_run = track(scene, mode, scene.duration_ns() / 2, anchored);
  DriftRun run;
  run.rmse_mm = bump_run.rmse_after_mm;
  run.coverage = bump_run.coverage_after;
  run.corrections = bump_run.corrections.size();
  run.quarantines = bump_run.quarantines;
  Eigen::Matrix3Xd used(3, scene.cameras().size());
  Eigen::Matrix3Xd truth(3, scene.cameras().size());
  for (std::size_t i = 0; i < scene.cameras().size(); ++i) {
    const RigidTransform real = scene.camera_pose_at(i, scene.duration_ns());
    const RigidTransform& in_use = bump_run.final_poses.at(scene.cameras()[i].calibration.id);
    run.worst_rotation_deg =
        std::max(run.worst_rotation_deg, Eigen::AngleAxisd(in_use.q * real.q.conjugate()).angle() / kDegree);
    run.worst_centre_mm = std::max(run.worst_centre_mm, 1e3 * (in_use.t - real.t).norm());
    used.col(static_cast<Eigen::Index>(i)) = in_use.t;
    truth.col(static_cast<Eigen::Index>(i)) = real.t;
  }
  const Eigen::Matrix4d frame = Eigen::umeyama(truth, used, false);  // truth -> in use
  const Eigen::Vector3d centre(0.0, 0.0, 1.0);
  run.frame_moved_mm =
      1e3 * ((frame.topLeftCorner<3, 3>() * centre + frame.topRightCorner<3, 1>()) - centre).norm();
  return run;
}

TEST(CalibrationHealth, DriftOfEveryCameraIsFollowed) {
  const char* seconds_text = std::getenv("PANOPTES_DRIFT_SECONDS");
  const char* rate_text = std::getenv("PANOPTES_DRIFT_DEG_PER_MIN");
  const double seconds = seconds_text != nullptr ? std::atof(seconds_text) : 40.0;
  const double rate = rate_text != nullptr ? std::atof(rate_text) : 0.15;
  const std::string anchors = walk8_anchors();
  const Scene still = walk8_scene(seconds, 8, anchors);
  Scene drifting = walk8_scene(seconds, 8, anchors);
  for (std::size_t i = 0; i < drifting.cameras().size(); ++i)
    drifting.set_camera_drift(i, 0, rate, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  const auto show = [&](const char* what, const DriftRun& r) {
    std::printf(
        "DRIFT %-22s %.0f s at %.3f deg/min: RMSE (second half) %.3f mm, coverage %.4f, %zu corrections, "
        "%llu quarantines; at the end worst camera %.4f deg %.2f mm, frame moved %.2f mm\n",
        what, seconds, rate, r.rmse_mm, r.coverage, r.corrections,
        static_cast<unsigned long long>(r.quarantines), r.worst_rotation_deg, r.worst_centre_mm,
        r.frame_moved_mm);
  };
  const DriftRun reference = drift_run(still, "correct");
  show("no drift, correct", reference);
  const DriftRun detect = drift_run(drifting, "detect");
  show("drift, detect", detect);
  const DriftRun followed = drift_run(drifting, "correct");
  show("drift, correct", followed);
  const DriftRun anchored = drift_run(drifting, "correct", true);
  show("drift, correct, anchors", anchored);
  const DriftRun still_anchored = drift_run(still, "correct", true);
  show("no drift, correct, anchors", still_anchored);
  EXPECT_EQ(reference.corrections, 0u) << "an unmoved rig was corrected";
  // An unmoved, anchored rig may be refined by the noise of a refinement (a few thousandths of a
  // degree), which must not cost accuracy.
  EXPECT_LE(still_anchored.worst_rotation_deg, 0.01);
  EXPECT_LE(still_anchored.rmse_mm, 1.02 * reference.rmse_mm);
  // Without anchors the tracks stay whole while the world frame moves with the cameras' mean.
  EXPECT_GE(followed.coverage, 0.99);
  EXPECT_EQ(followed.quarantines, 0u);
  // With anchors the frame holds and the cameras stay near their drifting truth (measured at 40 s
  // and 0.15 deg/min: 0.17 mm, 0.014 deg, RMSE x1.206 of the unmoved rig's; at 60 s 0.16 mm,
  // 0.011 deg, x1.196).
  EXPECT_GE(anchored.coverage, 0.99);
  EXPECT_LE(anchored.frame_moved_mm, 1.0);
  EXPECT_LE(anchored.worst_rotation_deg, 0.025);
  EXPECT_LE(anchored.rmse_mm, 1.3 * still_anchored.rmse_mm);
  EXPECT_LT(anchored.rmse_mm, detect.rmse_mm);
}

}  // namespace
}  // namespace panoptes::estimator
