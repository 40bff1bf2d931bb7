// SPDX-License-Identifier: Apache-2.0
// panoptes_label's library (tools/label): `model` over the real Gait2392 static trial writes a
// subject model that reads back, its report and summary line, and bad inputs naming the file;
// `run` labels walk1 given as anonymous columns, writes every name right and reports the fill.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>

#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include "../scratch_dir.h"
#include "../shared_data.h"
#include "panoptes/dds/decode.h"
#include "panoptes/errors.h"
#include "panoptes/export_job/recording_source.h"
#include "panoptes/formats/trc.h"
#include "panoptes/label_job/label_job.h"
#include "panoptes/labelling_files/subject_model_file.h"
#include "panoptes/recording/mcap_writer.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::label_job {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return panoptes::testing::process_scratch_dir("panoptes_label_job") / name;
}

ModelCommandOptions gait2392() {
  ModelCommandOptions options;
  options.static_trial = test::shared_data("static/gait2392_subject01_static.trc").string();
  options.marker_set = (fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "markersets" / "gait2392.yaml").string();
  options.out = scratch("subject01.yaml").string();
  return options;
}

TEST(LabelJob, SubjectNameDefaultsToTheStaticFilesStem) {
  ModelCommandOptions options = gait2392();
  EXPECT_EQ(subject_name(options), "gait2392_subject01_static");
  options.subject = "subject01";
  EXPECT_EQ(subject_name(options), "subject01");
}

TEST(LabelJob, NeedsExactlyOneTrialAndAFrameRange) {
  ModelCommandOptions options = gait2392();
  EXPECT_FALSE(find_problem(options));
  options.labelled = "walk.trc";
  ASSERT_TRUE(find_problem(options));
  EXPECT_NE(find_problem(options)->find("exactly one of --static"), std::string::npos);
  options.static_trial.clear();
  EXPECT_FALSE(find_problem(options));
  EXPECT_EQ(trial_file(options), "walk.trc");
  EXPECT_EQ(subject_name(options), "walk");
  for (const char* bad : {"10", "a:5", "5:5", "9:3", "1:2x"}) {
    options.frames = bad;
    ASSERT_TRUE(find_problem(options)) << bad;
    EXPECT_NE(find_problem(options)->find("--frames"), std::string::npos) << bad;
  }
  EXPECT_EQ(frame_range("0:75"), std::make_pair(std::size_t{0}, std::size_t{75}));
  EXPECT_EQ(frame_range(":75").second, 75U);
  EXPECT_EQ(frame_range("75:").first, 75U);
  EXPECT_EQ(frame_range("75:").second, std::numeric_limits<std::size_t>::max());
}

TEST(LabelJob, ModelFromHalfALabelledTrial) {
  PANOPTES_REQUIRE_SHARED(test::shared_data("static/gait2392_subject01_walk1.trc"));
  ModelCommandOptions options = gait2392();
  options.static_trial.clear();
  options.labelled = test::shared_data("static/gait2392_subject01_walk1.trc").string();
  options.frames = ":75";
  const auto model = run_model(options);
  EXPECT_EQ(model.frames, 75U);
  EXPECT_TRUE(model.options.dynamic);
  EXPECT_EQ(labelling::load_subject_model(options.out).options.dynamic, true);
  EXPECT_NE(
      model_report(model).find("flagged R.Knee.Med: calibration-only marker is not in the labelled trial"),
      std::string::npos)
      << model_report(model);
}

