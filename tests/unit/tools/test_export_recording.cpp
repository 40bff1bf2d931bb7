// SPDX-License-Identifier: Apache-2.0
// panoptes_export --in-recording (docs/recording.md, "Export a recording"): an MCAP recording
// written here by the project's MCAP writer from known MocapFrames is exported and every record
// compared with what was published: track ids, positions, covariances, stamps, labels as
// "<body>_<n>" names, poses; fixed-rate frames keep their instants; bad input is refused or counted.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/dds/decode.h"
#include "panoptes/errors.h"
#include "panoptes/export_job/export_job.h"
#include "panoptes/export_job/recording_source.h"
#include "panoptes/formats/resample.h"
#include "panoptes/jsonl.h"
#include "panoptes/recording/mcap_writer.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::export_job {
namespace {

namespace fs = std::filesystem;
constexpr std::int64_t kT0 = 1'764'000'000'000'000'000;  // a whole second

fs::path temp_path(const std::string& name) {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  return fs::temp_directory_path() / (std::string("export_recording_") + test->name() + "_" + name);
}

msg::FrameMarker marker(std::int64_t id, double x, const std::string& body = "", int index = -1,
                        std::uint8_t status = 1) {
  msg::FrameMarker m;
  m.state().id(id);
  m.state().position({x, 0.25 + 1e-9 * static_cast<double>(id), 1.0 / 3.0});
  m.state().velocity({0.5, -0.125, 0.0});
  m.state().covariance({1e-8, 1e-10, 0.0, 2e-8, 0.0, 3e-8});
  m.state().status(status);
  m.state().cameras(3);
  m.body(body);
  m.body_marker(index);
  return m;
}

msg::FrameBody body(const std::string& name, int id, bool tracked, double x) {
  msg::FrameBody b;
  b.name(name);
  b.id(id);
  b.tracking_valid(tracked);
  if (!tracked) return b;
  b.pose().position({x, 0.5, 0.75});
  b.pose().orientation({0.0, 0.0, std::sqrt(0.5), std::sqrt(0.5)});
  b.linear_velocity({0.1, 0.2, 0.3});
  b.angular_velocity({0.0, 0.0, 1.5});
  b.sigma({1e-4, 2e-4, 3e-4, 1e-3, 2e-3, 3e-3});
  b.quality(0.75F);
  b.mean_marker_error(2e-4);
  b.prediction_horizon_ns(5'000'000);
  b.cameras(4);
  return b;
}

// Frame k: tracks 5 and 6 labelled wand_0 and wand_1 (6 unlabelled in frame 0), loose track 9,
// a tentative track 11; wand tracked, stick not.
msg::MocapFrame frame(std::uint64_t number, std::int64_t stamp_ns, bool fixed_rate) {
  msg::MocapFrame f;
  f.frame_number(number);
  f.stamp_ns(stamp_ns);
  f.publish_ns(stamp_ns + 2'000'000);
  f.source_camera(fixed_rate ? "" : "cam" + std::to_string(number % 2));
  f.source_frame(fixed_rate ? -1 : static_cast<std::int64_t>(number));
  const double x = 0.001 * static_cast<double>(number);
  f.markers().push_back(marker(5, 0.1 + x, "wand", 0));
  f.markers().push_back(number == 1 ? marker(6, 0.2 + x) : marker(6, 0.2 + x, "wand", 1));
  f.markers().push_back(marker(9, 0.3 + x));
  f.markers().push_back(marker(11, 0.4 + x, "", -1, 0));
  f.bodies().push_back(body("wand", 1, true, 1.0 + x));
  f.bodies().push_back(body("stick", 2, false, 0.0));
  return f;
}

msg::BodyDescriptions descriptions() {
  msg::BodyDescriptions d;
  d.stamp_ns(kT0);
  d.generation(1);
  for (const auto& [name, markers] : {std::pair<std::string, int>{"wand", 3}, {"stick", 4}}) {
    msg::BodyDescription b;
    b.name(name);
    b.id(static_cast<std::int32_t>(d.bodies().size()) + 1);
    b.kind("passive");
    b.markers().resize(static_cast<std::size_t>(markers));
    d.bodies().push_back(b);
  }
  return d;
}

struct Recording {
  std::vector<msg::MocapFrame> frames;
  std::vector<std::vector<std::uint8_t>> extra_frame_payloads;  // written after the frames (bad records)
  bool frames_channel = true;
};

void write_recording(const fs::path& path, const Recording& rec) {
  recording::McapWriter writer(path);
  const auto schema = writer.add_schema("panoptes/msg/BodyDescriptions", "ros2idl", "");
  const auto desc = writer.add_channel(schema, kDescriptionsChannel, "cdr");
  writer.write(desc, 0, static_cast<std::uint64_t>(kT0), static_cast<std::uint64_t>(kT0),
               dds::encode_sample(descriptions()));
  if (!rec.frames_channel) return writer.close();
  const auto frames =
      writer.add_channel(writer.add_schema("panoptes/msg/MocapFrame", "ros2idl", ""), kFramesChannel, "cdr");
  std::uint32_t sequence = 0;
  for (const auto& f : rec.frames) {
    const auto t = static_cast<std::uint64_t>(f.publish_ns());
    writer.write(frames, sequence++, t, t, dds::encode_sample(f));
  }
  for (const auto& payload : rec.extra_frame_payloads) {
    const auto t = static_cast<std::uint64_t>(rec.frames.back().publish_ns() + 1);
    writer.write(frames, sequence++, t, t, payload);
  }
  writer.close();
}

Recording per_camera_recording(int count) {
  Recording rec;
  for (int k = 1; k <= count; ++k)
    rec.frames.push_back(frame(static_cast<std::uint64_t>(k), kT0 + k * 3'100'000LL, false));
  return rec;
}

// The records the frames carry, as the live estimator wrote them with --out-tracks / --out-poses.
void expected_records(const Recording& rec, std::vector<TrackRecord>& tracks,
                      std::vector<PoseRecord>& poses) {
  for (const auto& f : rec.frames) {
    for (const auto& m : f.markers()) {
      TrackRecord t;
      t.stamp_ns = f.stamp_ns();
      t.id = m.state().id();
      t.p = Eigen::Vector3d(m.state().position()[0], m.state().position()[1], m.state().position()[2]);
      t.v = Eigen::Vector3d(m.state().velocity()[0], m.state().velocity()[1], m.state().velocity()[2]);
      t.position_covariance = m.state().covariance();
      t.status = static_cast<TrackStatus>(m.state().status());
      t.cameras = m.state().cameras();
      tracks.push_back(t);
    }
    for (const auto& b : f.bodies()) {
      if (!b.tracking_valid()) continue;
      PoseRecord p;
      p.stamp_ns = f.stamp_ns();
      p.body = b.name();
      const auto& q = b.pose().orientation();
      p.p = Eigen::Vector3d(b.pose().position()[0], b.pose().position()[1], b.pose().position()[2]);
      p.q = Eigen::Vector4d(q[0], q[1], q[2], q[3]);
      p.v = Eigen::Vector3d(0.1, 0.2, 0.3);
      p.w = Eigen::Vector3d(0.0, 0.0, 1.5);
      p.horizon_ns = b.prediction_horizon_ns();
      p.quality = b.quality();
      p.cameras = b.cameras();
      p.sigma = b.sigma();
      poses.push_back(p);
    }
  }
}

std::vector<std::string> lines_of(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

TEST(ExportRecording, EveryRecordEqualsWhatWasPublished) {
  const Recording rec = per_camera_recording(4);
  const fs::path mcap = temp_path("take.mcap");
  write_recording(mcap, rec);
  ExportOptions options;
  options.in_recording = mcap.string();
  options.out_tracks = temp_path("tracks.jsonl").string();
  options.out_poses = temp_path("poses.jsonl").string();
  const ExportSummary summary = run_export(options);
  EXPECT_EQ(summary.recorded_frames, 4U);
  EXPECT_EQ(summary.skipped_records, 0U);

  std::vector<TrackRecord> tracks;
  std::vector<PoseRecord> poses;
  expected_records(rec, tracks, poses);
  // The same lines the estimator's JsonlOutputs writes for these records, byte for byte.
  const auto track_lines = lines_of(options.out_tracks);
  ASSERT_EQ(track_lines.size(), tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) EXPECT_EQ(track_lines[i], to_json_line(tracks[i])) << i;
  const auto pose_lines = lines_of(options.out_poses);
  ASSERT_EQ(pose_lines.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(pose_lines[i], to_json_line(poses[i])) << i;
  // Read back, the numbers are the published doubles exactly.
  const auto read = read_tracks(options.out_tracks);
  ASSERT_EQ(read.size(), tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    EXPECT_EQ(read[i].p, tracks[i].p);
    EXPECT_EQ(read[i].stamp_ns, tracks[i].stamp_ns);
    EXPECT_EQ(read[i].position_covariance, tracks[i].position_covariance);
  }
  for (const auto& path : {mcap.string(), options.out_tracks, options.out_poses}) fs::remove(path);
}

TEST(ExportRecording, QualityIsTheFractionOfTheLayoutNotItsFloat) {
  Recording rec = per_camera_recording(2);
  rec.frames[0].bodies()[0].quality(static_cast<float>(2.0 / 3.0));  // the wand has 3 markers
  rec.frames[1].bodies()[0].quality(0.7F);                           // no fraction of 3: kept as sent
  const fs::path mcap = temp_path("take.mcap");
  write_recording(mcap, rec);
  RecordingRecordSource source(mcap);
  const ExportRecords records = source.read();
  ASSERT_EQ(records.poses.size(), 2U);
  EXPECT_EQ(records.poses[0].quality, 2.0 / 3.0);  // what the estimator wrote to --out-poses
  EXPECT_EQ(records.poses[1].quality, static_cast<double>(0.7F));
  fs::remove(mcap);
}

TEST(ExportRecording, LabelledMarkersAreNamedAfterTheirBodyMarker) {
  const Recording rec = per_camera_recording(3);
  const fs::path mcap = temp_path("take.mcap");
  write_recording(mcap, rec);
  RecordingRecordSource source(mcap);
  const ExportRecords records = source.read();
  ASSERT_EQ(records.labels.size(), records.tracks.size());
  EXPECT_EQ(records.labels[0].body, "wand");
  EXPECT_EQ(records.labels[1].body, "");  // track 6 unlabelled in frame 1
  EXPECT_EQ(records.labels[5].body, "wand");
  EXPECT_EQ(records.labels[5].marker, 1);
  EXPECT_EQ(records.body_order, (std::vector<std::string>{"wand", "stick"}));

  ExportOptions options;
  options.in_recording = mcap.string();
  options.csv = temp_path("markers.csv").string();
  options.rate_hz = 1e9 / 3'100'000.0;  // the frames' spacing: every sample is on an update
  options.rate_given = true;
  const ExportSummary summary = run_export(options);
  EXPECT_EQ(summary.labelled_markers, 2U);
  const auto lines = lines_of(options.csv);
  ASSERT_EQ(lines.size(), 4U);  // header + 3 frames
  const std::vector<std::string> header = fields_of(lines[0]);
  // Track 5 is always labelled (no track_5 column), 11 is tentative (left out by default).
  const std::vector<std::string> names = {"wand_0", "wand_1", "track_6", "track_9", "wand"};
  ASSERT_EQ(header.size(), 2 + 3 * names.size()) << lines[0];
  for (std::size_t m = 0; m < names.size(); ++m) EXPECT_EQ(header[2 + 3 * m], names[m] + "_x") << lines[0];
  // Frame 1: track 6 unlabelled (track_6 set, wand_1 empty); frames 2, 3: the other way round.
  const auto row1 = fields_of(lines[1]);
  const auto row3 = fields_of(lines[3]);
  EXPECT_EQ(row1[2], "0.1010000");   // wand_0 x, frame 1
  EXPECT_EQ(row1[5], "");            // wand_1
  EXPECT_EQ(row1[8], "0.2010000");   // track_6
  EXPECT_EQ(row3[5], "0.2030000");   // wand_1, frame 3
  EXPECT_EQ(row3[8], "");            // track_6
  EXPECT_EQ(row3[11], "0.3030000");  // track_9
  EXPECT_EQ(row3[14], "1.0030000");  // the wand's origin
  fs::remove(mcap);
  fs::remove(options.csv);
}

TEST(ExportRecording, FixedRateFramesKeepTheirInstantsAndRate) {
  Recording rec;
  // 100 Hz instants s + k * 10 ms, frame numbers 1..6 with number 4 skipped live.
  for (std::uint64_t n : {1, 2, 3, 5, 6})
    rec.frames.push_back(frame(n, kT0 + static_cast<std::int64_t>(n) * 10'000'000, true));
  const fs::path mcap = temp_path("fixed.mcap");
  write_recording(mcap, rec);
  ExportOptions options;
  options.in_recording = mcap.string();
  options.csv = temp_path("fixed.csv").string();
  const ExportSummary summary = run_export(options);
  EXPECT_EQ(summary.rate_hz, 100.0);
  EXPECT_EQ(summary.frames, 6U);  // frame numbers 1..6: one row each, the skipped one included
  const auto lines = lines_of(options.csv);
  ASSERT_EQ(lines.size(), 7U);
  for (std::size_t row = 1; row <= 6; ++row) {
    const auto fields = fields_of(lines[row]);
    char expected[32];
    std::snprintf(expected, sizeof expected, "%.6f", 0.01 * static_cast<double>(row - 1));
    EXPECT_EQ(fields[1], expected) << lines[row];  // time_s
    if (row == 4) continue;                        // interpolated between its neighbours
    std::snprintf(expected, sizeof expected, "%.7f", 0.1 + 0.001 * static_cast<double>(row));
    EXPECT_EQ(fields[2], expected) << lines[row];  // wand_0 x at exactly the recorded instant
  }
  fs::remove(mcap);
  fs::remove(options.csv);
}

TEST(ExportRecording, GridOfTheFixedRateClockIsExact) {
  // 240 Hz: periods of 4 166 666 or 4 166 667 ns (docs/frames.md), starting mid-second.
  const SampleGrid grid = fixed_rate_grid(kT0 + 4'166'666, kT0 + 1'000'000'000 + 8'333'333, 240);
  ASSERT_EQ(grid.count, 242U);  // periods 1..239 of the first second, 0..2 of the next
  EXPECT_EQ(grid.times.front(), kT0 + 4'166'666);
  EXPECT_EQ(grid.times[1], kT0 + 8'333'333);
  EXPECT_EQ(grid.times[238], kT0 + 995'833'333);  // floor(239 * 10^9 / 240)
  EXPECT_EQ(grid.times[239], kT0 + 1'000'000'000);
  EXPECT_EQ(grid.times.back(), kT0 + 1'000'000'000 + 8'333'333);
  EXPECT_THROW(fixed_rate_grid(kT0, kT0 + 1, 0), std::invalid_argument);
}

TEST(ExportRecording, BadRecordsAreCountedAndSkipped) {
  Recording rec = per_camera_recording(3);
  rec.extra_frame_payloads.push_back({0x00, 0x01, 0x00, 0x00, 0xff, 0xff, 0xff, 0x7f});  // an absurd length
  msg::MocapFrame mislabelled = frame(4, kT0 + 20'000'000, false);
  mislabelled.markers()[0].body_marker(7);  // the wand has 3 markers
  rec.extra_frame_payloads.push_back(dds::encode_sample(mislabelled));
  const fs::path mcap = temp_path("bad.mcap");
  write_recording(mcap, rec);
  RecordingRecordSource source(mcap);
  const ExportRecords records = source.read();
  EXPECT_EQ(source.contents().frames, 4U);
  ASSERT_EQ(records.skipped.size(), 2U);
  EXPECT_NE(records.skipped[0].find(mcap.string() + ": message "), std::string::npos) << records.skipped[0];
  EXPECT_NE(records.skipped[0].find("cannot decode"), std::string::npos) << records.skipped[0];
  EXPECT_NE(records.skipped[1].find("wand_7"), std::string::npos) << records.skipped[1];
  EXPECT_EQ(records.labels[12].body, "");  // the label outside the layout is dropped
  fs::remove(mcap);
}

TEST(ExportRecording, TruncatedRecordingKeepsItsCompleteChunks) {
  Recording rec = per_camera_recording(50);
  const fs::path mcap = temp_path("cut.mcap");
  {
    recording::McapWriterOptions small;
    small.chunk_size = 2048;  // several chunks
    recording::McapWriter writer(mcap, small);
    const auto frames = writer.add_channel(writer.add_schema("panoptes/msg/MocapFrame", "ros2idl", ""),
                                           kFramesChannel, "cdr");
    std::uint32_t sequence = 0;
    for (const auto& f : rec.frames)
      writer.write(frames, sequence++, static_cast<std::uint64_t>(f.stamp_ns()),
                   static_cast<std::uint64_t>(f.stamp_ns()), dds::encode_sample(f));
    writer.close();
  }
  fs::resize_file(mcap, fs::file_size(mcap) * 2 / 3);
  RecordingRecordSource source(mcap);
  const ExportRecords records = source.read();
  EXPECT_GT(source.contents().frames, 0U);
  EXPECT_LT(source.contents().frames, 50U);
  EXPECT_FALSE(records.skipped.empty());
  for (const auto& problem : records.skipped) EXPECT_EQ(problem.rfind(mcap.string(), 0), 0U) << problem;
  fs::remove(mcap);
}

TEST(ExportRecording, NotARecordingOrNoFramesIsRefusedNamingTheFile) {
  const fs::path text = temp_path("notes.mcap");
  { std::ofstream(text) << "not an mcap file\n"; }
  RecordingRecordSource not_mcap(text);
  try {
    not_mcap.read();
    ADD_FAILURE() << "read a text file";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(text.string()), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("not an MCAP file"), std::string::npos) << error.what();
  }
  const fs::path no_frames = temp_path("no_frames.mcap");
  Recording rec;
  rec.frames_channel = false;
  write_recording(no_frames, rec);
  RecordingRecordSource source(no_frames);
  try {
    source.read();
    ADD_FAILURE() << "exported a recording without frames";
  } catch (const ConfigError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find(no_frames.string()), std::string::npos) << what;
    EXPECT_NE(what.find("no /panoptes/frames channel"), std::string::npos) << what;
    EXPECT_NE(what.find("/panoptes/body_descriptions"), std::string::npos) << what;
  }
  fs::remove(text);
  fs::remove(no_frames);
}

TEST(ExportRecording, OutputsByExtensionAndTheirNeeds) {
  ExportOptions options;
  EXPECT_TRUE(set_output(options, "take.C3D"));
  EXPECT_TRUE(set_output(options, "take.trc"));
  EXPECT_TRUE(set_output(options, "take.csv"));
  EXPECT_FALSE(set_output(options, "take.mcap"));
  EXPECT_EQ(options.c3d, "take.C3D");
  EXPECT_TRUE(set_poses_output(options, "poses.jsonl"));
  EXPECT_TRUE(set_poses_output(options, "bodies.csv"));
  EXPECT_FALSE(set_poses_output(options, "poses.c3d"));
  EXPECT_EQ(options.out_poses, "poses.jsonl");
  EXPECT_EQ(options.bodies_csv, "bodies.csv");
  options.in_recording = "take.mcap";
  EXPECT_FALSE(find_problem(options).has_value());
  options.tracks = "tracks.jsonl";
  ASSERT_TRUE(find_problem(options).has_value());
  EXPECT_EQ(find_problem(options)->option, "input");
  options.in_recording.clear();
  options.out_poses.clear();
  options.out_tracks = "t.jsonl";
  ASSERT_TRUE(find_problem(options).has_value());
  EXPECT_EQ(find_problem(options)->option, "--out-tracks");
}

}  // namespace
}  // namespace panoptes::export_job
