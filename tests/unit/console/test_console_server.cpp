// SPDX-License-Identifier: Apache-2.0
// The console's server over real sockets on 127.0.0.1: the token, commands through the gate, and
// back-pressure (a client that stops reading costs skipped snapshots, not a slower server).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include <zlib.h>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/console/server.h"

namespace panoptes::console {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;

const std::string kToken = "unit-test-token-0123456789";

std::filesystem::path make_web_root() {
  auto root = std::filesystem::temp_directory_path() / ("panoptes_console_web_" + std::to_string(::getpid()));
  for (const char* file : {"index.html", "app.js", "style.css", "node_modules/three/build/three.module.js",
                           "node_modules/three/examples/jsm/controls/OrbitControls.js"}) {
    std::filesystem::create_directories((root / file).parent_path());
    std::ofstream(root / file) << "// " << file << "\n";
  }
  return root;
}

class ConsoleServerTest : public ::testing::Test {
 protected:
  void start(double update_hz = 30, bool with_body_sink = false) {
    ServerOptions options;
    options.port = 0;
    options.token = kToken;
    options.web_root = web_root_;
    options.update_hz = update_hz;
    options.bus_rejections = [] { return std::map<std::string, std::uint64_t>{{"id_outside_partition", 3}}; };
    server_ = std::make_unique<ConsoleServer>(
        options, state_,
        [this](const CameraCommandRequest& command) {
          forwarded_.push_back(command);
          return true;
        },
        [this](const RecorderCommandRequest& command) {
          recorder_commands_.push_back(command);
          return true;
        },
        CalibrationSink{},
        with_body_sink ? BodySink([this](const BodyCreateRequest& body, std::uint64_t client) {
          bodies_.emplace_back(body, client);
          return body.name == "busy" ? std::string("body 'other' is being made: wait for it") : std::string();
        })
                       : BodySink{});
    thread_ = std::thread([this] { server_->run(); });
  }
  void TearDown() override {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
    std::filesystem::remove_all(web_root_);
  }

  http::response<http::string_body> get(const std::string& target, const std::string& accept_encoding = {}) {
    net::io_context io;
    beast::tcp_stream stream(io);
    stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), server_->port()));
    http::request<http::string_body> request(http::verb::get, target, 11);
    request.set(http::field::host, "127.0.0.1");
    if (!accept_encoding.empty()) request.set(http::field::accept_encoding, accept_encoding);
    http::write(stream, request);
    beast::flat_buffer buffer;
    http::response<http::string_body> response;
    http::read(stream, buffer, response);
    return response;
  }

  std::unique_ptr<websocket::stream<tcp::socket>> open_socket(net::io_context& io,
                                                              const std::string& target) {
    auto ws = std::make_unique<websocket::stream<tcp::socket>>(io);
    ws->next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), server_->port()));
    ws->handshake("127.0.0.1", target);
    return ws;
  }

  static json read_json(websocket::stream<tcp::socket>& ws) {
    beast::flat_buffer buffer;
    ws.read(buffer);
    return json::parse(beast::buffers_to_string(buffer.data()));
  }

  // The next message of `type`, skipping state snapshots.
  static json read_until(websocket::stream<tcp::socket>& ws, const std::string& type) {
    for (int i = 0; i < 200; ++i) {
      json message = read_json(ws);
      if (message["type"] == type) return message;
    }
    return {};
  }

  std::filesystem::path web_root_ = make_web_root();
  ConsoleState state_;
  std::vector<CameraCommandRequest> forwarded_;
  std::vector<RecorderCommandRequest> recorder_commands_;
  std::vector<std::pair<BodyCreateRequest, std::uint64_t>> bodies_;
  std::unique_ptr<ConsoleServer> server_;
  std::thread thread_;
};