TEST(LabelJob, ModelWritesASubjectModelAndReportsTheFlags) {
  PANOPTES_REQUIRE_SHARED(test::shared_data("static/gait2392_subject01_static.trc"));
  ModelCommandOptions options = gait2392();
  options.min_tolerance_mm = 1.0;
  const auto model = run_model(options);
  const auto back = labelling::load_subject_model(options.out);
  EXPECT_EQ(back.marker_count(), 49U);
  EXPECT_DOUBLE_EQ(back.options.min_tolerance_m, 0.001);
  const std::string report = model_report(model);
  EXPECT_NE(report.find("flagged L.Temple: moved 21.1 mm RMS"), std::string::npos) << report;
  EXPECT_NE(report.find("R.Thigh (parent Pelvis): 3 tracked markers + 2 calibration-only, static fit RMS"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("R.Forearm (parent R.UpperArm): 2 tracked markers, no pose"), std::string::npos)
      << report;
  const auto summary = nlohmann::json::parse(model_summary_line(model));
  EXPECT_EQ(summary["markers"], 49);
  EXPECT_EQ(summary["segments"], 13);
  EXPECT_EQ(summary["joints"], 4);
  EXPECT_EQ(summary["flagged"], 1);
}

// A walking C3D trial given as the static one: built, every marker flagged, and the report says the
// subject did not stand still.
TEST(LabelJob, AWalkGivenAsTheStaticTrialIsReportedAsNotStandingStill) {
  const auto walk = test::shared_data("c3d/Walk1.c3d");
  PANOPTES_REQUIRE_SHARED(walk);
  ModelCommandOptions options = gait2392();
  options.static_trial = walk.string();
  options.marker_set = scratch("pelvis.yaml").string();
  std::ofstream(options.marker_set) << "name: pelvis\nmarkers: [RASI, LASI, VSAC]\n"
                                       "segments: [{name: Pelvis, markers: [RASI, LASI, VSAC]}]\n";
  const auto model = run_model(options);
  const std::string report = model_report(model);
  EXPECT_NE(report.find("the subject did not stand still: 3 of 3 markers moved"), std::string::npos)
      << report;
  EXPECT_LT(model.segments[0].static_fit_rms_m, 0.002);  // the pelvis stays rigid while walking
}

TEST(LabelJob, ABadMarkerSetIsAConfigErrorNamingTheFileAndEntry) {
  ModelCommandOptions options = gait2392();
  options.marker_set = scratch("bad.yaml").string();
  std::ofstream(options.marker_set) << "name: bad\nmarkers: [A, B, C]\nsegments:\n"
                                       "  - {name: S, parent: T, markers: [A, B, C]}\n";
  try {
    run_model(options);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what())
                  .find(options.marker_set + ": segments[0].parent: unknown parent segment 'T'"),
              std::string::npos)
        << error.what();
  }
}

TEST(LabelJob, RunOptionsAreChecked) {
  RunCommandOptions options;
  options.subjects = {"s1.yaml"};
  options.out = "labelled.c3d";
  ASSERT_TRUE(find_problem(options));  // no input
  EXPECT_NE(find_problem(options)->find("--tracks or --in-recording"), std::string::npos);
  options.tracks = "tracks.jsonl";
  options.in_recording = "session.mcap";
  ASSERT_TRUE(find_problem(options));  // two inputs
  options.tracks.clear();
  EXPECT_FALSE(find_problem(options));
  options.in_recording.clear();
  options.tracks = "tracks.jsonl";
  EXPECT_FALSE(find_problem(options));
  for (const char* out : {"labelled.TRC", "labelled.csv"}) {
    options.out = out;
    EXPECT_FALSE(find_problem(options)) << out;
  }
  options.out = "labelled.mp4";
  ASSERT_TRUE(find_problem(options));
  EXPECT_NE(find_problem(options)->find("--out"), std::string::npos);
  options.out = "labelled.trc";
  options.fill = "cubic";
  ASSERT_TRUE(find_problem(options));
  EXPECT_NE(find_problem(options)->find("--fill"), std::string::npos);
  options.fill = "spline";
  options.max_gap_s = -1.0;
  ASSERT_TRUE(find_problem(options));
  EXPECT_NE(find_problem(options)->find("--max-gap-s"), std::string::npos);
}

// Every sample of `truth` comes out under its own marker's name, equal to it (the hole of marker
// `hole` in frames [first, last) filled, within 10 mm). Returns the samples compared.
std::size_t expect_named_as(const MarkerTrajectories& out, const MarkerTrajectories& truth, std::size_t hole,
                            std::size_t first, std::size_t last) {
  std::size_t compared = 0;
  for (std::size_t m = 0; m < truth.marker_count(); ++m) {
    const auto column = std::find(out.marker_names.begin(), out.marker_names.end(), truth.marker_names[m]);
    EXPECT_NE(column, out.marker_names.end()) << truth.marker_names[m];
    if (column == out.marker_names.end()) continue;
    const auto o = static_cast<std::size_t>(column - out.marker_names.begin());
    for (std::size_t f = 0; f < std::min(truth.frame_count(), out.frame_count()); ++f) {
      if (!truth.is_valid(f, m)) continue;
      EXPECT_TRUE(out.is_valid(f, o)) << truth.marker_names[m] << " frame " << f;
      const double tolerance = m == hole && f >= first && f < last ? 0.01 : 1e-6;
      EXPECT_LT((out.position(f, o) - truth.position(f, m)).norm(), tolerance) << truth.marker_names[m] << f;
      ++compared;
    }
  }
  return compared;
}

