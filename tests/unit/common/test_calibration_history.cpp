// SPDX-License-Identifier: Apache-2.0
// Versioned calibration (panoptes/calibration_history.h): versions stored beside the file with
// their reason, cameras and residuals; a hand edit kept as a version; revert restores the exact
// bytes; accept marks a version; a damaged index is an error naming the file and line.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "panoptes/calibration_file.h"
#include "panoptes/calibration_history.h"
#include "panoptes/errors.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

SystemCalibration rig(double cam1_x) {
  SystemCalibration calibration;
  for (int c = 0; c < 3; ++c) {
    CameraCalibration camera;
    camera.id = "cam" + std::to_string(c);
    camera.intrinsics = {1280, 1024, 1000.0, 1000.0, 640.0, 512.0, {}};
    RigidTransform T;
    T.t = Eigen::Vector3d(c == 1 ? cam1_x : 1.0 * c, 2.0, 2.5);
    camera.T_world_cam = T;
    calibration.cameras.push_back(camera);
  }
  return calibration;
}

std::string bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(CalibrationHistory, RecordsVersionsBesideTheFileAndRevertsToExactBytes) {
  testing::TempDir dir;
  const auto file = dir.file("calibration.yaml");
  save_calibration(rig(1.0), file);
  const std::string original = bytes(file) + "# a comment the user wrote\n";
  std::ofstream(file, std::ios::binary) << original;

  CalibrationHistory history(file);
  EXPECT_TRUE(history.versions().empty());
  const auto corrected =
      history.record(rig(1.005), change_because("cam1 corrected after a bump", {"cam1"}, 1.9, 0.31));
  EXPECT_EQ(corrected.version, 2);  // version 1: the file as it was
  auto all = history.versions();
  ASSERT_EQ(all.size(), 2U);
  EXPECT_EQ(all[0].change.reason, "initial");
  EXPECT_EQ(history.bytes_of(1), original);  // comments and all
  EXPECT_EQ(all[1].change.cameras, std::vector<std::string>{"cam1"});
  EXPECT_DOUBLE_EQ(all[1].change.residual_before_px, 1.9);
  EXPECT_DOUBLE_EQ(all[1].change.residual_after_px, 0.31);
  EXPECT_EQ(all[1].state, VersionState::kApplied);
  EXPECT_EQ(all[1].time_utc.size(), 20U);  // 2026-11-28T16:58:03Z
  EXPECT_EQ(load_calibration(file).find("cam1")->T_world_cam->t.x(), 1.005);
  EXPECT_TRUE(std::filesystem::exists(dir.file("calibration.yaml.history") / "v0002.yaml"));

  const auto back = history.revert(1);
  EXPECT_EQ(back.version, 3);
  EXPECT_EQ(back.change.reason, "revert to 1");
  EXPECT_EQ(back.change.cameras, std::vector<std::string>{"cam1"});
  EXPECT_EQ(bytes(file), original);  // byte for byte
  all = history.versions();
  EXPECT_EQ(all[1].state, VersionState::kReverted);
  EXPECT_EQ(all[0].state, VersionState::kApplied);
  EXPECT_TRUE(std::isnan(all[2].change.residual_before_px));
  EXPECT_TRUE(std::isnan(all[0].change.residual_after_px));  // "initial": no residuals known
  EXPECT_EQ(history.revert(1).version, 3);                   // already the current file: no new version
  EXPECT_EQ(history.versions().size(), 3U);
}

// test_continuous_calibration (stop 97): the estimator wrote its version 3 and, in the same second,
// `calibrate revert` wrote version 4; the estimator's reload read the reverted file but the history's
// last version was still 3, so it logged the wrong version. A version is now listed before the file
// changes. Here a reader polls the file while versions are recorded and reverted: whenever it sees
// new bytes, they must be those of one of the history's versions.
TEST(CalibrationHistory, AReaderThatSeesTheNewFileFindsItsVersion) {
  testing::TempDir dir;
  const auto file = dir.file("calibration.yaml");
  save_calibration(rig(1.0), file);
  CalibrationHistory writer(file);
  writer.start();
  std::atomic<bool> done{false};
  int seen = 0, unlisted = 0;
  std::thread reader([&] {
    const CalibrationHistory history(file);
    std::string last;
    while (!done.load()) {
      const std::string now = bytes(file);
      if (now.empty() || now == last) continue;
      last = now;
      ++seen;
      const auto count = static_cast<int>(history.versions().size());
      bool listed = false;
      for (int v = count; v >= 1 && v > count - 3 && !listed; --v) listed = history.bytes_of(v) == now;
      unlisted += !listed;
    }
  });
  for (int i = 1; i <= 150; ++i) {
    writer.record(rig(1.0 + 0.001 * i), change_because("step " + std::to_string(i), {"cam1"}));
    if (i % 10 == 0) writer.revert(i);  // back to an earlier version, as an operator would
  }
  done = true;
  reader.join();
  std::printf("reader saw %d new files, %d of them not yet in the history\n", seen, unlisted);
  EXPECT_GT(seen, 0);
  EXPECT_EQ(unlisted, 0);
}

