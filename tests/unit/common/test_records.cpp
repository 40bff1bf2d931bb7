// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/jsonl.h"
#include "panoptes/records.h"
#include "temp_dir.h"

namespace panoptes {
namespace {

// Above 2^53, so a stamp that passed through a double would lose its last digits.
constexpr TimeNs kStamp = 1700000000123456789;

FeatureFrame sample_frame() {
  FeatureFrame frame;
  frame.camera_id = "cam-\"7\"\n";  // quotes and a newline must be escaped, not break the line
  frame.frame = 123456789012;
  frame.stamp_ns = kStamp;
  frame.arrival_ns = kStamp + 987654;
  frame.processing_ns = 345678;
  frame.blobs.push_back({0.1, 1.0 / 3.0, 17, 4321.125, 255, 0.7, -0.2, 1e-300});
  frame.blobs.push_back({1279.4999999999998, -0.5, 1, 1, 65535, 0, 0, 0});
  return frame;
}

void expect_same(const FeatureFrame& a, const FeatureFrame& b) {
  EXPECT_EQ(a.camera_id, b.camera_id);
  EXPECT_EQ(a.frame, b.frame);
  EXPECT_EQ(a.stamp_ns, b.stamp_ns);
  EXPECT_EQ(a.arrival_ns, b.arrival_ns);
  EXPECT_EQ(a.processing_ns, b.processing_ns);
  EXPECT_EQ(a.received_ns, b.received_ns);
  ASSERT_EQ(a.blobs.size(), b.blobs.size());
  for (std::size_t i = 0; i < a.blobs.size(); ++i) {
    EXPECT_EQ(a.blobs[i].x, b.blobs[i].x);
    EXPECT_EQ(a.blobs[i].y, b.blobs[i].y);
    EXPECT_EQ(a.blobs[i].area, b.blobs[i].area);
    EXPECT_EQ(a.blobs[i].sum, b.blobs[i].sum);
    EXPECT_EQ(a.blobs[i].peak, b.blobs[i].peak);
    EXPECT_EQ(a.blobs[i].m20, b.blobs[i].m20);
    EXPECT_EQ(a.blobs[i].m11, b.blobs[i].m11);
    EXPECT_EQ(a.blobs[i].m02, b.blobs[i].m02);
    EXPECT_EQ(a.blobs[i].x0, b.blobs[i].x0);
    EXPECT_EQ(a.blobs[i].y0, b.blobs[i].y0);
    EXPECT_EQ(a.blobs[i].x1, b.blobs[i].x1);
    EXPECT_EQ(a.blobs[i].y1, b.blobs[i].y1);
  }
}

struct BadLine {
  std::string line;
  std::string expected_error;  // a substring of the error
};

// The same line with a space after every ':' and ',' outside strings: valid JSON of the same values
// that the compact reader (jsonl_fast.h) does not take, so the full parser reads it.
std::string spaced(const std::string& line) {
  std::string out;
  bool in_string = false;
  for (char c : line) {
    out += c;
    if (c == '"') in_string = !in_string;
    if (!in_string && (c == ':' || c == ',')) out += ' ';
  }
  return out;
}

TEST(Records, FeatureFrameRoundTripIsExact) {
  const FeatureFrame original = sample_frame();
  const std::string line = to_json_line(original);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  EXPECT_NE(line.find("\"stamp_ns\":1700000000123456789"), std::string::npos) << line;
  const Parsed<FeatureFrame> parsed = parse_feature_frame(line);
  ASSERT_TRUE(parsed.value.has_value()) << parsed.error;
  EXPECT_TRUE(parsed.error.empty());
  expect_same(original, *parsed.value);
}

TEST(Records, FeatureFrameReceivedStampIsOptional) {
  FeatureFrame frame = sample_frame();
  const std::string without = to_json_line(frame);
  // Unknown (0): the key is left out, so files written before it existed are unchanged.
  EXPECT_EQ(without.find("received_ns"), std::string::npos) << without;
  ASSERT_TRUE(parse_feature_frame(without).value.has_value());
  EXPECT_EQ(parse_feature_frame(without).value->received_ns, 0);

  frame.received_ns = kStamp + 4'000'001;
  const std::string with = to_json_line(frame);
  EXPECT_NE(with.find("\"received_ns\":1700000000127456790"), std::string::npos) << with;
  const Parsed<FeatureFrame> parsed = parse_feature_frame(with);
  ASSERT_TRUE(parsed.value.has_value()) << parsed.error;
  expect_same(frame, *parsed.value);

  const auto bad = parse_feature_frame(
      R"({"camera_id": "cam0", "frame": 3, "stamp_ns": 1, "received_ns": "soon", "blobs": []})");
  EXPECT_FALSE(bad.value.has_value());
  EXPECT_NE(bad.error.find("received_ns"), std::string::npos) << bad.error;
}

// Lines as this library writes them are read by a fast path, anything else by the JSON library:
// both must read the same values, extreme doubles included.
TEST(Records, CompactAndSpacedLinesReadTheSame) {
  FeatureFrame frame = sample_frame();
  frame.camera_id = "cam7";  // no escapes: the compact writer and reader
  frame.received_ns = kStamp + 5;
  frame.blobs.push_back({5e-324, 1.7976931348623157e308, -0.0, 1e21, -2147483647, 1e-7, 123456.0, 0.1, -3, 0,
                         2147483647, -2147483647});
  const std::string line = to_json_line(frame);
  EXPECT_NE(line.find("\"camera_id\":\"cam7\",\"frame\":123456789012,"), std::string::npos) << line;
  const auto fast = parse_feature_frame(line);
  const auto full = parse_feature_frame(spaced(line));
  ASSERT_TRUE(fast.value.has_value()) << fast.error;
  ASSERT_TRUE(full.value.has_value()) << full.error << "\n" << spaced(line);
  expect_same(frame, *fast.value);
  expect_same(*full.value, *fast.value);
  EXPECT_TRUE(std::signbit(fast.value->blobs[2].area));

  TrackRecord track;
  track.stamp_ns = kStamp;
  track.id = -7;
  track.p = Eigen::Vector3d(0.5999594280639859, -1e-320, 4.0);
  track.v = Eigen::Vector3d(1e300, -0.0, 2.0 / 3.0);
  track.position_covariance = {7.103717836190519e-05, 0, 1, 1e16, 1e-5, 123.25};
  track.status = TrackStatus::kTentative;
  track.cameras = 11;
  const std::string track_line = to_json_line(track);
  // The shortest text that reads back to the double (the JSON library wrote 0.5999594280639859 for
  // it); integral doubles keep a fraction, as the JSON library writes them.
  EXPECT_NE(track_line.find("\"p\":[0.599959428063986,-1e-320,4.0]"), std::string::npos) << track_line;
  const auto fast_track = parse_track(track_line);
  const auto full_track = parse_track(spaced(track_line));
  ASSERT_TRUE(fast_track.value.has_value()) << fast_track.error;
  ASSERT_TRUE(full_track.value.has_value()) << full_track.error;
  for (const TrackRecord* read : {&*fast_track.value, &*full_track.value}) {
    EXPECT_EQ(read->stamp_ns, track.stamp_ns);
    EXPECT_EQ(read->id, track.id);
    EXPECT_EQ(read->p, track.p);
    EXPECT_EQ(read->v, track.v);
    EXPECT_EQ(read->position_covariance, track.position_covariance);
    EXPECT_EQ(read->status, track.status);
    EXPECT_EQ(read->cameras, track.cameras);
  }
}

// Lines one character away from the compact shape are refused with the JSON library's reasons,
// never read by the fast path with another meaning.
TEST(Records, NearlyCompactBadLinesGetTheFullParsersErrors) {
  TrackRecord track;
  track.stamp_ns = 5;
  track.id = 1;
  track.cameras = 2;
  const std::string good = to_json_line(track);
  ASSERT_TRUE(parse_track(good).value.has_value());
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string line = good;
    const auto at = line.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? line : line.replace(at, from.size(), to);
  };
  const std::vector<BadLine> cases = {
      {replaced("\"cameras\":2", "\"cameras\":2.5"), "cameras: expected an integer"},
      {replaced("\"cameras\":2", "\"cameras\":99999999999"), "cameras: integer out of range"},
      {replaced("\"id\":1", "\"id\":01"), "not valid JSON"},
      {replaced("\"stamp_ns\":5", "\"stamp_ns\":5e0"), "stamp_ns: expected an integer"},
      {replaced("\"stamp_ns\":5", "\"stamp_ns\":99999999999999999999"), "stamp_ns: "},
      {replaced("\"p\":[0.0", "\"p\":[0."), "not valid JSON"},
      {replaced("\"p\":[0.0", "\"p\":[.5"), "not valid JSON"},
      {replaced("\"p\":[0.0", "\"p\":[inf"), "not valid JSON"},
      {replaced("\"p\":[0.0", "\"p\":[null"), "p[0]: expected a number"},
      {replaced("\"confirmed\"", "\"lost\""), "status: expected tentative, confirmed or coasting"},
      {good + "x", "not valid JSON"},
  };
  for (const BadLine& bad : cases) {
    const auto parsed = parse_track(bad.line);
    EXPECT_FALSE(parsed.value.has_value()) << bad.line;
    EXPECT_NE(parsed.error.find(bad.expected_error), std::string::npos) << bad.line << "\n" << parsed.error;
  }
  FeatureFrame frame;
  frame.camera_id = "c";
  frame.blobs.push_back({1, 2, 3, 4, 5, 6, 7, 8, 0, 0, 2, 2});
  const std::string frame_line = to_json_line(frame);
  std::string bad_peak = frame_line;
  bad_peak.replace(bad_peak.find("\"peak\":5"), 8, "\"peak\":5.5");
  const auto parsed = parse_feature_frame(bad_peak);
  EXPECT_FALSE(parsed.value.has_value()) << bad_peak;
  EXPECT_NE(parsed.error.find("blobs[0].peak: expected an integer"), std::string::npos) << parsed.error;
}

// NaN and infinities have no JSON number: written as null (as the JSON library writes them) and
// refused when read, naming the field.
TEST(Records, NonFiniteNumbersAreWrittenAsNullAndRefusedOnReading) {
  TrackRecord track;
  track.v =
      Eigen::Vector3d(0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity());
  const std::string line = to_json_line(track);
  EXPECT_NE(line.find("\"v\":[0.0,null,null]"), std::string::npos) << line;
  const auto parsed = parse_track(line);
  EXPECT_FALSE(parsed.value.has_value());
  EXPECT_NE(parsed.error.find("v[1]: expected a number"), std::string::npos) << parsed.error;
}

TEST(Records, TrackRoundTripIsExact) {
  TrackRecord original;
  original.stamp_ns = kStamp;
  original.id = 42;
  original.p = Eigen::Vector3d(0.1, -2.0 / 3.0, 1e-17);
  original.v = Eigen::Vector3d(1e10, -0.0, 3.0);
  original.position_covariance = {1e-6, 2e-7, -3e-7, 4e-6, 5e-8, 6e-6};
  original.status = TrackStatus::kCoasting;
  original.cameras = 5;
  const Parsed<TrackRecord> parsed = parse_track(to_json_line(original));
  ASSERT_TRUE(parsed.value.has_value()) << parsed.error;
  const TrackRecord& track = *parsed.value;
  EXPECT_EQ(track.stamp_ns, kStamp);
  EXPECT_EQ(track.id, 42);
  EXPECT_EQ(track.p, original.p);
  EXPECT_EQ(track.v, original.v);
  EXPECT_EQ(track.position_covariance, original.position_covariance);
  EXPECT_EQ(track.status, TrackStatus::kCoasting);
  EXPECT_EQ(track.cameras, 5);
}

TEST(Records, TrackStatusNames) {
  for (TrackStatus status : {TrackStatus::kTentative, TrackStatus::kConfirmed, TrackStatus::kCoasting}) {
    TrackRecord track;
    track.status = status;
    const std::string line = to_json_line(track);
    EXPECT_NE(line.find("\"status\":\"" + std::string(to_string(status)) + "\""), std::string::npos) << line;
    EXPECT_EQ(parse_track(line).value->status, status);
  }
  EXPECT_EQ(to_string(TrackStatus::kTentative), "tentative");
  EXPECT_EQ(to_string(TrackStatus::kConfirmed), "confirmed");
  EXPECT_EQ(to_string(TrackStatus::kCoasting), "coasting");
}

TEST(Records, PoseRoundTripIsExact) {
  PoseRecord original;
  original.stamp_ns = kStamp;
  original.body = "wand";
  original.p = Eigen::Vector3d(0.5, 0.25, 1.0 / 7.0);
  original.q = Eigen::Vector4d(0.1, 0.2, 0.3, std::sqrt(1 - 0.14));
  const std::string line = to_json_line(original);
  EXPECT_NE(line.find("\"q\":[0.1,0.2,0.3,"), std::string::npos) << line;  // x, y, z, w order
  const Parsed<PoseRecord> parsed = parse_pose(line);
  ASSERT_TRUE(parsed.value.has_value()) << parsed.error;
  EXPECT_EQ(parsed.value->stamp_ns, kStamp);
  EXPECT_EQ(parsed.value->body, "wand");
  EXPECT_EQ(parsed.value->p, original.p);
  EXPECT_EQ(parsed.value->q, original.q);
}

TEST(Records, ContractExamplesParseWithDefaultsAndExtraKeys) {
  const auto frame = parse_feature_frame(
      R"({"camera_id": "cam0", "frame": 3, "stamp_ns": 1700000000000000001, "extra": {"a": 1},)"
      R"( "blobs": [{"x": 10.5, "y": 20.25, "area": 12, "sum": 3000, "peak": 250}, {"x": 1, "y": 2}]})");
  ASSERT_TRUE(frame.value.has_value()) << frame.error;
  EXPECT_EQ(frame.value->stamp_ns, 1700000000000000001);
  EXPECT_EQ(frame.value->arrival_ns, 0);
  ASSERT_EQ(frame.value->blobs.size(), 2u);
  EXPECT_EQ(frame.value->blobs[0].peak, 250);
  EXPECT_EQ(frame.value->blobs[1].area, 0.0);
  EXPECT_EQ(frame.value->blobs[1].peak, 0);

  const auto track =
      parse_track(R"({"stamp_ns": 5, "id": 1, "p": [1, 2, 3], "v": [0, 0, 0.5], "note": "x"})");
  ASSERT_TRUE(track.value.has_value()) << track.error;
  EXPECT_EQ(track.value->p, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(track.value->status, TrackStatus::kConfirmed);

  const auto pose =
      parse_pose(R"({"stamp_ns": 5, "body": "wand", "p": [1, 2, 3], "q": [0, 0, 0, 1], "quality": 1})");
  ASSERT_TRUE(pose.value.has_value()) << pose.error;
  EXPECT_EQ(pose.value->q, Eigen::Vector4d(0, 0, 0, 1));
}

TEST(Records, MalformedFeatureFramesGiveErrorsNotExceptions) {
  const std::vector<BadLine> cases = {
      {"this is not json", "not valid JSON"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1)", "not valid JSON"},
      {"[1, 2, 3]", "expected a JSON object"},
      {R"({"camera_id": "c", "frame": 1, "blobs": []})", "stamp_ns: missing"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1.7e18, "blobs": []})", "stamp_ns: expected an integer"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": "17", "blobs": []})", "stamp_ns: expected an integer"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 18446744073709551615, "blobs": []})",
       "stamp_ns: integer out of range"},
      {R"({"camera_id": 7, "frame": 1, "stamp_ns": 1, "blobs": []})", "camera_id: expected a string"},
      {R"({"camera_id": "c", "stamp_ns": 1, "blobs": []})", "frame: missing"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1})", "blobs: missing"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1, "blobs": {}})", "blobs: expected a list"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1, "blobs": [{"x": 1, "y": 1}, 5]})",
       "blobs[1]: expected an object"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1, "blobs": [{"x": 1, "y": 1}, {"x": 1, "y": 1},)"
       R"( {"x": 1, "y": 1}, {"x": "1", "y": 1}]})",
       "blobs[3].x: expected a number"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1, "blobs": [{"x": 1}]})", "blobs[0].y: missing"},
      {R"({"camera_id": "c", "frame": 1, "stamp_ns": 1, "blobs": [{"x": 1, "y": 2, "peak": 2.5}]})",
       "blobs[0].peak: expected an integer"},
      {"", "not valid JSON"},
  };
  for (const BadLine& bad : cases) {
    Parsed<FeatureFrame> parsed;
    ASSERT_NO_THROW(parsed = parse_feature_frame(bad.line)) << bad.line;
    EXPECT_FALSE(parsed.value.has_value()) << bad.line;
    EXPECT_NE(parsed.error.find(bad.expected_error), std::string::npos)
        << "line: " << bad.line << "\nerror: " << parsed.error;
  }
}

