// SPDX-License-Identifier: Apache-2.0
// The Client over the loopback bus in one process: a Bus writer plays the estimator. Delivery in
// order to the queue, latest() and callbacks; late-joining body descriptions and their replacement
// by a restarted estimator; malformed samples counted and ignored; gaps, restarts, drops, timeouts,
// callback exceptions, close(); errors naming what is wrong.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "../dds_test_support.h"
#include "panoptes/client/client.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/shm_ports.h"
#include "panoptes/process.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/surface.h"

namespace panoptes::client {
namespace {

using namespace std::chrono_literals;

using panoptes::test::wait_until;

int test_domain() {
  return panoptes::test::dds_test_domain();
}

ClientOptions client_options() {
  ClientOptions o;
  o.domain_id = test_domain();
  return o;
}

// The estimator's side of the two topics.
struct FakeEstimator {
  FakeEstimator() : bus(make_options()) {}
  static dds::BusOptions make_options() {
    dds::BusOptions o;
    o.domain_id = test_domain();
    o.participant_name = "fake_estimator";
    return o;
  }
  dds::Bus bus;
  std::unique_ptr<dds::Writer<msg::MocapFrame>> frames = bus.make_writer<msg::MocapFrame>();
  std::unique_ptr<dds::Writer<msg::BodyDescriptions>> descriptions = bus.make_writer<msg::BodyDescriptions>();
};

msg::MocapFrame frame(std::uint64_t number) {
  msg::MocapFrame f;
  f.frame_number(number);
  f.stamp_ns(static_cast<long long>(number) * 1000);
  f.publish_ns(static_cast<long long>(number) * 1000 + 500);
  msg::FrameBody body;
  body.name("head");
  body.id(1);
  body.tracking_valid(true);
  body.pose().position({0.5, static_cast<double>(number), 1.5});
  body.pose().orientation({0, 0, 0, 1});
  f.bodies().push_back(body);
  return f;
}

msg::BodyDescriptions descriptions(std::uint64_t generation, const std::string& name) {
  msg::BodyDescriptions d;
  d.generation(generation);
  msg::BodyDescription b;
  b.name(name);
  b.id(1);
  b.kind("passive");
  for (double x : {0.0, 0.1, 0.2}) {
    msg::MarkerPosition p;
    p.position({x, 0.0, 0.0});
    b.markers().push_back(p);
  }
  d.bodies().push_back(b);
  return d;
}

TEST(Client, DeliversFramesInOrderToQueueLatestAndCallbacks) {
  FakeEstimator estimator;
  estimator.descriptions->write(descriptions(1, "head"));  // before the client: a late joiner
  Client client(client_options());
  std::atomic<int> called{0};
  client.add_callback([&](const Frame& f) { called += static_cast<int>(f.frame_number); });
  ASSERT_TRUE(estimator.frames->wait_for_readers(1, 5s));
  for (std::uint64_t n = 1; n <= 5; ++n) estimator.frames->write(frame(n));
  for (std::uint64_t n = 1; n <= 5; ++n) {
    const FrameResult result = client.wait_for_frame(2s);
    ASSERT_EQ(result.status, Status::kOk) << client.status_text();
    EXPECT_EQ(result.frame.frame_number, n);
    EXPECT_EQ(result.frame.bodies.at(0).position[1], static_cast<double>(n));
    EXPECT_EQ(result.frame.latency.capture_to_publish_ns, 500);
    EXPECT_GT(result.frame.receive_ns, 0);
  }
  EXPECT_TRUE(wait_until([&] { return called.load() == 1 + 2 + 3 + 4 + 5; }));
  ASSERT_TRUE(client.latest());
  EXPECT_EQ(client.latest()->frame_number, 5U);
  EXPECT_TRUE(client.connected());
  EXPECT_NE(client.status_text().find("receiving"), std::string::npos) << client.status_text();
  ASSERT_TRUE(wait_until([&] { return client.body_descriptions().size() == 1; }));
  EXPECT_EQ(client.body_description("head").markers.size(), 3U);
  try {
    client.body_description("nobody");
    FAIL() << "no UnknownBody";
  } catch (const UnknownBody& e) {
    EXPECT_NE(std::string(e.what()).find("'nobody'"), std::string::npos) << e.what();
  }
  const Stats stats = client.stats();
  EXPECT_EQ(stats.frames_received, 5U);
  EXPECT_EQ(stats.frames_missed, 0U);
  EXPECT_EQ(client.domain_id(), test_domain());
}

TEST(Client, CountsAndIgnoresMalformedSamples) {
  FakeEstimator estimator;
  Client client(client_options());
  ASSERT_TRUE(estimator.frames->wait_for_readers(1, 5s));
  ASSERT_TRUE(estimator.descriptions->wait_for_readers(1, 5s));
  estimator.descriptions->write(descriptions(1, "head"));
  ASSERT_TRUE(wait_until([&] { return client.stats().descriptions_received == 1; }));
  estimator.descriptions->write(descriptions(2, ""));  // malformed: the previous set stays
  msg::MocapFrame bad = frame(1);
  bad.bodies()[0].pose().position({std::numeric_limits<double>::quiet_NaN(), 0, 0});
  estimator.frames->write(bad);
  estimator.frames->write(frame(2));
  ASSERT_EQ(client.wait_for_frame(2s).frame.frame_number, 2U);
  ASSERT_TRUE(wait_until([&] { return client.stats().descriptions_malformed == 1; }));
  const Stats stats = client.stats();
  EXPECT_EQ(stats.frames_malformed, 1U);
  EXPECT_EQ(stats.frames_received, 1U);
  EXPECT_EQ(client.body_descriptions().at(0).name, "head");
  EXPECT_FALSE(stats.last_error.empty());
}

TEST(Client, GapsRestartsAndTheNewRunsDescriptions) {
  auto first = std::make_unique<FakeEstimator>();
  Client client(client_options());
  ASSERT_TRUE(first->frames->wait_for_readers(1, 5s));
  first->descriptions->write(descriptions(1, "head"));
  for (std::uint64_t n : {1, 2, 5}) first->frames->write(frame(n));
  ASSERT_TRUE(wait_until([&] { return client.stats().frames_received == 3; }));
  first.reset();  // the estimator goes away; a new one starts with other bodies
  FakeEstimator second;
  second.descriptions->write(descriptions(1, "tool"));
  ASSERT_TRUE(second.frames->wait_for_readers(1, 5s));
  second.frames->write(frame(1));
  ASSERT_TRUE(wait_until([&] { return client.stats().frames_received == 4; }));
  ASSERT_TRUE(wait_until([&] {
    const auto bodies = client.body_descriptions();
    return bodies.size() == 1 && bodies[0].name == "tool";
  }));
  const Stats stats = client.stats();
  EXPECT_EQ(stats.frames_missed, 2U);
  EXPECT_EQ(stats.estimator_restarts, 1U);
  EXPECT_EQ(client.latest()->frame_number, 1U);
}

TEST(Client, QueueOverflowDropsTheOldestOnceWaitedOn) {
  FakeEstimator estimator;
  ClientOptions options = client_options();
  options.queue_depth = 2;
  Client client(options);
  ASSERT_TRUE(estimator.frames->wait_for_readers(1, 5s));
  EXPECT_EQ(client.wait_for_frame(1ms).status, Status::kTimeout);
  for (std::uint64_t n = 1; n <= 5; ++n) estimator.frames->write(frame(n));
  ASSERT_TRUE(wait_until([&] { return client.stats().frames_received == 5; }));
  EXPECT_EQ(client.stats().frames_dropped, 3U);
  EXPECT_EQ(client.wait_for_frame(1s).frame.frame_number, 4U);
  EXPECT_EQ(client.wait_for_frame(1s).frame.frame_number, 5U);
}

TEST(Client, CallbackExceptionsAreCaughtAndRemovedCallbacksStop) {
  FakeEstimator estimator;
  Client client(client_options());
  std::atomic<int> calls{0};
  const int thrower = client.add_callback([](const Frame&) { throw std::runtime_error("application bug"); });
  client.add_callback([&](const Frame&) { ++calls; });
  ASSERT_TRUE(estimator.frames->wait_for_readers(1, 5s));
  estimator.frames->write(frame(1));
  ASSERT_TRUE(wait_until([&] { return calls.load() == 1; }));
  EXPECT_EQ(client.stats().callback_errors, 1U);
  EXPECT_NE(client.stats().last_error.find("application bug"), std::string::npos);
  client.remove_callback(thrower);
  estimator.frames->write(frame(2));
  ASSERT_TRUE(wait_until([&] { return calls.load() == 2; }));
  EXPECT_EQ(client.stats().callback_errors, 1U);
}

TEST(Client, TimeoutSaysNoDataAndCloseWakesAWaiter) {
  Client client(client_options());
  const FrameResult result = client.wait_for_frame(50ms);
  EXPECT_EQ(result.status, Status::kTimeout);
  EXPECT_EQ(result.frame.frame_number, 0U);
  EXPECT_FALSE(client.connected());
  EXPECT_NE(client.status_text().find("no data for"), std::string::npos) << client.status_text();
  FrameResult woken;
  std::thread waiter([&] { woken = client.wait_for_frame(10s); });
  std::this_thread::sleep_for(50ms);
  client.close();
  waiter.join();
  EXPECT_EQ(woken.status, Status::kClosed);
  client.close();  // idempotent
  EXPECT_EQ(client.wait_for_frame(1ms).status, Status::kClosed);
}

TEST(Client, CloseFromItsOwnCallback) {
  FakeEstimator estimator;
  Client client(client_options());
  std::atomic<int> calls{0};
  client.add_callback([&](const Frame&) {
    ++calls;
    client.close();
  });
  ASSERT_TRUE(estimator.frames->wait_for_readers(1, 5s));
  estimator.frames->write(frame(1));
  ASSERT_TRUE(wait_until([&] { return calls.load() == 1; }));
  estimator.frames->write(frame(2));
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(calls.load(), 1);
  EXPECT_EQ(client.wait_for_frame(1ms).status, Status::kClosed);
}

TEST(Client, BadOptionsNameWhatIsWrong) {
  ClientOptions options = client_options();
  options.profile_file = "/nonexistent/profile.xml";
  try {
    Client client(options);
    FAIL() << "no ClientError";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/profile.xml"), std::string::npos) << e.what();
  }
  options = client_options();
  options.queue_depth = 0;
  EXPECT_THROW(Client{options}, OptionError);
  options = client_options();
  options.domain_id = 300;
  EXPECT_THROW(Client{options}, OptionError);
}

// Issue 34 item 2: a y-up client returns the z-up client's frame rotated, -90 degrees about x: the
// markers (positions, velocities, covariances) and the bodies (positions, orientations), so a body
// marker placed by the y-up pose is the z-up marker rotated. The descriptions (body frame) are alike.
TEST(Client, YUpClientReturnsTheZUpFrameRotated) {
  FakeEstimator estimator;
  estimator.descriptions->write(descriptions(1, "head"));
  Client z_up(client_options());
  ClientOptions y_options = client_options();
  y_options.up_axis = "y";
  Client y_up(y_options);
  EXPECT_EQ(z_up.up_axis(), "z");
  EXPECT_EQ(y_up.up_axis(), "y");
  ASSERT_TRUE(estimator.frames->wait_for_readers(2, 5s));
  msg::MocapFrame sent = frame(1);
  const double h = std::sqrt(0.5);
  sent.bodies()[0].pose().orientation({0, 0, h, h});  // 90 degrees about z
  sent.bodies()[0].linear_velocity({0.1, 0.2, 0.3});
  msg::FrameMarker marker;
  marker.state().id(7);
  marker.state().position({0.3, -0.4, 1.2});
  marker.state().velocity({1, 2, 3});
  marker.state().covariance({1, 2, 3, 4, 5, 6});
  marker.state().status(1);
  marker.body("");
  marker.body_marker(-1);
  sent.markers().push_back(marker);
  estimator.frames->write(sent);
  const FrameResult z = z_up.wait_for_frame(2s);
  const FrameResult y = y_up.wait_for_frame(2s);
  ASSERT_EQ(z.status, Status::kOk) << z_up.status_text();
  ASSERT_EQ(y.status, Status::kOk) << y_up.status_text();
  const Marker& mz = z.frame.markers.at(0);
  const Marker& my = y.frame.markers.at(0);
  EXPECT_EQ(mz.position, (Vec3{0.3, -0.4, 1.2}));
  EXPECT_EQ(my.position, (Vec3{0.3, 1.2, 0.4}));
  EXPECT_EQ(my.velocity, (Vec3{1, 3, -2}));
  EXPECT_EQ(my.covariance, (std::array<double, 6>{1, 3, -2, 6, -5, 4}));
  const RigidBody& bz = z.frame.bodies.at(0);
  const RigidBody& by = y.frame.bodies.at(0);
  EXPECT_EQ(by.position, (Vec3{bz.position[0], bz.position[2], -bz.position[1]}));
  EXPECT_EQ(by.linear_velocity, (Vec3{0.1, 0.3, -0.2}));
  // Each layout marker: R * (p + q m) == p' + q' m, with q' = (-h, 0, 0, h) * q.
  const auto rotate = [](const Quat& q, const Vec3& v) {
    const double x = q[0];
    const double y = q[1];
    const double z = q[2];
    const double w = q[3];
    const Vec3 t{2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])};
    return Vec3{v[0] + w * t[0] + y * t[2] - z * t[1], v[1] + w * t[1] + z * t[0] - x * t[2],
                v[2] + w * t[2] + x * t[1] - y * t[0]};
  };
  ASSERT_TRUE(wait_until([&] { return y_up.body_descriptions().size() == 1; }));
  EXPECT_EQ(y_up.body_description("head").markers, z_up.body_description("head").markers);
  for (const Vec3& layout : y_up.body_description("head").markers) {
    const Vec3 rz = rotate(bz.orientation, layout);
    const Vec3 world_z{bz.position[0] + rz[0], bz.position[1] + rz[1], bz.position[2] + rz[2]};
    const Vec3 ry = rotate(by.orientation, layout);
    const Vec3 world_y{by.position[0] + ry[0], by.position[1] + ry[1], by.position[2] + ry[2]};
    EXPECT_NEAR(world_y[0], world_z[0], 1e-12);
    EXPECT_NEAR(world_y[1], world_z[2], 1e-12);
    EXPECT_NEAR(world_y[2], -world_z[1], 1e-12);
  }
}