TEST_F(ConsoleServerTest, EveryRequestNeedsTheToken) {
  start();
  EXPECT_EQ(get("/").result(), http::status::unauthorized);
  EXPECT_EQ(get("/api/state").result(), http::status::unauthorized);
  EXPECT_EQ(get("/?token=" + kToken + "x").result(), http::status::unauthorized);
  const auto page = get("/?token=" + kToken);
  EXPECT_EQ(page.result(), http::status::ok);
  EXPECT_NE(std::string(page[http::field::set_cookie]).find(kToken), std::string::npos);
  EXPECT_EQ(get("/app.js?token=" + kToken).body(), "// app.js\n");
  EXPECT_EQ(get("/../../etc/passwd?token=" + kToken).result(), http::status::not_found);
  EXPECT_EQ(json::parse(get("/api/state?token=" + kToken).body())["type"], "state");
  EXPECT_EQ(get("/api/calibration").result(), http::status::unauthorized);
  EXPECT_EQ(get("/calibration/calibration.layout.png").result(), http::status::unauthorized);
  EXPECT_EQ(get("/api/calibration?token=" + kToken).result(), http::status::ok);
  // Plots: a bare .png name only; nothing outside the calibration directory.
  EXPECT_EQ(get("/calibration/..%2F..%2Fetc%2Fpasswd?token=" + kToken).result(), http::status::not_found);
  EXPECT_EQ(get("/calibration/../app.js?token=" + kToken).result(), http::status::not_found);

  net::io_context io;
  EXPECT_THROW(open_socket(io, "/ws"), beast::system_error);
  EXPECT_THROW(open_socket(io, "/ws?token=wrong"), beast::system_error);
  auto ws = open_socket(io, "/ws?token=" + kToken);
  EXPECT_EQ(read_json(*ws)["type"], "hello");
  EXPECT_GE(server_->counters()["clients_refused"].get<int>(), 2);
}