TEST(Records, MalformedTracksAndPosesGiveErrors) {
  const std::vector<BadLine> tracks = {
      {R"({"id": 1, "p": [1, 2, 3], "v": [0, 0, 0]})", "stamp_ns: missing"},
      {R"({"stamp_ns": 1, "p": [1, 2, 3], "v": [0, 0, 0]})", "id: missing"},
      {R"({"stamp_ns": 1, "id": 1, "p": [1, 2], "v": [0, 0, 0]})", "p: expected a list of 3 numbers, got 2"},
      {R"({"stamp_ns": 1, "id": 1, "p": [1, 2, 3], "v": [0, "a", 0]})", "v[1]: expected a number"},
      {R"({"stamp_ns": 1, "id": 1, "p": [1, 2, 3], "v": [0, 0, 0], "cov": [1]})",
       "cov: expected a list of 6 numbers"},
      {R"({"stamp_ns": 1, "id": 1, "p": [1, 2, 3], "v": [0, 0, 0], "status": "lost"})",
       "status: expected tentative, confirmed or coasting"},
      {R"({"stamp_ns": 1, "id": 1, "p": [1, 2, 3], "v": [0, 0, 0], "cameras": 1.5})",
       "cameras: expected an integer"},
  };
  for (const BadLine& bad : tracks) {
    Parsed<TrackRecord> parsed;
    ASSERT_NO_THROW(parsed = parse_track(bad.line)) << bad.line;
    EXPECT_FALSE(parsed.value.has_value()) << bad.line;
    EXPECT_NE(parsed.error.find(bad.expected_error), std::string::npos) << bad.line << "\n" << parsed.error;
  }
  const std::vector<BadLine> poses = {
      {R"({"body": "w", "p": [1, 2, 3], "q": [0, 0, 0, 1]})", "stamp_ns: missing"},
      {R"({"stamp_ns": 1, "p": [1, 2, 3], "q": [0, 0, 0, 1]})", "body: missing"},
      {R"({"stamp_ns": 1, "body": "w", "p": [1, 2, 3], "q": [0, 0, 1]})",
       "q: expected a list of 4 numbers, got 3"},
      {R"({"stamp_ns": 1.5, "body": "w", "p": [1, 2, 3], "q": [0, 0, 0, 1]})",
       "stamp_ns: expected an integer"},
  };
  for (const BadLine& bad : poses) {
    Parsed<PoseRecord> parsed;
    ASSERT_NO_THROW(parsed = parse_pose(bad.line)) << bad.line;
    EXPECT_FALSE(parsed.value.has_value()) << bad.line;
    EXPECT_NE(parsed.error.find(bad.expected_error), std::string::npos) << bad.line << "\n" << parsed.error;
  }
}