// walk1 as anonymous columns (the TRC's names are not read) with a hole cut into R.ASIS: every
// sample comes out under the name of the walk's own marker, the hole filled and counted.
TEST(LabelJob, RunLabelsWalk1AndFillsAHole) {
  const auto walk_path = test::shared_data("static/gait2392_subject01_walk1.trc");
  PANOPTES_REQUIRE_SHARED(walk_path);
  PANOPTES_REQUIRE_SHARED(test::shared_data("static/gait2392_subject01_static.trc"));
  ModelCommandOptions model = gait2392();
  model.subject = "s1";
  run_model(model);
  MarkerTrajectories walk = load_trc(walk_path);
  for (std::size_t f = 60; f < 70; ++f) walk.valid[f * walk.marker_count()] = 0;  // R.ASIS, 167 ms
  const auto holed = scratch("holed.trc");
  write_trc(holed, walk);
  RunCommandOptions options;
  options.tracks = holed.string();
  options.subjects = {model.out};
  options.out = scratch("labelled.trc").string();
  options.report = scratch("labelled.json").string();
  const RunSummary summary = run_labelling(options);
  EXPECT_EQ(summary.labelling.labelled_frames, summary.labelling.run_frames);
  ASSERT_EQ(summary.subjects.size(), 1U);
  // The default fill (pattern), with the whole walk to learn from.
  EXPECT_EQ(summary.subjects[0].fill.pattern.gaps, 1U);
  EXPECT_EQ(summary.subjects[0].fill.pattern.frames, 10U);
  EXPECT_EQ(expect_named_as(load_trc(options.out), load_trc(walk_path), 0, 60, 70), 41U * 151U);
  const auto report = nlohmann::json::parse(std::ifstream(options.report));
  EXPECT_EQ(report["subjects"][0]["filled"]["pattern"]["frames"].get<int>(), 10);
  EXPECT_EQ(report["track_frames_labelled"], report["track_frames"]);
}

// walk1 recorded as the estimator publishes it (a MocapFrame per sample, every marker a track with
// an id of its own, one track's id changing after a 150 ms occlusion), labelled from the recording
// with --in-recording: every marker named as the walk's own, the occlusion filled.
TEST(LabelJob, RunLabelsARecordingAsPublishedLive) {
  const auto walk_path = test::shared_data("static/gait2392_subject01_walk1.trc");
  PANOPTES_REQUIRE_SHARED(walk_path);
  PANOPTES_REQUIRE_SHARED(test::shared_data("static/gait2392_subject01_static.trc"));
  ModelCommandOptions model = gait2392();
  model.subject = "s1";
  run_model(model);
  const MarkerTrajectories walk = load_trc(walk_path);
  const auto mcap = scratch("walk1.mcap");
  {
    recording::McapWriter writer(mcap);
    const auto channel = writer.add_channel(writer.add_schema("panoptes/msg/MocapFrame", "ros2idl", ""),
                                            export_job::kFramesChannel, "cdr");
    const std::int64_t t0 = 1'764'000'000'000'000'000;
    for (std::size_t f = 0; f < walk.frame_count(); ++f) {
      msg::MocapFrame frame;
      frame.frame_number(f + 1);
      frame.stamp_ns(t0 + static_cast<std::int64_t>(std::llround(1e9 * f / walk.data_rate_hz)));
      frame.publish_ns(frame.stamp_ns() + 1'000'000);
      frame.source_frame(static_cast<std::int64_t>(f));
      for (std::size_t m = 0; m < walk.marker_count(); ++m) {
        if (!walk.is_valid(f, m) || (m == 3 && f >= 60 && f < 69)) continue;
        msg::FrameMarker marker;
        marker.state().id(static_cast<std::int64_t>(m == 3 && f >= 69 ? 1000 : 100 + m));
        const Eigen::Vector3d& p = walk.position(f, m);
        marker.state().position({p.x(), p.y(), p.z()});
        marker.state().status(1);
        frame.markers().push_back(marker);
      }
      const auto t = static_cast<std::uint64_t>(frame.publish_ns());
      writer.write(channel, static_cast<std::uint32_t>(f), t, t, dds::encode_sample(frame));
    }
    writer.close();
  }
  RunCommandOptions options;
  options.in_recording = mcap.string();
  options.subjects = {model.out};
  options.rate_hz = walk.data_rate_hz;
  options.out = scratch("from_recording.trc").string();
  ASSERT_FALSE(find_problem(options));
  const RunSummary summary = run_labelling(options);
  EXPECT_EQ(summary.input_format, "recording");
  EXPECT_EQ(summary.tracks, 42U);  // 41 markers, one of them under a new id after its occlusion
  EXPECT_EQ(summary.labelling.labelled_frames, summary.labelling.run_frames);
  ASSERT_EQ(summary.subjects.size(), 1U);
  EXPECT_EQ(summary.subjects[0].fill.pattern.frames, 9U);
  EXPECT_GE(expect_named_as(load_trc(options.out), walk, 3, 60, 69), 41U * 150U);
}

TEST(LabelJob, RunWithAMarkerSetAsTheSubjectIsAConfigErrorNamingIt) {
  RunCommandOptions options;
  options.tracks = (fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc").string();
  options.subjects = {(fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "markersets" / "gait2392.yaml").string()};
  options.out = scratch("never.c3d").string();
  try {
    run_labelling(options);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find(options.subjects[0]), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(options.out));
}

}  // namespace
}  // namespace panoptes::label_job