TEST(CalibrationHistory, AHandEditIsKeptAsAVersionBeforeTheNextChange) {
  testing::TempDir dir;
  const auto file = dir.file("calibration.yaml");
  save_calibration(rig(1.0), file);
  CalibrationHistory history(file);
  history.record(rig(1.01), change_because("wand solve"));
  save_calibration(rig(1.02), file);  // edited by hand (or by another program)
  const auto next = history.record(rig(1.03), change_because("drift refinement", {"cam1"}));
  EXPECT_EQ(next.version, 4);
  const auto all = history.versions();
  EXPECT_EQ(all[2].change.reason, "edited outside the history");
  EXPECT_EQ(load_calibration(history.directory() / all[2].file).find("cam1")->T_world_cam->t.x(), 1.02);
}

TEST(CalibrationHistory, AcceptMarksAVersionAndUnknownVersionsAreErrorsNamingTheHistory) {
  testing::TempDir dir;
  const auto file = dir.file("calibration.yaml");
  save_calibration(rig(1.0), file);
  CalibrationHistory history(file);
  history.record(rig(1.01), change_because("cam1 corrected", {"cam1"}));
  history.accept(2);
  EXPECT_EQ(history.versions()[1].state, VersionState::kAccepted);
  for (const int bad : {0, 3, -1}) {
    try {
      history.revert(bad);
      ADD_FAILURE() << bad;
    } catch (const ConfigError& error) {
      EXPECT_NE(error.file().find("history.jsonl"), std::string::npos);
      EXPECT_NE(std::string(error.what()).find("no version " + std::to_string(bad) + " (2 stored)"),
                std::string::npos)
          << error.what();
    }
    EXPECT_THROW(history.accept(bad), ConfigError);
  }
  history.revert(1);
  EXPECT_THROW(history.accept(2), ConfigError);  // reverted
}

TEST(CalibrationHistory, StartedHistoriesVersionEveryWriteOfTheFile) {
  testing::TempDir dir;
  const auto file = dir.file("calibration.yaml");
  write_calibration_text(file, calibration_to_yaml(rig(1.0)), change_because("calibrate solve"));
  EXPECT_FALSE(std::filesystem::exists(CalibrationHistory(file).directory()));  // no history: a plain write
  CalibrationHistory history(file);
  history.start();
  history.start();  // once
  ASSERT_EQ(history.versions().size(), 1U);
  write_calibration_text(file, "# solved\n" + calibration_to_yaml(rig(1.2)),
                         change_because("calibrate solve"));
  const auto all = history.versions();
  ASSERT_EQ(all.size(), 2U);
  EXPECT_EQ(all[1].change.cameras, std::vector<std::string>{"cam1"});  // found from the difference
  EXPECT_EQ(bytes(file).rfind("# solved\n", 0), 0U);
  EXPECT_THROW(CalibrationHistory(dir.file("missing.yaml")).start(), ConfigError);
}

TEST(CalibrationHistory, ADamagedIndexNamesTheFileAndLine) {
  testing::TempDir dir;
  const auto file = dir.file("calibration.yaml");
  save_calibration(rig(1.0), file);
  CalibrationHistory history(file);
  history.record(rig(1.01), change_because("x"));
  std::ofstream(history.directory() / "history.jsonl", std::ios::app) << "{\"version\": 3, oops\n";
  try {
    history.versions();
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("history.jsonl: line 3"), std::string::npos) << error.what();
  }
}

TEST(CalibrationHistory, ChangedCamerasComparesEveryParameter) {
  SystemCalibration a = rig(1.0);
  SystemCalibration b = rig(1.0);
  EXPECT_TRUE(changed_cameras(a, b).empty());
  b.cameras[2].intrinsics.distortion[0] = 1e-3;
  b.cameras.pop_back();
  b.cameras.push_back(a.cameras[2]);
  b.cameras.back().intrinsics.fx += 1e-6;
  CameraCalibration extra = a.cameras[0];
  extra.id = "cam9";
  b.cameras.push_back(extra);
  a.cameras[0].T_world_cam->q = Eigen::Quaterniond(Eigen::AngleAxisd(0.001, Eigen::Vector3d::UnitZ()));
  EXPECT_EQ(changed_cameras(a, b), (std::vector<std::string>{"cam0", "cam2", "cam9"}));
}

}  // namespace
}  // namespace panoptes