TEST(Records, ReadFeatureFramesSkipsBadLinesAndReportsFileLine) {
  testing::TempDir dir;
  const auto path = dir.file("features.jsonl");
  {
    std::ofstream out(path);
    out << to_json_line(sample_frame()) << "\n";  // line 1
    out << "garbage\n";                           // line 2
    out << "\n";                                  // line 3: blank, skipped
    out << R"({"camera_id": "c", "frame": 1, "blobs": []})"
        << "\n";     // line 4: no stamp
    out << "   \n";  // line 5: blank
    out << R"({"camera_id": "c", "frame": 2, "stamp_ns": 9, "blobs": []})"
        << "\r\n";  // line 6: CRLF
  }
  std::vector<std::string> errors;
  const std::vector<FeatureFrame> frames = read_feature_frames(path, &errors);
  ASSERT_EQ(frames.size(), 2u);
  expect_same(frames[0], sample_frame());
  EXPECT_EQ(frames[1].stamp_ns, 9);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].rfind(path.string() + ":2: ", 0), 0u) << errors[0];
  EXPECT_EQ(errors[1], path.string() + ":4: stamp_ns: missing");
  // Without an error sink the good lines still come back.
  EXPECT_EQ(read_feature_frames(path).size(), 2u);
}

TEST(Records, WriterAndReadersRoundTripFiles) {
  testing::TempDir dir;
  TrackRecord track;
  track.stamp_ns = kStamp;
  track.id = 3;
  PoseRecord pose;
  pose.stamp_ns = kStamp + 1;
  pose.body = "wand";
  {
    JsonlWriter tracks(dir.file("tracks.jsonl"));
    tracks.write(track);
    track.id = 4;
    tracks.write(track);
    tracks.flush();
    JsonlWriter poses(dir.file("poses.jsonl"));
    poses.write(pose);
    JsonlWriter frames(dir.file("frames.jsonl"));
    frames.write(sample_frame());
  }
  std::vector<std::string> errors;
  const auto tracks = read_tracks(dir.file("tracks.jsonl"), &errors);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(tracks[0].id, 3);
  EXPECT_EQ(tracks[1].id, 4);
  EXPECT_EQ(tracks[1].stamp_ns, kStamp);
  const auto poses = read_poses(dir.file("poses.jsonl"), &errors);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].stamp_ns, kStamp + 1);
  const auto frames = read_feature_frames(dir.file("frames.jsonl"), &errors);
  ASSERT_EQ(frames.size(), 1u);
  expect_same(frames[0], sample_frame());
  EXPECT_TRUE(errors.empty());

  // A second writer on the same path starts the file afresh.
  {
    JsonlWriter again(dir.file("tracks.jsonl"));
    again.write(track);
  }
  EXPECT_EQ(read_tracks(dir.file("tracks.jsonl")).size(), 1u);
}

TEST(Records, MissingFilesThrowNamingTheFile) {
  const std::string missing = "/nonexistent/dir/tracks.jsonl";
  for (int reader = 0; reader < 3; ++reader) {
    try {
      if (reader == 0) read_feature_frames(missing);
      if (reader == 1) read_tracks(missing);
      if (reader == 2) read_poses(missing);
      ADD_FAILURE() << "reader " << reader << " did not throw";
    } catch (const std::runtime_error& error) {
      EXPECT_EQ(std::string(error.what()), missing + ": cannot open");
    }
  }
  try {
    JsonlWriter writer(missing);
    ADD_FAILURE() << "writer did not throw";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace panoptes