// The OptionError a client opened with `options` throws; "" when it opens.
std::string option_error_of(const ClientOptions& options) {
  try {
    const Client client(options);
  } catch (const OptionError& e) {
    return e.what();
  }
  return "";
}

// ClientOptions::up_axis and $PANOPTES_UP_AXIS: anything but z or y is an OptionError naming it.
TEST(Client, BadUpAxisIsAnOptionErrorNamingIt) {
  ClientOptions options = client_options();
  options.up_axis = "x";
  EXPECT_EQ(option_error_of(options), "ClientOptions::up_axis=x: not an up axis (z or y)");
  ::setenv("PANOPTES_UP_AXIS", "up", 1);
  EXPECT_EQ(option_error_of(client_options()), "PANOPTES_UP_AXIS=up: not an up axis (z or y)");
  ::setenv("PANOPTES_UP_AXIS", "y", 1);
  {
    const Client client(client_options());
    EXPECT_EQ(client.up_axis(), "y");
  }
  ::unsetenv("PANOPTES_UP_AXIS");
}

// $PANOPTES_DOMAIN goes through the same check as every program's (dds::resolve_domain): a typo
// is an OptionError naming the variable and the value, never domain 0.
TEST(Client, BadDomainVariableIsAnOptionErrorNamingIt) {
  const char* old = std::getenv("PANOPTES_DOMAIN");
  const std::string saved = old != nullptr ? old : "";
  for (const char* bad : {"abc", "300"}) {
    ::setenv("PANOPTES_DOMAIN", bad, 1);
    ClientOptions options = client_options();
    options.domain_id = -1;
    try {
      Client client(options);
      ADD_FAILURE() << "no OptionError for PANOPTES_DOMAIN=" << bad;
    } catch (const OptionError& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("PANOPTES_DOMAIN=") + bad + ": not a DDS domain id (an integer 0..232)");
    }
  }
  if (old != nullptr) {
    ::setenv("PANOPTES_DOMAIN", saved.c_str(), 1);
  } else {
    ::unsetenv("PANOPTES_DOMAIN");
  }
}

