// SPDX-License-Identifier: Apache-2.0
// Issue 34's export acceptance without a bus: an offline run of the estimator's session builds, for
// every processed frame, the MocapFrame the live node publishes (FrameOutputBuilder,
// to_frame_message) and the records it writes to --out-tracks / --out-poses (to_json_line of
// current_tracks / current_poses, as JsonlOutputs does). The MocapFrames go into an MCAP file with
// the project's writer; panoptes_export --in-recording must give back exactly those records, and
// names for the body-labelled markers. (The live check of the same is
// tests/integration/test_export_recording.sh.)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/dds/decode.h"
#include "panoptes/estimator_app/frame_messages.h"
#include "panoptes/export_job/export_job.h"
#include "panoptes/export_job/recording_source.h"
#include "panoptes/jsonl.h"
#include "panoptes/recording/mcap_writer.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/session/frame_clock.h"
#include "panoptes/session/frame_output.h"
#include "panoptes/simulator.h"
#include "scene_frames.h"

namespace panoptes::session {
namespace {

namespace fs = std::filesystem;
using testing::simulate;

std::vector<std::string> lines_of(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

struct LiveRun {
  std::vector<std::string> track_lines;               // what --out-tracks would hold
  std::vector<std::string> pose_lines;                // what --out-poses would hold
  std::vector<std::string> pose_lines_float_quality;  // the same with quality rounded to a float
  std::size_t frames = 0;
};

// One published frame: its MocapFrame into the recording, its records as the JSONL lines.
class Publisher {
 public:
  Publisher(recording::McapWriter& writer, std::uint16_t channel, LiveRun& run)
      : writer_(writer), channel_(channel), run_(run) {}
  void publish(const FrameOutput& out, const std::vector<TrackRecord>& tracks,
               const std::vector<PoseRecord>& poses) {
    const TimeNs publish_ns = out.stamp_ns + 3'000'000;
    writer_.write(channel_, static_cast<std::uint32_t>(run_.frames++), static_cast<std::uint64_t>(publish_ns),
                  static_cast<std::uint64_t>(publish_ns),
                  dds::encode_sample(estimator_app::to_frame_message(out, publish_ns)));
    for (const auto& track : tracks) run_.track_lines.push_back(to_json_line(track));
    for (PoseRecord pose : poses) {
      run_.pose_lines.push_back(to_json_line(pose));
      // MocapFrame's FrameBody.quality is a float: the one field that cannot come back as the double.
      pose.quality = static_cast<float>(pose.quality);
      run_.pose_lines_float_quality.push_back(to_json_line(pose));
    }
  }

 private:
  recording::McapWriter& writer_;
  std::uint16_t channel_;
  LiveRun& run_;
};

// The offline run, writing the MocapFrames and body descriptions to `mcap`: one frame per processed
// camera frame, or (`fixed_rate_hz` > 0) one per instant of the frame clock, as the live node
// publishes them (docs/frames.md; offline timing model: instants before each frame's stamp).
LiveRun run_and_record(const Scene& scene, double seconds, const fs::path& mcap, int fixed_rate_hz = 0) {
  EstimatorConfig config;
  EstimatorSession session(config);
  session.tracker().set_calibration(scene.calibration());
  session.tracker().set_bodies(scene.body_definitions());
  recording::McapWriter writer(mcap);
  const auto descriptions =
      writer.add_channel(writer.add_schema("panoptes/msg/BodyDescriptions", "ros2idl", ""),
                         export_job::kDescriptionsChannel, "cdr");
  const auto frames = writer.add_channel(writer.add_schema("panoptes/msg/MocapFrame", "ros2idl", ""),
                                         export_job::kFramesChannel, "cdr");
  const auto input = simulate(scene, seconds);
  writer.write(descriptions, 0, 1, 1,
               dds::encode_sample(estimator_app::to_descriptions_message(
                   scene.body_definitions(), 1, "bodies.yaml", input.front().stamp_ns)));
  FrameOutputBuilder builder;
  LiveRun run;
  Publisher publisher(writer, frames, run);
  FrameClock clock(std::max(fixed_rate_hz, 1));
  const estimator::Tracker& tracker = session.tracker();
  for (const FeatureFrame& frame : input) {
    while (fixed_rate_hz > 0 && tracker.last_stamp_ns() != 0) {
      const auto tick = clock.next_due(frame.stamp_ns - 1);
      if (!tick) break;
      const auto tracks = tracker.tracks_at(tick->instant_ns);
      const auto poses = session.poses_at(tick->instant_ns);
      publisher.publish(builder.build_at(tracker, tick->frame_number, tick->instant_ns, {}, poses, tracks),
                        tracks, poses);
    }
    if (session.process(frame) != estimator::FrameOutcome::kProcessed || fixed_rate_hz > 0) continue;
    const auto poses = session.current_poses();
    const auto tracks = tracker.current_tracks();
    publisher.publish(builder.build(tracker, frame, {}, poses, tracks), tracks, poses);
  }
  writer.close();
  return run;
}

// panoptes_export --in-recording DIR/take.mcap --out-tracks --out-poses --out markers.csv, in DIR.
export_job::ExportOptions export_options(const fs::path& dir) {
  export_job::ExportOptions options;
  options.in_recording = (dir / "take.mcap").string();
  options.out_tracks = (dir / "tracks.jsonl").string();
  options.out_poses = (dir / "poses.jsonl").string();
  options.csv = (dir / "markers.csv").string();
  return options;
}

TEST(ExportEquality, RecordingExportEqualsTheRecordsWrittenForTheSameFrames) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/clients.yaml");
  const fs::path dir = fs::temp_directory_path() / "panoptes_export_equality";
  fs::create_directories(dir);
  const LiveRun run = run_and_record(scene, 2.0, dir / "take.mcap");
  ASSERT_GT(run.frames, 500U);
  ASSERT_GT(run.pose_lines.size(), 500U);

  const export_job::ExportOptions options = export_options(dir);
  const export_job::ExportSummary summary = export_job::run_export(options);
  EXPECT_EQ(summary.recorded_frames, run.frames);
  EXPECT_EQ(summary.skipped_records, 0U);

  const auto tracks = lines_of(options.out_tracks);
  ASSERT_EQ(tracks.size(), run.track_lines.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i) differing += tracks[i] != run.track_lines[i] ? 1 : 0;
  EXPECT_EQ(differing, 0U) << "first: " << tracks.front() << " vs " << run.track_lines.front();

  const auto poses = lines_of(options.out_poses);
  ASSERT_EQ(poses.size(), run.pose_lines.size());
  std::size_t poses_differing = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) poses_differing += poses[i] != run.pose_lines[i] ? 1 : 0;
  EXPECT_EQ(poses_differing, 0U) << "first: " << poses.front() << " vs " << run.pose_lines.front();
  // Quality travels as a float: the export recovers the double (seen / markers) from the layout.
  std::size_t quality_rounded = 0;
  for (std::size_t i = 0; i < poses.size(); ++i)
    quality_rounded += run.pose_lines[i] != run.pose_lines_float_quality[i] ? 1 : 0;
  // The clients scene's bodies (head: 4 markers, wand: 3...) are named by their markers.
  std::ifstream csv(options.csv);
  std::string header;
  std::getline(csv, header);
  for (const auto& body : scene.body_definitions())
    for (std::size_t n = 0; n < body.markers.size(); ++n)
      EXPECT_NE(header.find("," + body.name + "_" + std::to_string(n) + "_x,"), std::string::npos)
          << body.name << " " << n << ": " << header.substr(0, 300);
  EXPECT_GT(summary.labelled_markers, 0U);
  std::printf(
      "%zu frames: %zu track records, %zu pose records equal (%zu of them with a quality that a float cannot "
      "hold); "
      "%zu labelled marker points of %zu\n",
      run.frames, tracks.size(), poses.size(), quality_rounded, summary.labelled_markers, summary.markers);
  fs::remove_all(dir);
}

TEST(ExportEquality, FixedRateRecordingExportEqualsItsRecordsOnItsOwnInstants) {
  const Scene scene = Scene::load(std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/clients.yaml");
  const fs::path dir = fs::temp_directory_path() / "panoptes_export_equality_fixed";
  fs::create_directories(dir);
  const LiveRun run = run_and_record(scene, 2.0, dir / "take.mcap", 120);
  ASSERT_GT(run.frames, 200U);
  const export_job::ExportOptions options = export_options(dir);
  const export_job::ExportSummary summary = export_job::run_export(options);
  EXPECT_EQ(summary.rate_hz, 120.0);
  EXPECT_EQ(summary.frames, run.frames) << "one output frame per fixed-rate frame";
  EXPECT_EQ(lines_of(options.out_tracks), run.track_lines);
  EXPECT_EQ(lines_of(options.out_poses), run.pose_lines);
  std::printf("fixed 120 Hz: %zu frames, %zu track and %zu pose records equal, %zu CSV frames\n", run.frames,
              run.track_lines.size(), run.pose_lines.size(), summary.frames);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace panoptes::session
