// SPDX-License-Identifier: Apache-2.0
// panoptes_export's library (tools/export): which option combinations it refuses, how it picks a
// marker file's format, its summary line, and the error for records with nothing to export.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/errors.h"
#include "panoptes/export_job/export_job.h"

namespace panoptes::export_job {
namespace {

ExportOptions records_to_c3d() {
  ExportOptions options;
  options.tracks = "tracks.jsonl";
  options.c3d = "out.c3d";
  return options;
}

TEST(ExportJob, AcceptsRecordsOrMarkersWithAnOutput) {
  EXPECT_FALSE(find_problem(records_to_c3d()));
  ExportOptions poses_only;
  poses_only.poses = "poses.jsonl";
  poses_only.bodies_csv = "bodies.csv";
  EXPECT_FALSE(find_problem(poses_only));
  ExportOptions convert;
  convert.markers = "walk.trc";
  convert.csv = "walk.csv";
  EXPECT_FALSE(find_problem(convert));
}

TEST(ExportJob, RefusesNoInputOrBothInputs) {
  ExportOptions none = records_to_c3d();
  none.tracks.clear();
  ASSERT_TRUE(find_problem(none));
  EXPECT_EQ(find_problem(none)->option, "input");
  ExportOptions both = records_to_c3d();
  both.markers = "walk.trc";
  ASSERT_TRUE(find_problem(both));
  EXPECT_EQ(find_problem(both)->reason, "give --tracks and/or --poses, --markers, or --in-recording");
}

TEST(ExportJob, RefusesNoOutput) {
  ExportOptions options = records_to_c3d();
  options.c3d.clear();
  ASSERT_TRUE(find_problem(options));
  EXPECT_EQ(find_problem(options)->option, "output");
}

TEST(ExportJob, RefusesBodiesFromAMarkerFile) {
  ExportOptions options;
  options.markers = "walk.c3d";
  options.bodies_csv = "bodies.csv";
  ASSERT_TRUE(find_problem(options));
  EXPECT_EQ(find_problem(options)->option, "--bodies-csv");
  EXPECT_EQ(find_problem(options)->reason, "needs --poses or --in-recording");
}

TEST(ExportJob, MarkerFileFormatByExtensionInAnyCase) {
  EXPECT_EQ(marker_file_format("a/walk.c3d"), MarkerFileFormat::kC3d);
  EXPECT_EQ(marker_file_format("WALK.C3D"), MarkerFileFormat::kC3d);
  EXPECT_EQ(marker_file_format("walk.trc"), MarkerFileFormat::kTrc);
  EXPECT_EQ(marker_file_format("walk.c3d.trc"), MarkerFileFormat::kTrc);
  EXPECT_EQ(marker_file_format("c3d"), MarkerFileFormat::kTrc);  // no extension: read as TRC
}

TEST(ExportJob, SummaryLineIsTheDocumentedJson) {
  ExportSummary summary;
  summary.frames = 1200;
  summary.markers = 12;
  summary.bodies = 2;
  summary.rate_hz = 100;
  summary.skipped_records = 3;
  summary.seconds = 0.12345;
  EXPECT_EQ(summary_line(summary),
            "{\"frames\": 1200, \"markers\": 12, \"bodies\": 2, \"rate_hz\": 100, \"skipped_records\": 3, "
            "\"seconds\": 0.123}");
}

TEST(ExportJob, RecordsWithNothingToExportNameTheFile) {
  const std::filesystem::path tracks =
      std::filesystem::temp_directory_path() /
      ("export_job_empty_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + ".jsonl");
  { std::ofstream(tracks) << ""; }
  ExportOptions options = records_to_c3d();
  options.tracks = tracks.string();
  options.c3d = (tracks.parent_path() / "never_written.c3d").string();
  try {
    run_export(options);
    ADD_FAILURE() << "exported nothing without an error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find(tracks.string()), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("no track or pose records"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(std::filesystem::exists(options.c3d));
  std::filesystem::remove(tracks);
}

}  // namespace
}  // namespace panoptes::export_job