// Surface mode (docs/surface.md): stroke events to the pull queue and the stroke callbacks, in
// order; a malformed sample counted and ignored; a removed callback stops.
TEST(Client, DeliversStrokeEventsToQueueAndCallbacks) {
  dds::Bus bus(FakeEstimator::make_options());
  auto writer = bus.make_writer<msg::StrokeEvents>();
  Client client(client_options());
  std::atomic<int> begun{0}, ended{0};
  const int handle = client.add_stroke_callback([&](const Stroke& s) {
    begun += s.phase == StrokePhase::kBegin ? 1 : 0;
    ended += s.phase == StrokePhase::kEnd ? 1 : 0;
  });
  ASSERT_TRUE(writer->wait_for_readers(1, 5s));
  const auto sample = [](std::uint8_t phase, std::uint32_t id, double s) {
    msg::StrokeEvents message;
    message.source_camera("w0");
    message.surface_size({3.0, 1.0});
    msg::StrokeEvent event;
    event.phase(phase);
    event.stroke_id(id);
    event.stamp_ns(static_cast<long long>(s * 1e9));
    event.position({s, 0.5});
    message.events().push_back(event);
    return message;
  };
  writer->write(sample(0, 1, 0.1));
  writer->write(sample(1, 1, 0.2));
  writer->write(sample(7, 1, 0.25));  // no such phase: counted, dropped
  writer->write(sample(2, 1, 0.3));
  const std::array<StrokePhase, 3> phases{StrokePhase::kBegin, StrokePhase::kContinue, StrokePhase::kEnd};
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const StrokeResult result = client.wait_for_stroke(2s);
    ASSERT_EQ(result.status, Status::kOk) << client.stats().last_error;
    EXPECT_EQ(result.stroke.phase, phases[i]);
    EXPECT_EQ(result.stroke.id, 1U);
    EXPECT_DOUBLE_EQ(result.stroke.position[0], 0.1 * static_cast<double>(i + 1));
    EXPECT_EQ(result.stroke.surface_size[0], 3.0);
  }
  EXPECT_TRUE(wait_until([&] { return begun == 1 && ended == 1; }));
  const Stats stats = client.stats();
  EXPECT_EQ(stats.strokes_received, 3U);
  EXPECT_EQ(stats.strokes_malformed, 1U);
  EXPECT_NE(stats.last_error.find("phase 7"), std::string::npos) << stats.last_error;
  client.remove_stroke_callback(handle);
  writer->write(sample(0, 2, 0.4));
  EXPECT_EQ(client.wait_for_stroke(2s).stroke.id, 2U);
  EXPECT_EQ(begun.load(), 1);
  EXPECT_EQ(client.wait_for_stroke(50ms).status, Status::kTimeout);
}

