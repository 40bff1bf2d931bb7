// SPDX-License-Identifier: Apache-2.0
// The client's conversion of rt/panoptes/frames and rt/panoptes/body_descriptions samples, the
// checks that reject malformed ones, the latency figures and the frame-number bookkeeping.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "conversion.h"
#include "frame_sequence.h"
#include "panoptes/frame_grid.h"

namespace panoptes::client::detail {
namespace {

msg::FrameBody tracked_body(const std::string& name, int id) {
  msg::FrameBody body;
  body.name(name);
  body.id(id);
  body.tracking_valid(true);
  body.pose().position({0.1, 0.2, 0.30000000000000004});
  body.pose().orientation({0.0, 0.0, std::sqrt(0.5), std::sqrt(0.5)});
  body.linear_velocity({1, 2, 3});
  body.angular_velocity({0.1, 0.2, 0.3});
  body.sigma({1e-4, 2e-4, 3e-4, 1e-3, 2e-3, 3e-3});
  body.quality(0.75F);
  body.mean_marker_error(0.0004);
  body.prediction_horizon_ns(5'000'000);
  body.cameras(4);
  return body;
}

msg::FrameMarker marker(long long id, const std::string& body, int index) {
  msg::FrameMarker m;
  m.state().id(id);
  m.state().position({1.0 / 3.0, 2, 3});
  m.state().velocity({0, 0, 0.5});
  m.state().covariance({1e-8, 0, 0, 1e-8, 0, 1e-8});
  m.state().status(index == 99 ? 2 : 1);
  m.state().cameras(3);
  m.body(body);
  m.body_marker(index);
  return m;
}

msg::MocapFrame good_frame() {
  msg::MocapFrame f;
  f.frame_number(42);
  f.stamp_ns(1'000'000'000);
  f.publish_ns(1'004'000'000);
  f.source_camera("cam0");
  f.source_frame(7);
  f.stages().feature_publish_ns(1'001'000'000);
  f.stages().received_ns(1'001'500'000);
  f.stages().dequeued_ns(1'002'500'000);
  f.stages().updated_ns(1'003'000'000);
  f.bodies().push_back(tracked_body("head", 1));
  msg::FrameBody lost;
  lost.name("tool");
  lost.id(2);
  f.bodies().push_back(lost);
  f.markers().push_back(marker(5, "head", 0));
  f.markers().push_back(marker(9, "", -1));
  f.markers().push_back(marker(11, "", 99));  // coasting, unlabelled
  return f;
}

TEST(Conversion, CopiesEveryFieldExactly) {
  std::string error;
  const auto frame = to_frame(good_frame(), 1'005'000'000, error);
  ASSERT_TRUE(frame) << error;
  EXPECT_EQ(frame->frame_number, 42U);
  EXPECT_EQ(frame->stamp_ns, 1'000'000'000);
  EXPECT_EQ(frame->publish_ns, 1'004'000'000);
  EXPECT_EQ(frame->receive_ns, 1'005'000'000);
  EXPECT_EQ(frame->source_camera, "cam0");
  EXPECT_EQ(frame->source_frame, 7);
  ASSERT_EQ(frame->bodies.size(), 2U);
  const RigidBody& head = frame->bodies[0];
  EXPECT_EQ(head.name, "head");
  EXPECT_EQ(head.id, 1);
  EXPECT_TRUE(head.tracking_valid);
  EXPECT_EQ(head.position[2], 0.30000000000000004);  // bit for bit, no float detour
  EXPECT_EQ(head.orientation[3], std::sqrt(0.5));
  EXPECT_EQ(head.linear_velocity[1], 2.0);
  EXPECT_EQ(head.angular_velocity[2], 0.3);
  EXPECT_EQ(head.sigma[5], 3e-3);
  EXPECT_FLOAT_EQ(head.quality, 0.75);
  EXPECT_EQ(head.mean_marker_error, 0.0004);
  EXPECT_EQ(head.prediction_horizon_ns, 5'000'000);
  EXPECT_EQ(head.cameras, 4);
  EXPECT_FALSE(frame->bodies[1].tracking_valid);
  EXPECT_EQ(frame->bodies[1].orientation[3], 1.0);
  ASSERT_EQ(frame->markers.size(), 3U);
  EXPECT_TRUE(frame->markers[0].labelled());
  EXPECT_EQ(frame->markers[0].body, "head");
  EXPECT_EQ(frame->markers[0].body_marker, 0);
  EXPECT_EQ(frame->markers[0].position[0], 1.0 / 3.0);
  EXPECT_EQ(frame->markers[0].cameras, 3);
  EXPECT_FALSE(frame->markers[0].occluded);
  EXPECT_FALSE(frame->markers[1].labelled());
  EXPECT_EQ(frame->markers[1].body_marker, -1);
  EXPECT_TRUE(frame->markers[2].occluded);
  EXPECT_EQ(frame->markers[2].body_marker, -1);  // unlabelled: no index whatever was sent
  EXPECT_EQ(frame->unlabelled_markers().size(), 2U);
  ASSERT_NE(frame->body("head"), nullptr);
  EXPECT_EQ(frame->body("head")->id, 1);
  EXPECT_EQ(frame->body("nobody"), nullptr);
}

TEST(Conversion, LatencyFromTheStamps) {
  const Latency l = latency_of(good_frame(), 1'005'000'000);
  EXPECT_EQ(l.capture_to_publish_ns, 4'000'000);
  EXPECT_EQ(l.publish_to_receive_ns, 1'000'000);
  EXPECT_EQ(l.capture_to_receive_ns, 5'000'000);
  EXPECT_EQ(l.camera_ns, 1'000'000);
  EXPECT_EQ(l.network_ns, 500'000);
  EXPECT_EQ(l.queue_ns, 1'000'000);
  EXPECT_EQ(l.update_ns, 500'000);
  EXPECT_EQ(l.output_ns, 1'000'000);
  msg::MocapFrame without_stages = good_frame();
  without_stages.stages(msg::FrameStages());
  const Latency unknown = latency_of(without_stages, 1'005'000'000);
  EXPECT_EQ(unknown.camera_ns, 0);
  EXPECT_EQ(unknown.network_ns, 0);
  EXPECT_EQ(unknown.queue_ns, 0);
  EXPECT_EQ(unknown.update_ns, 0);
  EXPECT_EQ(unknown.output_ns, 0);
  EXPECT_EQ(unknown.capture_to_receive_ns, 5'000'000);
}

// Each malformed variant is rejected with an error naming what is wrong.
void expect_rejected(const msg::MocapFrame& frame, const std::string& named) {
  std::string error;
  EXPECT_FALSE(to_frame(frame, 1, error));
  EXPECT_NE(error.find(named), std::string::npos) << error;
}

TEST(Conversion, RejectsMalformedFrames) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  msg::MocapFrame f = good_frame();
  f.bodies()[0].pose().position({nan, 0, 0});
  expect_rejected(f, "body 'head'");
  f = good_frame();
  f.bodies()[0].pose().orientation({0, 0, 0, 0.5});
  expect_rejected(f, "unit quaternion");
  f = good_frame();
  f.bodies()[0].angular_velocity({0, std::numeric_limits<double>::infinity(), 0});
  expect_rejected(f, "non-finite");
  f = good_frame();
  f.bodies()[1].name("");
  expect_rejected(f, "without a name");
  f = good_frame();
  f.bodies()[1].name("head");
  expect_rejected(f, "'head' appears twice");
  f = good_frame();
  f.markers()[1].state().position({0, nan, 0});
  expect_rejected(f, "marker 9");
  f = good_frame();
  f.markers()[0].body_marker(-1);
  expect_rejected(f, "marker 5");
  f = good_frame();
  f.frame_number(0);
  expect_rejected(f, "frame_number");
  // A body that is not tracked may carry anything in its (unused) pose fields.
  f = good_frame();
  f.bodies()[1].pose().position({nan, nan, nan});
  std::string error;
  EXPECT_TRUE(to_frame(f, 1, error)) << error;
}

msg::BodyDescriptions good_descriptions() {
  msg::BodyDescriptions d;
  d.generation(3);
  for (const char* name : {"head", "tool"}) {
    msg::BodyDescription b;
    b.name(name);
    b.id(static_cast<int>(d.bodies().size()) + 1);
    b.kind("passive");
    for (double x : {0.0, 0.1, 0.2}) {
      msg::MarkerPosition p;
      p.position({x, x * x, 0.0});
      b.markers().push_back(p);
    }
    d.bodies().push_back(b);
  }
  return d;
}

TEST(Conversion, Descriptions) {
  std::string error;
  const auto bodies = to_descriptions(good_descriptions(), error);
  ASSERT_TRUE(bodies) << error;
  ASSERT_EQ(bodies->size(), 2U);
  EXPECT_EQ((*bodies)[1].name, "tool");
  EXPECT_EQ((*bodies)[1].id, 2);
  EXPECT_EQ((*bodies)[1].kind, "passive");
  ASSERT_EQ((*bodies)[1].markers.size(), 3U);
  EXPECT_EQ((*bodies)[1].markers[2][1], 0.2 * 0.2);
}

TEST(Conversion, RejectsMalformedDescriptions) {
  std::string error;
  msg::BodyDescriptions d = good_descriptions();
  d.bodies()[1].name("head");
  EXPECT_FALSE(to_descriptions(d, error));
  EXPECT_NE(error.find("'head' appears twice"), std::string::npos) << error;
  d = good_descriptions();
  d.bodies()[0].name("");
  EXPECT_FALSE(to_descriptions(d, error));
  EXPECT_NE(error.find("without a name"), std::string::npos) << error;
  d = good_descriptions();
  d.bodies()[1].markers()[2].position({0, std::numeric_limits<double>::quiet_NaN(), 0});
  EXPECT_FALSE(to_descriptions(d, error));
  EXPECT_NE(error.find("'tool': markers[2]"), std::string::npos) << error;
  d = good_descriptions();
  d.bodies()[0].markers().clear();
  EXPECT_FALSE(to_descriptions(d, error));
  EXPECT_NE(error.find("'head': no markers"), std::string::npos) << error;
  d.bodies()[0].kind("rig");  // an inside-out rig may carry no markers
  const auto with_rig = to_descriptions(d, error);
  ASSERT_TRUE(with_rig.has_value()) << error;
  EXPECT_EQ(with_rig->front().kind, "rig");
  EXPECT_TRUE(with_rig->front().markers.empty());
}

msg::MarkerLabels good_labels() {
  msg::MarkerLabels labels;
  labels.stamp_ns(1'000'000'000);
  labels.generation(3);
  msg::SubjectLabels s1;
  s1.name("s1");
  s1.marker_set("gait2392");
  s1.markers({"R.ASIS", "L.ASIS", "S2"});
  msg::LabelStick stick;
  stick.from("R.ASIS");
  stick.to("L.ASIS");
  s1.sticks().push_back(stick);
  msg::TrackLabel named;
  named.track_id(9);
  named.marker("L.ASIS");
  s1.labels().push_back(named);
  named.track_id(11);
  named.marker("S2");
  s1.labels().push_back(named);
  labels.subjects().push_back(s1);
  msg::SubjectLabels s2 = s1;
  s2.name("s2");
  s2.labels().clear();
  labels.subjects().push_back(s2);
  return labels;
}

// rt/panoptes/labels (docs/marker_sets.md, "Labels on the wire"): the map names the frame's markers
// by track id; frame.subject("s1").marker(...) finds them.
TEST(Conversion, LabelsNameTheFramesMarkersByTrack) {
  std::string error;
  const auto map = to_label_map(good_labels(), error);
  ASSERT_TRUE(map) << error;
  ASSERT_EQ(map->subjects.size(), 2U);
  EXPECT_EQ(map->subjects[0].marker_set, "gait2392");
  ASSERT_EQ(map->subjects[0].sticks.size(), 1U);
  EXPECT_EQ(map->subjects[0].sticks[0].second, "L.ASIS");
  auto frame = to_frame(good_frame(), 1'005'000'000, error);
  ASSERT_TRUE(frame) << error;
  apply_names(*frame, *map);
  const Marker* asis = frame->subject("s1").marker("L.ASIS");
  ASSERT_NE(asis, nullptr);
  EXPECT_EQ(asis->id, 9);
  EXPECT_EQ(frame->subject("s1").marker("S2")->id, 11);
  EXPECT_EQ(frame->subject("s1").marker("R.ASIS"), nullptr);  // not named in this frame
  EXPECT_EQ(frame->subject("s2").marker("L.ASIS"), nullptr);
  EXPECT_EQ(frame->subject("s1").markers().size(), 2U);
  EXPECT_FALSE(frame->markers[0].named());  // track 5: a body's marker, no subject's
  EXPECT_EQ(frame->markers[0].body, "head");
}

TEST(Conversion, RejectsMalformedLabels) {
  std::string error;
  msg::MarkerLabels labels = good_labels();
  labels.subjects()[1].name("s1");
  EXPECT_FALSE(to_label_map(labels, error));
  EXPECT_NE(error.find("duplicate"), std::string::npos) << error;
  labels = good_labels();
  labels.subjects()[0].labels()[1].marker("R.Knee");
  EXPECT_FALSE(to_label_map(labels, error));
  EXPECT_NE(error.find("'R.Knee', not one of its markers"), std::string::npos) << error;
  labels = good_labels();
  labels.subjects()[1].labels().push_back(labels.subjects()[0].labels()[0]);
  EXPECT_FALSE(to_label_map(labels, error));
  EXPECT_NE(error.find("track 9 named twice"), std::string::npos) << error;
  labels = good_labels();
  labels.subjects()[0].sticks()[0].to("nowhere");
  EXPECT_FALSE(to_label_map(labels, error));
  EXPECT_NE(error.find("stick R.ASIS-nowhere"), std::string::npos) << error;
}

// Client::frame_rate(): a fixed-rate grid gives its rate exactly, even with a frame missing and the
// stamps out of order; per camera frame, the mean rate (issue 34: the client can query the rate).
TEST(Conversion, FrameRateFromStamps) {
  std::vector<std::int64_t> grid;
  for (std::int64_t k = 0; k < 64; ++k)
    if (k != 20) grid.push_back(1'700'000'000'000'000'000 + k * 8'333'333 + (k % 3 == 0 ? 1 : 0));
  std::swap(grid[3], grid[40]);
  EXPECT_NEAR(rate_from_stamps(grid, true), 120.0, 0.00002);
  // The third frame of a stream whose second period was skipped (the estimator behind): the
  // period still, not twice it; and with most of a window's periods skipped.
  EXPECT_NEAR(rate_from_stamps({0, 16'666'667, 25'000'000}, true), 120.0, 0.00002);
  EXPECT_NEAR(rate_from_stamps({0, 16'666'667, 33'333'333, 41'666'667}, true), 120.0, 0.00002);
  EXPECT_EQ(rate_from_stamps({}, true), 0.0);
  EXPECT_EQ(rate_from_stamps({5, 5}, true), 0.0);
  const std::vector<std::int64_t> per_camera = {0, 1'000'000, 1'500'000, 4'000'000, 10'000'000};
  EXPECT_DOUBLE_EQ(rate_from_stamps(per_camera, false), 400.0);
}

// Client::timecode(): a frame on a whole-rate fixed grid gets the grid's timecode (one place for
// the maths, panoptes/frame_grid.h); per-camera frames, stamps off the grid and rates that are not
// whole get none.
TEST(Conversion, TimecodeOfAFixedRateFrame) {
  const FrameGrid grid(120);
  const std::int64_t stamp = grid.instant(1'796'000'000LL * 120 + 37);  // 37th frame of its second
  const auto timecode = timecode_of(stamp, FrameRate{true, 1e9 / 8'333'333.0});
  ASSERT_TRUE(timecode);
  const auto expected = grid.timecode(stamp);
  EXPECT_EQ(timecode->hours, expected.hours);
  EXPECT_EQ(timecode->minutes, expected.minutes);
  EXPECT_EQ(timecode->seconds, expected.seconds);
  EXPECT_EQ(timecode->frames, 37);
  EXPECT_EQ(timecode->rate_hz, 120);
  EXPECT_EQ(timecode->text, to_string(expected, 120));
  EXPECT_FALSE(timecode_of(stamp + 1, FrameRate{true, 120.0})) << "off the grid";
  EXPECT_FALSE(timecode_of(stamp, FrameRate{false, 120.0})) << "per-camera frames";
  EXPECT_FALSE(timecode_of(stamp, FrameRate{true, 119.5})) << "not a whole rate";
  EXPECT_FALSE(timecode_of(stamp, FrameRate{true, 0.0})) << "rate not known yet";
}

TEST(FrameSequence, CountsGapsAndRestarts) {
  FrameSequence sequence;
  EXPECT_EQ(sequence.observe(100).missed, 0U);  // joined late: not missed
  EXPECT_EQ(sequence.observe(101).missed, 0U);
  EXPECT_EQ(sequence.observe(105).missed, 3U);
  const auto restart = sequence.observe(3);  // a new run whose frames 1 and 2 did not arrive
  EXPECT_TRUE(restart.restart);
  EXPECT_EQ(restart.missed, 2U);
  EXPECT_FALSE(sequence.observe(4).restart);
}

}  // namespace
}  // namespace panoptes::client::detail

namespace panoptes::client::detail {
namespace {

msg::StrokeEvents stroke_sample() {
  msg::StrokeEvents message;
  message.source_camera("w1");
  message.stamp_ns(1'700'000'000'010'000'000);
  message.surface_size({3.0, 1.0});
  message.publish_ns(1'700'000'000'011'000'000);
  msg::StrokeEvent event;
  event.phase(2);
  event.stroke_id(9);
  event.stamp_ns(1'700'000'000'005'000'000);
  event.position({1.5, 0.25});
  event.velocity({-0.5, 0.125});
  event.acceleration({3.0, -1.0});
  event.cameras(2);
  message.events().push_back(event);
  return message;
}

TEST(Conversion, StrokesCopyEveryField) {
  std::string error;
  const auto strokes = to_strokes(stroke_sample(), 42, error);
  ASSERT_TRUE(strokes.has_value()) << error;
  ASSERT_EQ(strokes->size(), 1U);
  const Stroke& s = strokes->front();
  EXPECT_EQ(s.phase, StrokePhase::kEnd);
  EXPECT_EQ(s.id, 9U);
  EXPECT_EQ(s.stamp_ns, 1'700'000'000'005'000'000);
  EXPECT_EQ(s.position, (std::array<double, 2>{1.5, 0.25}));
  EXPECT_EQ(s.velocity, (std::array<double, 2>{-0.5, 0.125}));
  EXPECT_EQ(s.acceleration, (std::array<double, 2>{3.0, -1.0}));
  EXPECT_EQ(s.cameras, 2);
  EXPECT_EQ(s.surface_size, (std::array<double, 2>{3.0, 1.0}));
  EXPECT_EQ(s.source_camera, "w1");
  EXPECT_EQ(s.publish_ns, 1'700'000'000'011'000'000);
  EXPECT_EQ(s.receive_ns, 42);
}

TEST(Conversion, RejectsMalformedStrokes) {
  std::string error;
  auto bad_phase = stroke_sample();
  bad_phase.events()[0].phase(3);
  EXPECT_FALSE(to_strokes(bad_phase, 0, error).has_value());
  EXPECT_NE(error.find("phase 3"), std::string::npos) << error;
  auto no_id = stroke_sample();
  no_id.events()[0].stroke_id(0);
  EXPECT_FALSE(to_strokes(no_id, 0, error).has_value());
  EXPECT_NE(error.find("stroke_id 0"), std::string::npos) << error;
  auto not_finite = stroke_sample();
  not_finite.events()[0].velocity({std::numeric_limits<double>::quiet_NaN(), 0.0});
  EXPECT_FALSE(to_strokes(not_finite, 0, error).has_value());
  EXPECT_NE(error.find("non-finite"), std::string::npos) << error;
}

}  // namespace
}  // namespace panoptes::client::detail

namespace panoptes::client::detail {
namespace {

msg::ChainFrame chain_sample() {
  msg::ChainFrame message;
  message.source_camera("c2");
  message.source_frame(17);
  message.stamp_ns(1'700'000'000'010'000'000);
  message.publish_ns(1'700'000'000'011'000'000);
  msg::ChainState state;
  state.name("index");
  state.chain_id(1);
  state.status(0);
  state.stamp_ns(1'700'000'000'010'000'000);
  state.angles({0.25, 1.5});
  for (int k = 0; k < 4; ++k) {
    msg::ChainMarker marker;
    marker.position({0.01 * k, 0.0, 1.0});
    state.markers().push_back(marker);
  }
  state.marker_valid({true, true, false, true});
  state.tip({0.05, 0.0, 0.99});
  state.predicted_tip({0.06, 0.0, 0.98});
  state.prediction_horizon_ns(80'000'000);
  state.grabbing(true);
  message.chains().push_back(state);
  msg::ChainEvent event;
  event.chain("index");
  event.chain_id(1);
  event.kind(1);
  event.stamp_ns(1'700'000'000'009'000'000);
  event.tip({0.04, 0.01, 0.97});
  event.bend(0.95);
  message.events().push_back(event);
  return message;
}

TEST(Conversion, ChainUpdateCopiesEveryField) {
  std::string error;
  const auto update = to_chain_update(chain_sample(), 42, error);
  ASSERT_TRUE(update.has_value()) << error;
  EXPECT_EQ(update->source_camera, "c2");
  EXPECT_EQ(update->source_frame, 17);
  EXPECT_EQ(update->stamp_ns, 1'700'000'000'010'000'000);
  EXPECT_EQ(update->receive_ns, 42);
  ASSERT_EQ(update->chains.size(), 1U);
  const Chain* chain = update->chain("index");
  ASSERT_NE(chain, nullptr);
  EXPECT_EQ(update->chain("thumb"), nullptr);
  EXPECT_TRUE(chain->tracking());
  EXPECT_EQ(chain->id, 1);
  EXPECT_EQ(chain->joint_angles, (std::vector<double>{0.25, 1.5}));
  ASSERT_EQ(chain->markers.size(), 4U);
  EXPECT_EQ(chain->markers[3], (Vec3{0.03, 0.0, 1.0}));
  EXPECT_EQ(chain->marker_valid, (std::vector<bool>{true, true, false, true}));
  EXPECT_EQ(chain->tip, (Vec3{0.05, 0.0, 0.99}));
  EXPECT_EQ(chain->predicted_tip, (Vec3{0.06, 0.0, 0.98}));
  EXPECT_EQ(chain->prediction_horizon_ns, 80'000'000);
  EXPECT_TRUE(chain->grabbing);
  ASSERT_EQ(update->events.size(), 1U);
  const GrabEvent& event = update->events[0];
  EXPECT_EQ(event.kind, GrabKind::kRelease);
  EXPECT_EQ(event.chain, "index");
  EXPECT_EQ(event.stamp_ns, 1'700'000'000'009'000'000);
  EXPECT_EQ(event.tip, (Vec3{0.04, 0.01, 0.97}));
  EXPECT_DOUBLE_EQ(event.bend, 0.95);
  EXPECT_EQ(event.publish_ns, 1'700'000'000'011'000'000);
  EXPECT_EQ(event.receive_ns, 42);
}

TEST(Conversion, ChainNotTrackingCarriesNoShape) {
  auto message = chain_sample();
  message.chains()[0].status(1);
  message.chains()[0].markers().clear();  // an ambiguous chain has none: not an error
  std::string error;
  const auto update = to_chain_update(message, 0, error);
  ASSERT_TRUE(update.has_value()) << error;
  EXPECT_EQ(update->chains[0].status, ChainStatus::kAmbiguous);
  EXPECT_TRUE(update->chains[0].markers.empty());
}

TEST(Conversion, RejectsMalformedChains) {
  const auto rejected = [](const msg::ChainFrame& message, const std::string& expected) {
    std::string error;
    const bool dropped = !to_chain_update(message, 0, error).has_value();
    return dropped && error.find(expected) != std::string::npos ? ::testing::AssertionSuccess()
                                                                : ::testing::AssertionFailure() << error;
  };
  auto bad_status = chain_sample();
  bad_status.chains()[0].status(3);
  EXPECT_TRUE(rejected(bad_status, "status 3"));
  auto no_id = chain_sample();
  no_id.chains()[0].chain_id(0);
  EXPECT_TRUE(rejected(no_id, "chain_id 0"));
  auto short_flags = chain_sample();
  short_flags.chains()[0].marker_valid().pop_back();
  EXPECT_TRUE(rejected(short_flags, "3 valid flags"));
  auto extra_angle = chain_sample();
  extra_angle.chains()[0].angles().push_back(0.0);
  EXPECT_TRUE(rejected(extra_angle, "3 angles"));
  auto nan_marker = chain_sample();
  nan_marker.chains()[0].markers()[1].position({0.0, std::numeric_limits<double>::quiet_NaN(), 1.0});
  EXPECT_TRUE(rejected(nan_marker, "non-finite marker"));
  auto infinite_tip = chain_sample();
  infinite_tip.chains()[0].predicted_tip({std::numeric_limits<double>::infinity(), 0.0, 0.0});
  EXPECT_TRUE(rejected(infinite_tip, "non-finite tip"));
  auto bad_kind = chain_sample();
  bad_kind.events()[0].kind(2);
  EXPECT_TRUE(rejected(bad_kind, "kind 2"));
  auto nan_bend = chain_sample();
  nan_bend.events()[0].bend(std::numeric_limits<double>::quiet_NaN());
  EXPECT_TRUE(rejected(nan_bend, "non-finite tip or bend"));
}

}  // namespace
}  // namespace panoptes::client::detail