// zlib's own inflate of a gzip member: what a browser does with Content-Encoding: gzip.
std::string gunzip(const std::string& gz) {
  z_stream stream{};
  EXPECT_EQ(inflateInit2(&stream, 15 + 16), Z_OK);
  std::string out(1 << 20, '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));  // NOLINT
  stream.avail_in = static_cast<uInt>(gz.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(inflate(&stream, Z_FINISH), Z_STREAM_END);
  out.resize(stream.total_out);
  inflateEnd(&stream);
  return out;
}

TEST_F(ConsoleServerTest, LargeFilesAreGzippedForBrowsersThatAcceptIt) {
  std::string library;
  for (int i = 0; i < 4000; ++i)
    library += "export const value" + std::to_string(i) + " = " + std::to_string(i * 7) + ";\n";
  std::ofstream(web_root_ / "node_modules/three/build/three.module.js") << library;
  start();
  const std::string target = "/vendor/three.module.js?token=" + kToken;
  const auto plain = get(target);
  EXPECT_EQ(plain.body(), library);
  EXPECT_EQ(plain[http::field::content_encoding], "");
  for (const std::string accept : {"gzip", "gzip, deflate, br", "br;q=1.0, gzip;q=0.8"}) {
    const auto gz = get(target, accept);
    EXPECT_EQ(gz[http::field::content_encoding], "gzip") << accept;
    EXPECT_LT(gz.body().size(), library.size() / 4) << accept;
    EXPECT_EQ(gunzip(gz.body()), library) << accept;
  }
  EXPECT_EQ(get(target, "gzip;q=0").body(), library);
  EXPECT_EQ(get(target, "br").body(), library);
  // Small files are sent as they are.
  EXPECT_EQ(get("/app.js?token=" + kToken, "gzip")[http::field::content_encoding], "");
}

TEST_F(ConsoleServerTest, CommandsPassTheGateOrAreRejectedAndCounted) {
  state_.on_info("cam0", {"sim", "sim", 60, {640, 480, {}, false, {}}}, wall_now_ns());
  start();
  net::io_context io;
  auto ws = open_socket(io, "/ws?token=" + kToken);
  ws->write(net::buffer(std::string("{not json")));
  EXPECT_EQ(read_until(*ws, "command_result")["counter"], "bad_message");
  ws->write(net::buffer(std::string(20000, ' ')));
  EXPECT_EQ(read_until(*ws, "command_result")["counter"], "oversized");
  ws->write(net::buffer(
      json{{"type", "command"}, {"id", 3}, {"camera", "cam0"}, {"command", "set_threshold"}, {"args", {-5}}}
          .dump()));
  const json range = read_until(*ws, "command_result");
  EXPECT_EQ(range["id"], 3);
  EXPECT_EQ(range["counter"], "out_of_range");
  ws->write(net::buffer(
      json{{"type", "command"}, {"id", 4}, {"camera", "cam0"}, {"command", "set_threshold"}, {"args", {200}}}
          .dump()));
  const json sent = read_until(*ws, "command_result");
  EXPECT_EQ(sent["result"], "sent");
  ASSERT_EQ(forwarded_.size(), 1u);  // only the valid command reached the sink
  EXPECT_EQ(forwarded_[0].arguments, std::vector<std::string>({"200"}));
  const json counters = server_->counters();
  EXPECT_EQ(counters["rejected"]["bad_message"], 1);
  EXPECT_EQ(counters["rejected"]["oversized"], 1);
  EXPECT_EQ(counters["rejected"]["out_of_range"], 1);
  EXPECT_EQ(counters["commands_forwarded"], 1);
  EXPECT_EQ(counters["bus_rejected"]["id_outside_partition"], 3);  // the bus's own drops, alongside
}

// A recorder command reaches the recorder sink; a page that selects a track gets its figures.
TEST_F(ConsoleServerTest, RecorderCommandsAndDetailsOfTheSelection) {
  state_.on_recorder_status("studio", {}, wall_now_ns());
  TrackPoint track;
  track.id = 7;
  track.cameras = 2;
  state_.on_tracks({track}, wall_now_ns());
  start();
  net::io_context io;
  auto ws = open_socket(io, "/ws?token=" + kToken);
  ws->write(net::buffer(
      json{{"type", "recorder"}, {"id", 1}, {"recorder", "studio"}, {"command", "start"}, {"name", "a.mcap"}}
          .dump()));
  const json sent = read_until(*ws, "command_result");
  EXPECT_EQ(sent["result"], "sent");
  ASSERT_EQ(recorder_commands_.size(), 1u);
  EXPECT_EQ(recorder_commands_[0].path, "a.mcap");
  ws->write(net::buffer(json{
      {"type", "recorder"}, {"id", 2}, {"recorder", "studio"}, {"command", "start"}, {"name", "../a.mcap"}}
                            .dump()));
  EXPECT_EQ(read_until(*ws, "command_result")["counter"], "bad_arguments");
  EXPECT_EQ(recorder_commands_.size(), 1u);
  ws->write(net::buffer(json{{"type", "select"}, {"kind", "track"}, {"key", "7"}}.dump()));
  json details;
  for (int i = 0; i < 20 && !details["figures"].is_object(); ++i) {  // live tracks time out after 0.5 s
    state_.on_tracks({track}, wall_now_ns());
    details = read_until(*ws, "details");
  }
  EXPECT_EQ(details["key"], "7");
  EXPECT_EQ(details["figures"]["cameras"], 2);
  ws->write(net::buffer(json{{"type", "select"}, {"kind", "planet"}, {"key", "7"}}.dump()));
  EXPECT_EQ(read_until(*ws, "command_result")["counter"], "bad_message");
}

// A body request passes the gate to the body sink ("sent"); its outcome, posted to the state later
// for the same browser, reaches that browser. A refusal of the sink and a console without one are
// rejected with their reasons.
TEST_F(ConsoleServerTest, BodyRequestsReachTheBodyMakerAndItsOutcomeTheBrowser) {
  start(30, true);
  net::io_context io;
  auto ws = open_socket(io, "/ws?token=" + kToken);
  ws->write(net::buffer(json{{"type", "body"}, {"id", 3}, {"name", "wand"}, {"tracks", {4, 5, 6}}}.dump()));
  const json sent = read_until(*ws, "command_result");
  EXPECT_EQ(sent["result"], "sent");
  EXPECT_EQ(sent["body"], "wand");
  ASSERT_EQ(bodies_.size(), 1u);
  EXPECT_EQ(bodies_[0].first.tracks, std::vector<std::int64_t>({4, 5, 6}));
  state_.on_outcome({bodies_[0].second, 3, CommandResult::kApplied, R"({"body":"wand"})"});
  const json applied = read_until(*ws, "command_result");
  EXPECT_EQ(applied["id"], 3);
  EXPECT_EQ(applied["result"], "applied");
  EXPECT_EQ(applied["reason"], R"({"body":"wand"})");
  ws->write(net::buffer(json{{"type", "body"}, {"id", 4}, {"name", "busy"}, {"tracks", {4, 5, 6}}}.dump()));
  const json busy = read_until(*ws, "command_result");
  EXPECT_EQ(busy["counter"], "refused");
  EXPECT_NE(busy["reason"].get<std::string>().find("being made"), std::string::npos) << busy.dump();
  ws->write(net::buffer(json{{"type", "body"}, {"id", 5}, {"name", "x"}, {"tracks", {4, 5}}}.dump()));
  EXPECT_EQ(read_until(*ws, "command_result")["counter"], "bad_arguments");
  EXPECT_EQ(bodies_.size(), 2u);
}

TEST_F(ConsoleServerTest, WithoutABodiesFileBodyRequestsAreNotSent) {
  start();
  net::io_context io;
  auto ws = open_socket(io, "/ws?token=" + kToken);
  ws->write(net::buffer(json{{"type", "body"}, {"id", 1}, {"name", "wand"}, {"tracks", {4, 5, 6}}}.dump()));
  const json answer = read_until(*ws, "command_result");
  EXPECT_EQ(answer["counter"], "not_sent");
  EXPECT_NE(answer["reason"].get<std::string>().find("--bodies"), std::string::npos) << answer.dump();
}

// Large snapshots at 60 Hz and a client that never reads: its socket fills, the server keeps only
// the latest snapshot for it (counted as skipped), and a second client still gets every tick. The
// fast client reads for 2 s, and on until 20 were skipped (at most 10 s): a fresh-clone suite run
// built fewer snapshots in 2 s than the slow client's socket took before it filled (5 skipped).
TEST_F(ConsoleServerTest, ASlowClientSkipsSnapshotsAndDoesNotSlowOthers) {
  const TimeNs now = wall_now_ns();
  for (int camera = 0; camera < 40; ++camera) {
    FeatureRecord features{1, now, std::vector<BlobPoint>(400, BlobPoint{123.45F, 234.56F, 12.3F})};
    state_.on_features("cam" + std::to_string(camera), features, now);
  }
  start(60);
  net::io_context io;
  auto slow = open_socket(io, "/ws?token=" + kToken);  // never read again
  auto fast = open_socket(io, "/ws?token=" + kToken);
  const auto start_time = std::chrono::steady_clock::now();
  const int built_before = server_->counters()["snapshots"].get<int>();
  int states = 0;
  for (auto elapsed = std::chrono::steady_clock::duration::zero();
       elapsed < std::chrono::seconds(2) ||
       (elapsed < std::chrono::seconds(10) && server_->counters()["snapshots_skipped"].get<int>() <= 20);
       elapsed = std::chrono::steady_clock::now() - start_time) {
    if (read_json(*fast)["type"] == "state") ++states;
  }
  const json counters = server_->counters();
  EXPECT_GT(counters["snapshots_skipped"].get<int>(), 20) << counters.dump();
  // The fast client received (nearly) every snapshot built meanwhile, however busy the machine.
  const int built = counters["snapshots"].get<int>() - built_before;
  EXPECT_GT(built, 30);
  EXPECT_GE(states, built - 3) << "the fast client got " << states << " of " << built << " snapshots";
  EXPECT_EQ(counters["clients"], 2);
}

}  // namespace
}  // namespace panoptes::console