// Articulated chains (docs/articulated.md): updates to the chain callbacks and latest_chains(),
// their grab events to the pull queue in order; a malformed sample counted and ignored.
TEST(Client, DeliversChainUpdatesAndGrabEvents) {
  dds::Bus bus(FakeEstimator::make_options());
  auto writer = bus.make_writer<msg::ChainFrame>();
  Client client(client_options());
  std::atomic<int> updates{0}, grabbing{0};
  const int handle = client.add_chain_callback([&](const ChainUpdate& update) {
    ++updates;
    if (const Chain* chain = update.chain("index"); chain != nullptr && chain->grabbing) ++grabbing;
  });
  ASSERT_TRUE(writer->wait_for_readers(1, 5s));
  const auto sample = [](std::int64_t frame, int event_kind, std::uint8_t status) {
    msg::ChainFrame message;
    message.source_camera("c0");
    message.source_frame(frame);
    message.stamp_ns(frame * 10'000'000);
    msg::ChainState state;
    state.name("index");
    state.chain_id(1);
    state.status(status);
    state.grabbing(event_kind == 0);
    if (status == 0) {  // tracking: a 3-marker chain's shape
      state.angles({0.5});
      state.markers().resize(3);
      state.marker_valid({true, true, true});
    }
    message.chains().push_back(state);
    if (event_kind >= 0) {
      msg::ChainEvent event;
      event.chain("index");
      event.chain_id(1);
      event.kind(static_cast<std::uint8_t>(event_kind));
      event.stamp_ns(frame * 10'000'000);
      event.tip({0.01 * static_cast<double>(frame), 0.0, 1.0});
      message.events().push_back(event);
    }
    return message;
  };
  writer->write(sample(1, -1, 2));
  writer->write(sample(2, 0, 0));
  writer->write(sample(3, -1, 9));  // no such status: counted, dropped
  writer->write(sample(4, 1, 0));
  const std::array<GrabKind, 2> kinds{GrabKind::kGrab, GrabKind::kRelease};
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    const GrabResult result = client.wait_for_grab_event(2s);
    ASSERT_EQ(result.status, Status::kOk) << client.stats().last_error;
    EXPECT_EQ(result.event.kind, kinds[i]);
    EXPECT_EQ(result.event.chain, "index");
    EXPECT_DOUBLE_EQ(result.event.tip[0], 0.01 * static_cast<double>(2 * i + 2));
  }
  EXPECT_TRUE(wait_until([&] { return updates == 3; }));
  EXPECT_EQ(grabbing.load(), 1);
  const auto latest = client.latest_chains();
  ASSERT_TRUE(latest.has_value());
  EXPECT_EQ(latest->source_frame, 4);
  const Stats stats = client.stats();
  EXPECT_EQ(stats.chain_updates_received, 3U);
  EXPECT_EQ(stats.chain_updates_malformed, 1U);
  EXPECT_EQ(stats.grab_events_received, 2U);
  EXPECT_NE(stats.last_error.find("status 9"), std::string::npos) << stats.last_error;
  client.remove_chain_callback(handle);
  writer->write(sample(5, 0, 0));
  EXPECT_EQ(client.wait_for_grab_event(2s).event.kind, GrabKind::kGrab);
  EXPECT_EQ(updates.load(), 3);
  EXPECT_EQ(client.wait_for_grab_event(50ms).status, Status::kTimeout);
}

// Runs `wait` on a thread and, once it waits, `act`: the wait's result and how long after `act`
// began it returned.
template <class Wait, class Act>
auto wait_while(Wait wait, Act act) {
  decltype(wait()) result;
  std::chrono::steady_clock::time_point returned;
  std::thread waiter([&] {
    result = wait();
    returned = std::chrono::steady_clock::now();
  });
  std::this_thread::sleep_for(50ms);
  const auto acted = std::chrono::steady_clock::now();
  act();
  waiter.join();
  return std::make_pair(result, returned - acted);
}

TEST(Client, WaitForDescriptionsReturnsAsSoonAsTheyArrive) {
  FakeEstimator estimator;
  Client client(client_options());
  ASSERT_TRUE(estimator.descriptions->wait_for_readers(1, 5s));
  const auto [got, waited] = wait_while([&] { return client.wait_for_descriptions(10s); },
                                        [&] { estimator.descriptions->write(descriptions(1, "head")); });
  ASSERT_EQ(got.status, Status::kOk) << client.status_text();
  ASSERT_EQ(got.descriptions.size(), 1U);
  EXPECT_EQ(got.descriptions[0].name, "head");
  EXPECT_EQ(got.descriptions[0].markers.size(), 3U);
  EXPECT_LT(waited, 2s);  // woken by the arrival, not by the 10 s timeout
  // Known now: at once, and the same as body_descriptions().
  const auto before = std::chrono::steady_clock::now();
  const DescriptionsResult again = client.wait_for_descriptions(10s);
  EXPECT_LT(std::chrono::steady_clock::now() - before, 1s);
  ASSERT_EQ(again.status, Status::kOk);
  EXPECT_EQ(again.descriptions.size(), client.body_descriptions().size());
}

TEST(Client, WaitForDescriptionsOfAnEstimatorWithoutBodiesIsOkAndEmpty) {
  FakeEstimator estimator;
  msg::BodyDescriptions none;
  none.generation(1);
  estimator.descriptions->write(none);
  Client client(client_options());
  const DescriptionsResult got = client.wait_for_descriptions(5s);
  EXPECT_EQ(got.status, Status::kOk) << client.status_text();
  EXPECT_TRUE(got.descriptions.empty());
}

TEST(Client, WaitForDescriptionsTimesOutWithoutAnEstimatorAndCloseWakesIt) {
  Client client(client_options());
  const auto before = std::chrono::steady_clock::now();
  const DescriptionsResult result = client.wait_for_descriptions(100ms);
  EXPECT_GE(std::chrono::steady_clock::now() - before, 100ms);
  EXPECT_EQ(result.status, Status::kTimeout);
  EXPECT_TRUE(result.descriptions.empty());
  const auto [woken, waited] =
      wait_while([&] { return client.wait_for_descriptions(10s); }, [&] { client.close(); });
  EXPECT_EQ(woken.status, Status::kClosed);
  EXPECT_LT(waited, 2s);
  EXPECT_EQ(client.wait_for_descriptions(1ms).status, Status::kClosed);
}

// The estimator of LateJoinerGetsDescriptionsWithItsFirstFrames, in a process of its own (within
// one process Fast DDS delivers without the transports, and discovery differs): this test binary
// run with PANOPTES_TEST_ESTIMATOR_DOMAIN set writes the descriptions, then frames every 2 ms (the
// ~500 Hz of the clients scene) for PANOPTES_TEST_ESTIMATOR_SECONDS. Skipped otherwise.
TEST(ClientEstimatorProcess, WritesDescriptionsThenFrames) {
  const char* domain = std::getenv("PANOPTES_TEST_ESTIMATOR_DOMAIN");
  const char* seconds = std::getenv("PANOPTES_TEST_ESTIMATOR_SECONDS");
  if (domain == nullptr || seconds == nullptr) GTEST_SKIP() << "the estimator of a late-joiner test";
  dds::BusOptions options;
  options.domain_id = std::stoi(domain);
  options.participant_name = "fake_estimator";
  dds::Bus bus(options);
  auto frames = bus.make_writer<msg::MocapFrame>();
  auto writer = bus.make_writer<msg::BodyDescriptions>();
  writer->write(descriptions(1, "head"));
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(std::stod(seconds));
  const pid_t parent = ::getppid();  // the test: stop with it, not write for minutes without it
  // Stopped with SIGINT (ChildProcess::stop): it closes its participant, as an estimator does, rather
  // than leave its shared-memory files to every later run of the test.
  static volatile std::sig_atomic_t interrupted = 0;
  std::signal(SIGINT, [](int) { interrupted = 1; });
  for (std::uint64_t n = 1;
       std::chrono::steady_clock::now() < end && ::getppid() == parent && interrupted == 0; ++n) {
    frames->write(frame(n));
    std::this_thread::sleep_for(2ms);
  }
}

// The last lines of a child's log, for a failure message.
std::string log_tail(const std::filesystem::path& path, std::size_t max_chars = 4000) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return text.size() > max_chars ? text.substr(text.size() - max_chars) : text;
}

double milliseconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

// One late joiner: how long after opening its first frame and the descriptions arrived, ms; or
// what it saw when either did not come within 5 s.
struct Join {
  bool ok = false;
  double frame_ms = 0;
  double descriptions_ms = 0;
  std::string status;
};

Join join_late() {
  const auto opened = std::chrono::steady_clock::now();
  Client client(client_options());
  std::chrono::steady_clock::time_point first_frame;
  std::thread frame_waiter([&] {
    if (client.wait_for_frame(5s).status == Status::kOk) first_frame = std::chrono::steady_clock::now();
  });
  const DescriptionsResult got = client.wait_for_descriptions(5s);
  const auto described = std::chrono::steady_clock::now();
  frame_waiter.join();
  Join join;
  join.ok = got.status == Status::kOk && first_frame != std::chrono::steady_clock::time_point{};
  join.frame_ms = milliseconds(first_frame - opened);
  join.descriptions_ms = milliseconds(described - opened);
  join.status = client.status_text();
  return join;
}

// The estimator of the late-joiner test: this binary's ClientEstimatorProcess in a process of its
// own on the test's domain, writing until stopped; its output in `log`.
std::unique_ptr<ChildProcess> start_fake_estimator(const std::filesystem::path& log) {
  ::setenv("PANOPTES_TEST_ESTIMATOR_DOMAIN", std::to_string(test_domain()).c_str(), 1);
  // Until the test stops it: the joiners' time is not bounded (under a parallel build 24 took longer
  // than the 30 s it once ran for, and the last 8 found no estimator).
  ::setenv("PANOPTES_TEST_ESTIMATOR_SECONDS", "240", 1);
  auto estimator = std::make_unique<ChildProcess>(
      "fake estimator",
      std::vector<std::string>{"/proc/self/exe",
                               "--gtest_filter=ClientEstimatorProcess.WritesDescriptionsThenFrames"},
      log);
  ::unsetenv("PANOPTES_TEST_ESTIMATOR_DOMAIN");
  Client probe(client_options());  // until the estimator runs
  EXPECT_EQ(probe.wait_for_frame(20s).status, Status::kOk) << probe.status_text();
  return estimator;
}

// Clients started while an estimator (another process) runs: the descriptions it wrote long before
// come with their first frames (docs/clients.md, "Late joiners"), not tens of milliseconds after.
TEST(Client, LateJoinerGetsDescriptionsWithItsFirstFrames) {
  // 20 clients opened one after another in this process (12 until the participant ids: from the 15th
  // or 16th on, clients that took id 0 again with the GUID of every one before found no estimator for
  // 10 s, in two of seven fresh-clone suites; shm_ports.h). Two later failures were defects of Fast
  // DDS 2.9.1 in the estimator (docs/protocol.md, "Closing a participant"): its shared-memory port
  // wedged by a client that closed (every later joiner got frames, no descriptions), or its frames
  // writer deadlocked as a client left (every later joiner found no estimator). Both worked around
  // in the Bus; the estimator's log and whether it still ran are printed on a failure.
  constexpr int kJoiners = 20;
  const std::filesystem::path log = std::filesystem::temp_directory_path() /
                                    ("client_tests_estimator_" + std::to_string(::getpid()) + ".log");
  std::unique_ptr<ChildProcess> estimator = start_fake_estimator(log);
  ASSERT_FALSE(::testing::Test::HasFailure());
  std::vector<double> lags;
  std::vector<double> first_frames;
  int estimator_restarts = 0;
  int missed_in_a_row = 0;
  for (int i = 0; i < kJoiners;) {
    const Join join = join_late();
    if (!estimator->running()) {
      // Not the client's doing: the estimator ended under this joiner (Fast DDS 2.9.1 can abort on its
      // lease check, docs/benchmarks.md). Said, and the joiner runs again against a new estimator.
      std::printf("the fake estimator ended (exit %d) during late joiner %d; its log:\n%s\n",
                  estimator->exit_code(), i, log_tail(log).c_str());
      ASSERT_LT(++estimator_restarts, 3) << "the fake estimator ended 3 times";
      estimator = start_fake_estimator(log);
      ASSERT_FALSE(::testing::Test::HasFailure());
      continue;
    }
    std::printf("late joiner %d: first frame %.1f ms, descriptions %.1f ms after opening (%+.1f ms)%s\n", i,
                join.frame_ms, join.descriptions_ms, join.descriptions_ms - join.frame_ms,
                join.ok ? "" : (", not within 5 s: " + join.status).c_str());
    if (!join.ok) {
      ADD_FAILURE() << "late joiner " << i
                    << " got no frame or no descriptions within 5 s while the estimator ran: " << join.status;
      if (++missed_in_a_row == 2) break;  // the rest would wait too: the log below says more
    } else {
      missed_in_a_row = 0;
      lags.push_back(join.descriptions_ms - join.frame_ms);
      first_frames.push_back(join.frame_ms);
    }
    ++i;
  }
  estimator->stop();
  if (::testing::Test::HasFailure()) {
    std::printf("the fake estimator's log (kept: %s):\n%s\n", log.c_str(), log_tail(log).c_str());
  } else {
    std::filesystem::remove(log);
  }
  if (estimator_restarts > 0)
    std::printf("the fake estimator was started again %d time(s)\n", estimator_restarts);
  // Before the late-joiner QoS (topics.cpp) 25 of 68 got them 30-77 ms late (37 %: 2 or fewer of 12
  // has a chance of about 12 %, 3 or fewer of 24 had 0.5 %); after it none of 100 more than 26 ms, on a
  // loaded machine too. But endpoint discovery has no order: under ctest -j2 beside live tests a joiner can
  // match the frames before the descriptions' writer (2 of 12 > 30 ms in one CI run), so 2 slow joiners of 12
  // are allowed.
  const auto late = std::count_if(lags.begin(), lags.end(), [](double lag) { return lag > 30.0; });
  EXPECT_LE(late, 2) << "late joiners that got the descriptions > 30 ms after their first frame, of "
                     << kJoiners;
  // A joiner whose first announcement the estimator answered before it listened finds the estimator
  // at its next announcement: within 250 ms with the profile's period (docs/protocol.md, "Participants
  // that join late"). With the former 1 s, 12 of 30 joiners took 0.5-1 s; here 3 of 20 may take
  // over 600 ms (a loaded machine: 3 in a fresh check of stop 73, at 618, 622 and 816 ms), not more.
  const auto slow =
      std::count_if(first_frames.begin(), first_frames.end(), [](double ms) { return ms > 600.0; });
  EXPECT_LE(slow, 3) << "late joiners whose first frame came > 600 ms after opening, of " << kJoiners;
}

// The frames of a panoptes_client_probe output (JSON lines) whose number is at least `first`.
int frames_from(const std::filesystem::path& jsonl, std::uint64_t first) {
  std::ifstream in(jsonl);
  int count = 0;
  for (std::string line; std::getline(in, line);) {
    const std::size_t at = line.find("\"frame\":");
    if (at != std::string::npos && std::stoull(line.substr(at + 8)) >= first) ++count;
  }
  return count;
}

// Fast DDS 2.9.1 hands a receiver a reference into the sender's shared-memory segment, which the
// receiver opens by name; if the sender closed first (the name removed), the receiver retries that
// reference for good and never receives another sample through shared memory, from anyone
// (shm_ports.h, docs/protocol.md "Closing a participant"). The late-joiner test met it as 20 clients
// came and went: the estimator never again heard a client's acknowledgement, so no client got the
// descriptions. A Bus that closes while a participant of another process on this host knows it
// leaves its segment under its name (the receivers' Fast DDS removes it once they see the owner
// gone); one that knows none removes it (dds.Bus.AParticipantHoldsOneSharedMemorySegmentOfItsOwn).
TEST(Client, AWriterThatClosesLeavesItsSegmentToTheApplicationsReadingIt) {
  const std::filesystem::path bin = std::filesystem::read_symlink("/proc/self/exe").parent_path();
  const std::string tag = std::to_string(::getpid());
  const std::filesystem::path tmp = std::filesystem::temp_directory_path();
  const std::filesystem::path out = tmp / ("client_tests_receiver_" + tag + ".jsonl");
  const std::filesystem::path log = tmp / ("client_tests_receiver_" + tag + ".log");
  ChildProcess receiver("panoptes_client_probe",
                        {(bin / "panoptes_client_probe").string(), "--out", out.string(), "--duration", "60",
                         "--domain", std::to_string(test_domain())},
                        log);
  const std::set<std::string> before = dds::shm_segments_held("/proc/self/fd");
  std::vector<std::string> segment;
  {
    dds::BusOptions options;
    options.domain_id = test_domain();
    options.participant_name = "first_writer";
    dds::Bus bus(options);
    const std::set<std::string> held = dds::shm_segments_held("/proc/self/fd");
    std::set_difference(held.begin(), held.end(), before.begin(), before.end(), std::back_inserter(segment));
    ASSERT_EQ(segment.size(), 1U);
    auto frames = bus.make_writer<msg::MocapFrame>();
    ASSERT_TRUE(frames->wait_for_readers(1, 20s)) << log_tail(log);
    for (std::uint64_t n = 1; n <= 5; ++n) frames->write(frame(n));
  }
  const std::filesystem::path name = std::filesystem::path("/dev/shm") / segment.front();
  EXPECT_TRUE(std::filesystem::exists(name)) << name << " went with its participant";
  EXPECT_FALSE(std::filesystem::exists(name.string() + "_keep"));
  // The application reads on, from the next writer.
  FakeEstimator next;
  ASSERT_TRUE(next.frames->wait_for_readers(1, 20s)) << log_tail(log);
  for (std::uint64_t n = 1000; n < 1200; ++n) {
    next.frames->write(frame(n));
    std::this_thread::sleep_for(2ms);
  }
  receiver.stop();
  EXPECT_GT(frames_from(out, 1000), 100) << "frames of the next writer, of 200; the application's log:\n"
                                         << log_tail(log);
  std::filesystem::remove(out);
  std::filesystem::remove(log);
}

TEST(Client, VersionIsTheProjectsAndThePackagesVersion) {
  EXPECT_EQ(version(), PANOPTES_PROJECT_VERSION);
  EXPECT_EQ(version(), std::to_string(version_major()) + "." + std::to_string(version_minor()) + "." +
                           std::to_string(version_patch()));
  // What pkg-config and find_package(Panoptes) report for the installed library.
  const auto read = [](const char* path) {
    std::ifstream in(path);
    EXPECT_TRUE(in) << path;
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_NE(read(PANOPTES_CLIENT_PC).find("\nVersion: " + version() + "\n"), std::string::npos)
      << PANOPTES_CLIENT_PC;
  EXPECT_NE(read(PANOPTES_CONFIG_VERSION).find("set(PACKAGE_VERSION \"" + version() + "\")"),
            std::string::npos)
      << PANOPTES_CONFIG_VERSION;
}

}  // namespace
}  // namespace panoptes::client
