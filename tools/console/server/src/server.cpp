// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/server.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <zlib.h>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/time.h"

namespace panoptes::console {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;

namespace {

constexpr std::size_t kMaxQueuedReplies = 64;
constexpr std::size_t kMaxRequestBytes = 8192;
constexpr const char* kCookieName = "panoptes_token";

struct Snapshot {
  std::uint64_t seq = 0;
  std::string text;
};

// Constant-time comparison: the time taken does not tell how much of a guess was right.
bool same_token(const std::string& given, const std::string& expected) {
  if (given.size() != expected.size() || expected.empty()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < given.size(); ++i)
    difference |= static_cast<unsigned char>(given[i] ^ expected[i]);
  return difference == 0;
}

std::string query_value(std::string_view target, std::string_view key) {
  const auto question = target.find('?');
  if (question == std::string_view::npos) return {};
  std::string_view query = target.substr(question + 1);
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    if (pair.size() > key.size() && pair.substr(0, key.size()) == key && pair[key.size()] == '=')
      return std::string(pair.substr(key.size() + 1));
    if (amp == std::string_view::npos) break;
    query = query.substr(amp + 1);
  }
  return {};
}

std::string cookie_value(std::string_view cookies, std::string_view key) {
  while (!cookies.empty()) {
    const auto semicolon = cookies.find(';');
    std::string_view pair = cookies.substr(0, semicolon);
    while (!pair.empty() && pair.front() == ' ') pair.remove_prefix(1);
    if (pair.size() > key.size() && pair.substr(0, key.size()) == key && pair[key.size()] == '=')
      return std::string(pair.substr(key.size() + 1));
    if (semicolon == std::string_view::npos) break;
    cookies = cookies.substr(semicolon + 1);
  }
  return {};
}

std::string_view view_of(beast::string_view text) {
  return {text.data(), text.size()};
}

std::string request_token(const http::request<http::string_body>& request) {
  std::string token = query_value(view_of(request.target()), "token");
  if (token.empty()) token = cookie_value(view_of(request[http::field::cookie]), kCookieName);
  return token;
}

std::string path_of(std::string_view target) {
  return std::string(target.substr(0, target.find('?')));
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file)
    throw std::runtime_error("cannot read " + path.string() + " (the console's web files; --web-root)");
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// The gzip member (RFC 1952) of `text` at the best compression; "" if zlib fails.
std::string gzip_of(std::string_view text) {
  z_stream stream{};
  constexpr int kGzipWindowBits = 15 + 16;  // zlib's way to ask for a gzip header and trailer
  if (deflateInit2(&stream, Z_BEST_COMPRESSION, Z_DEFLATED, kGzipWindowBits, 9, Z_DEFAULT_STRATEGY) != Z_OK)
    return {};
  std::string out(deflateBound(&stream, static_cast<uLong>(text.size())), '\0');
  // zlib's interface takes a non-const pointer; it does not write to the input.
  stream.next_in = reinterpret_cast<Bytef*>(
      const_cast<char*>(text.data()));  // NOLINT(cppcoreguidelines-pro-type-const-cast)
  stream.avail_in = static_cast<uInt>(text.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  const int result = deflate(&stream, Z_FINISH);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return result == Z_STREAM_END ? out : std::string{};
}

// The files worth compressing (three.module.js is 1.27 MB, 0.26 MB gzipped; issue 32), gzipped once.
std::map<std::string, std::string> gzip_web_files(
    const std::map<std::string, std::pair<std::string, std::string>>& files) {
  constexpr std::size_t kWorthCompressing = 1024;
  std::map<std::string, std::string> out;
  for (const auto& [path, file] : files) {
    if (file.first.size() < kWorthCompressing) continue;
    if (std::string gz = gzip_of(file.first); !gz.empty() && gz.size() < file.first.size())
      out.emplace(path, std::move(gz));
  }
  return out;
}

bool accepts_gzip(std::string_view accept_encoding) {
  // "gzip", "gzip;q=1.0", "deflate, gzip": enough for browsers; "gzip;q=0" refuses it.
  const auto at = accept_encoding.find("gzip");
  if (at == std::string_view::npos) return false;
  const auto end = accept_encoding.find(',', at);
  const std::string_view entry = accept_encoding.substr(at, end == std::string_view::npos ? end : end - at);
  const auto q = entry.find("q=");
  return q == std::string_view::npos || std::strtod(std::string(entry.substr(q + 2)).c_str(), nullptr) > 0;
}

}  // namespace

std::map<std::string, std::pair<std::string, std::string>> load_web_files(const std::filesystem::path& root) {
  const std::string js = "text/javascript; charset=utf-8";
  const std::map<std::string, std::pair<std::filesystem::path, std::string>> files = {
      {"/", {"index.html", "text/html; charset=utf-8"}},
      {"/app.js", {"app.js", js}},
      {"/style.css", {"style.css", "text/css; charset=utf-8"}},
      {"/vendor/three.module.js", {"node_modules/three/build/three.module.js", js}},
      {"/vendor/OrbitControls.js", {"node_modules/three/examples/jsm/controls/OrbitControls.js", js}},
  };
  std::map<std::string, std::pair<std::string, std::string>> out;
  for (const auto& [path, file] : files) out[path] = {read_file(root / file.first), file.second};
  return out;
}

struct Counters {
  std::atomic<std::uint64_t> clients_connected{0};
  std::atomic<std::uint64_t> clients_total{0};
  std::atomic<std::uint64_t> clients_refused{0};
  std::atomic<std::uint64_t> http_unauthorized{0};
  std::atomic<std::uint64_t> http_requests{0};
  std::atomic<std::uint64_t> snapshots_built{0};
  std::atomic<std::uint64_t> messages_sent{0};
  std::atomic<std::uint64_t> bytes_sent{0};
  std::atomic<std::uint64_t> snapshots_skipped{0};
  std::atomic<std::uint64_t> replies_dropped{0};
  std::atomic<std::uint64_t> commands_received{0};
  std::atomic<std::uint64_t> commands_forwarded{0};
  mutable std::mutex rejected_mutex;
  std::map<std::string, std::uint64_t> rejected;
};

class WebSocketSession;

struct ConsoleServer::Impl {
  Impl(ServerOptions options_in, ConsoleState& state_in, CommandSink sink_in, RecorderSink recorder_sink_in,
       CalibrationSink calibration_sink_in, BodySink body_sink_in)
      : options(std::move(options_in)),
        state(state_in),
        sink(std::move(sink_in)),
        recorder_sink(std::move(recorder_sink_in)),
        calibration_sink(std::move(calibration_sink_in)),
        body_sink(std::move(body_sink_in)),
        files(load_web_files(options.web_root)),
        gzipped(gzip_web_files(files)),
        acceptor(io),
        timer(io) {}

  void listen();
  void accept();
  void tick();
  void count_rejection(const std::string& counter) {
    std::lock_guard lock(counters.rejected_mutex);
    ++counters.rejected[counter];
  }
  void handle_client_message(WebSocketSession& session, std::string_view text);
  void handle_camera_command(WebSocketSession& session, const json& message, TimeNs now);
  void handle_recorder_command(WebSocketSession& session, const json& message, TimeNs now);
  void handle_calibration(WebSocketSession& session, const json& message, TimeNs now);
  void handle_body(WebSocketSession& session, const json& message, TimeNs now);
  void reject(WebSocketSession& session, std::int64_t request, const std::string& counter,
              const std::string& reason);
  // The per-browser rate limit; a refused command is rejected (rate_limited).
  bool admitted(WebSocketSession& session, std::int64_t request, TimeNs now);
  void send_details();
  static json stats_of(const Impl& impl);

  ServerOptions options;
  ConsoleState& state;
  CommandSink sink;
  RecorderSink recorder_sink;
  CalibrationSink calibration_sink;
  BodySink body_sink;
  std::map<std::string, std::pair<std::string, std::string>> files;
  std::map<std::string, std::string> gzipped;  // of `files`, by path: those worth compressing
  net::io_context io;
  tcp::acceptor acceptor;
  net::steady_timer timer;
  std::uint64_t ticks = 0;
  std::uint64_t next_client = 1;
  std::set<std::shared_ptr<WebSocketSession>> sessions;
  std::shared_ptr<const Snapshot> latest_full;
  std::shared_ptr<const Snapshot> latest_live;
  Counters counters;
};

// One browser. Writes go out one at a time: replies (bounded), then the latest full and live
// snapshots only; anything older is replaced and counted as skipped.
class WebSocketSession : public std::enable_shared_from_this<WebSocketSession> {
 public:
  WebSocketSession(tcp::socket socket, ConsoleServer::Impl& server, std::uint64_t id)
      : ws_(std::move(socket)),
        server_(server),
        id_(id),
        limiter_(server.options.commands_per_s, server.options.command_burst) {}

  void start(http::request<http::string_body> request) {
    request_ = std::move(request);  // kept until the handshake completes
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(server_.options.max_frame_bytes);
    ws_.async_accept(request_, [self = shared_from_this()](beast::error_code error) {
      if (error) return;
      self->server_.sessions.insert(self);
      ++self->server_.counters.clients_connected;
      ++self->server_.counters.clients_total;
      self->reply(json{{"type", "hello"},
                       {"client", self->id_},
                       {"commands", console_commands()},
                       {"max_message_bytes", self->server_.options.max_message_bytes},
                       {"update_hz", self->server_.options.update_hz}});
      auto first = std::make_shared<Snapshot>();
      first->text = self->server_.state.snapshot(wall_now_ns(), true).dump();
      self->offer(first, true, false);
      self->read();
    });
  }

  std::uint64_t id() const { return id_; }
  RateLimiter& limiter() { return limiter_; }
  // The track or body whose figures the page shows (kind "" when none).
  void select(std::string kind, std::string key) { selection_ = {std::move(kind), std::move(key)}; }
  const std::pair<std::string, std::string>& selection() const { return selection_; }

  void reply(const json& message) {
    if (replies_.size() >= kMaxQueuedReplies) {
      replies_.pop_front();
      ++server_.counters.replies_dropped;
    }
    replies_.push_back(std::make_shared<const std::string>(message.dump()));
    write_next();
  }

  void offer(std::shared_ptr<const Snapshot> snapshot, bool full, bool count_skip = true) {
    auto& slot = full ? pending_full_ : pending_live_;
    if (slot && count_skip) ++server_.counters.snapshots_skipped;
    slot = std::move(snapshot);
    write_next();
  }

  void close() {
    closed_ = true;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

 private:
  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code error, std::size_t bytes) {
      if (error) {
        if (error == websocket::error::message_too_big) self->server_.count_rejection("oversized");
        self->finish();
        return;
      }
      const std::string text = beast::buffers_to_string(self->buffer_.data());
      self->buffer_.consume(bytes);
      self->server_.handle_client_message(*self, text);
      if (!self->closed_) self->read();
    });
  }

  void write_next() {
    if (writing_ || closed_) return;
    std::shared_ptr<const std::string> next;
    if (!replies_.empty()) {
      next = replies_.front();
      replies_.pop_front();
    } else if (pending_full_) {
      if (pending_live_ && pending_live_->seq <= pending_full_->seq) {
        pending_live_.reset();
        ++server_.counters.snapshots_skipped;
      }
      next = std::shared_ptr<const std::string>(pending_full_, &pending_full_->text);
      pending_full_.reset();
    } else if (pending_live_) {
      next = std::shared_ptr<const std::string>(pending_live_, &pending_live_->text);
      pending_live_.reset();
    } else {
      return;
    }
    writing_ = true;
    ws_.text(true);
    ws_.async_write(net::buffer(*next),
                    [self = shared_from_this(), next](beast::error_code error, std::size_t bytes) {
                      self->writing_ = false;
                      if (error) {
                        self->finish();
                        return;
                      }
                      ++self->server_.counters.messages_sent;
                      self->server_.counters.bytes_sent += bytes;
                      self->write_next();
                    });
  }

  void finish() {
    if (server_.sessions.erase(shared_from_this()) > 0) --server_.counters.clients_connected;
    closed_ = true;
  }

  websocket::stream<beast::tcp_stream> ws_;
  http::request<http::string_body> request_;
  ConsoleServer::Impl& server_;
  std::uint64_t id_;
  RateLimiter limiter_;
  beast::flat_buffer buffer_;
  std::deque<std::shared_ptr<const std::string>> replies_;
  std::shared_ptr<const Snapshot> pending_full_;
  std::shared_ptr<const Snapshot> pending_live_;
  bool writing_ = false;
  bool closed_ = false;
  std::pair<std::string, std::string> selection_;
};

void ConsoleServer::Impl::reject(WebSocketSession& session, std::int64_t request, const std::string& counter,
                                 const std::string& reason) {
  count_rejection(counter);
  session.reply(json{{"type", "command_result"},
                     {"id", request},
                     {"result", "rejected"},
                     {"counter", counter},
                     {"reason", reason}});
}

bool ConsoleServer::Impl::admitted(WebSocketSession& session, std::int64_t request, TimeNs now) {
  if (session.limiter().allow(now)) return true;
  reject(session, request, "rate_limited",
         "more than " + std::to_string(static_cast<int>(options.commands_per_s)) + " commands per second");
  return false;
}

// Messages from the page: "command" (to a camera), "recorder" (to a recorder), "select" (which
// track, body or chain the page shows the figures of).
void ConsoleServer::Impl::handle_client_message(WebSocketSession& session, std::string_view text) {
  if (text.size() > options.max_message_bytes) {
    reject(session, 0, "oversized",
           "message of " + std::to_string(text.size()) + " bytes exceeds " +
               std::to_string(options.max_message_bytes));
    return;
  }
  const json message = json::parse(text, nullptr, false);
  if (message.is_discarded() || !message.is_object()) {
    reject(session, 0, "bad_message", "not a JSON object");
    return;
  }
  const auto type = message.find("type");
  const std::string kind = type != message.end() && type->is_string() ? type->get<std::string>() : "";
  if (kind == "select") {
    const auto what = message.find("kind");
    const auto key = message.find("key");
    if (what == message.end() || !what->is_string() ||
        (*what != "track" && *what != "body" && *what != "chain" &&
         !what->get_ref<const std::string&>().empty()) ||
        key == message.end() || !key->is_string() || key->get_ref<const std::string&>().size() > 128) {
      reject(session, 0, "bad_message",
             "select needs 'kind' (track | body | chain | \"\") and a string 'key'");
      return;
    }
    session.select(what->get<std::string>(), key->get<std::string>());
    return;
  }
  if (kind != "command" && kind != "recorder" && kind != "calibration" && kind != "body") {
    reject(
        session, 0, "bad_message",
        "unknown message type (expected \"command\", \"recorder\", \"calibration\", \"body\" or \"select\")");
    return;
  }
  ++counters.commands_received;
  const TimeNs now = wall_now_ns();
  if (kind == "recorder") {
    handle_recorder_command(session, message, now);
  } else if (kind == "calibration") {
    handle_calibration(session, message, now);
  } else if (kind == "body") {
    handle_body(session, message, now);
  } else {
    handle_camera_command(session, message, now);
  }
}

void ConsoleServer::Impl::handle_camera_command(WebSocketSession& session, const json& message, TimeNs now) {
  std::string camera;
  if (const auto field = message.find("camera"); field != message.end() && field->is_string())
    camera = *field;
  GateResult result = check_command(message, state.knows_camera(camera), state.image_size(camera));
  if (const auto* rejection = std::get_if<Rejection>(&result)) {
    reject(session, rejection->request, rejection->counter, rejection->reason);
    return;
  }
  const auto& command = std::get<CameraCommandRequest>(result);
  // The rate limit counts only valid commands, so a flood of them cannot starve the limit of others.
  if (!admitted(session, command.request, now)) return;
  if (!sink(command)) {
    reject(session, command.request, "not_sent", "no camera node is listening for commands");
    return;
  }
  ++counters.commands_forwarded;
  state.on_command_sent({session.id(), command.request, command.camera, command.command, 0, 0, now});
  session.reply(json{{"type", "command_result"},
                     {"id", command.request},
                     {"result", "sent"},
                     {"camera", command.camera},
                     {"command", command.command},
                     {"args", command.arguments}});
}

void ConsoleServer::Impl::handle_recorder_command(WebSocketSession& session, const json& message,
                                                  TimeNs now) {
  std::string recorder;
  if (const auto field = message.find("recorder"); field != message.end() && field->is_string())
    recorder = *field;
  RecorderGateResult result = check_recorder_command(message, state.knows_recorder(recorder));
  if (const auto* rejection = std::get_if<Rejection>(&result)) {
    reject(session, rejection->request, rejection->counter, rejection->reason);
    return;
  }
  const auto& command = std::get<RecorderCommandRequest>(result);
  if (!admitted(session, command.request, now)) return;
  if (!recorder_sink || !recorder_sink(command)) {
    reject(session, command.request, "not_sent", "no recorder is listening for commands");
    return;
  }
  ++counters.commands_forwarded;
  state.on_recorder_command_sent(
      {session.id(), command.request, command.recorder, command.command == "start", now});
  session.reply(json{{"type", "command_result"},
                     {"id", command.request},
                     {"result", "sent"},
                     {"recorder", command.recorder},
                     {"command", command.command},
                     {"args", command.path.empty() ? json::array() : json::array({command.path})}});
}

void ConsoleServer::Impl::handle_calibration(WebSocketSession& session, const json& message, TimeNs now) {
  CalibrationGateResult result = check_calibration_request(message);
  if (const auto* rejection = std::get_if<Rejection>(&result)) {
    reject(session, rejection->request, rejection->counter, rejection->reason);
    return;
  }
  const auto& request = std::get<CalibrationRequest>(result);
  if (!admitted(session, request.request, now)) return;
  if (!calibration_sink) {
    reject(session, request.request, "not_sent", "this console runs no calibration workflow");
    return;
  }
  if (const std::string refusal = calibration_sink(request); !refusal.empty()) {
    reject(session, request.request, "refused", refusal);
    return;
  }
  ++counters.commands_forwarded;
  session.reply(json{{"type", "command_result"},
                     {"id", request.request},
                     {"result", "applied"},
                     {"calibration", request.action},
                     {"command", request.action},
                     {"args", json::array()}});
}

void ConsoleServer::Impl::handle_body(WebSocketSession& session, const json& message, TimeNs now) {
  BodyGateResult result = check_body_request(message);
  if (const auto* rejection = std::get_if<Rejection>(&result)) {
    reject(session, rejection->request, rejection->counter, rejection->reason);
    return;
  }
  const auto& request = std::get<BodyCreateRequest>(result);
  if (!admitted(session, request.request, now)) return;
  if (!body_sink) {
    reject(session, request.request, "not_sent",
           "this console has no bodies file (panoptes_console --bodies)");
    return;
  }
  if (const std::string refusal = body_sink(request, session.id()); !refusal.empty()) {
    reject(session, request.request, "refused", refusal);
    return;
  }
  ++counters.commands_forwarded;
  json args = json::array();
  for (const std::int64_t id : request.tracks) args.push_back(std::to_string(id));
  session.reply(json{{"type", "command_result"},
                     {"id", request.request},
                     {"result", "sent"},
                     {"body", request.name},
                     {"command", "create_body"},
                     {"args", args}});
}

// The figures of each page's selected track or body, ~5 times a second (only pages that ask).
void ConsoleServer::Impl::send_details() {
  const TimeNs now = wall_now_ns();
  for (const auto& session : sessions) {
    const auto& [kind, key] = session->selection();
    if (kind.empty()) continue;
    session->reply(
        json{{"type", "details"}, {"kind", kind}, {"key", key}, {"figures", state.details(kind, key, now)}});
  }
}

// A plain HTTP connection: the page's files, /api/state, /api/stats, or the upgrade to /ws.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, ConsoleServer::Impl& server)
      : stream_(std::move(socket)), server_(server) {}

  void read() {
    parser_.emplace();
    parser_->body_limit(kMaxRequestBytes);
    parser_->header_limit(kMaxRequestBytes);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code error, std::size_t) {
                       if (error) return;
                       self->handle(self->parser_->release());
                     });
  }

 private:
  void handle(http::request<http::string_body> request) {
    ++server_.counters.http_requests;
    const std::string path = path_of(view_of(request.target()));
    const bool authorised = same_token(request_token(request), server_.options.token);
    if (websocket::is_upgrade(request)) {
      if (!authorised || path != "/ws" || server_.sessions.size() >= server_.options.max_clients) {
        ++server_.counters.clients_refused;
        respond(request, http::status::unauthorized, "text/plain",
                authorised ? "too many clients or wrong path\n" : "token required\n", false);
        return;
      }
      stream_.expires_never();
      std::make_shared<WebSocketSession>(stream_.release_socket(), server_, server_.next_client++)
          ->start(std::move(request));
      return;
    }
    if (!authorised) {
      ++server_.counters.http_unauthorized;
      respond(request, http::status::unauthorized, "text/plain",
              "token required: open the URL panoptes_console printed\n", false);
      return;
    }
    if (request.method() != http::verb::get) {
      respond(request, http::status::method_not_allowed, "text/plain", "GET only\n", false);
      return;
    }
    if (path == "/api/state") {
      respond(request, http::status::ok, "application/json",
              server_.state.snapshot(wall_now_ns(), true).dump(), false);
    } else if (path == "/api/calibration") {
      respond(request, http::status::ok, "application/json", server_.state.calibration_job(), false);
    } else if (path == "/api/stats") {
      respond(request, http::status::ok, "application/json", ConsoleServer::Impl::stats_of(server_).dump(),
              false);
    } else if (path.rfind("/api/preview/", 0) == 0) {
      const auto pgm = server_.state.preview_pgm(path.substr(std::string("/api/preview/").size()));
      if (pgm)
        respond(request, http::status::ok, "image/x-portable-graymap", *pgm, false);
      else
        respond(request, http::status::not_found, "text/plain", "no preview from that camera\n", false);
    } else if (path.rfind("/calibration/", 0) == 0) {
      serve_calibration_file(request, path.substr(std::string("/calibration/").size()));
    } else if (const auto file = server_.files.find(path); file != server_.files.end()) {
      const auto gz = server_.gzipped.find(path);
      if (gz != server_.gzipped.end() && accepts_gzip(view_of(request[http::field::accept_encoding])))
        respond(request, http::status::ok, file->second.second, gz->second, path == "/", "gzip");
      else
        respond(request, http::status::ok, file->second.second, file->second.first, path == "/");
    } else {
      respond(request, http::status::not_found, "text/plain", "not found\n", false);
    }
  }

  // A plot the calibration workflow wrote: a bare .png name inside the calibration directory.
  void serve_calibration_file(const http::request<http::string_body>& request, const std::string& name) {
    const bool plain =
        !name.empty() && name.front() != '.' && name.size() > 4 &&
        name.compare(name.size() - 4, 4, ".png") == 0 && std::all_of(name.begin(), name.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '.';
        });
    std::string body;
    if (plain && !server_.options.calibration_dir.empty()) {
      try {
        body = read_file(server_.options.calibration_dir / name);
      } catch (const std::exception&) {
        body.clear();
      }
    }
    if (body.empty()) {
      respond(request, http::status::not_found, "text/plain", "not found\n", false);
      return;
    }
    respond(request, http::status::ok, "image/png", std::move(body), false);
  }

  void respond(const http::request<http::string_body>& request, http::status status, const std::string& type,
               std::string body, bool set_cookie, std::string_view encoding = {}) {
    auto response = std::make_shared<http::response<http::string_body>>(status, request.version());
    response->set(http::field::server, "panoptes_console");
    response->set(http::field::content_type, type);
    if (!encoding.empty()) response->set(http::field::content_encoding, std::string(encoding));
    response->set(http::field::vary, "Accept-Encoding");
    response->set(http::field::cache_control, "no-store");
    if (set_cookie)
      response->set(http::field::set_cookie, std::string(kCookieName) + "=" + server_.options.token +
                                                 "; Path=/; HttpOnly; SameSite=Strict");
    response->keep_alive(request.keep_alive() && status == http::status::ok);
    response->body() = std::move(body);
    response->prepare_payload();
    http::async_write(stream_, *response,
                      [self = shared_from_this(), response](beast::error_code error, std::size_t) {
                        if (error) return;
                        if (response->keep_alive()) {
                          self->read();
                        } else {
                          beast::error_code ignored;
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                        }
                      });
  }

  beast::tcp_stream stream_;
  ConsoleServer::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

void ConsoleServer::Impl::listen() {
  const tcp::endpoint endpoint(net::ip::make_address(options.bind_address), options.port);
  acceptor.open(endpoint.protocol());
  acceptor.set_option(net::socket_base::reuse_address(true));
  acceptor.bind(endpoint);
  acceptor.listen(net::socket_base::max_listen_connections);
}

void ConsoleServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code error, tcp::socket socket) {
    if (error) return;  // the acceptor was closed
    std::make_shared<HttpSession>(std::move(socket), *this)->read();
    accept();
  });
}

// Builds one snapshot for every client and hands over the command outcomes.
void ConsoleServer::Impl::tick() {
  timer.expires_after(std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / options.update_hz)));
  timer.async_wait([this](beast::error_code error) {
    if (error) return;
    const TimeNs now = wall_now_ns();
    for (const CommandOutcome& outcome : state.take_outcomes(now)) {
      for (const auto& session : sessions) {
        if (session->id() != outcome.client) continue;
        session->reply(json(outcome));
      }
    }
    ++ticks;
    if (ticks % std::max<std::uint64_t>(1, static_cast<std::uint64_t>(options.update_hz / 5)) == 0)
      send_details();
    if (!sessions.empty()) {
      const bool full =
          options.full_every <= 1 || ticks % static_cast<std::uint64_t>(options.full_every) == 0;
      auto snapshot = std::make_shared<Snapshot>();
      snapshot->seq = ticks;
      json state_json = state.snapshot(now, full);
      state_json["console"] = stats_of(*this);
      snapshot->text = state_json.dump();
      ++counters.snapshots_built;
      (full ? latest_full : latest_live) = snapshot;
      // Copy: a failed write inside offer() removes its session from the set.
      const auto clients = sessions;
      for (const auto& session : clients) session->offer(snapshot, full);
    }
    tick();
  });
}

json ConsoleServer::Impl::stats_of(const Impl& impl) {
  const Counters& c = impl.counters;
  json rejected = json::object();
  {
    std::lock_guard lock(c.rejected_mutex);
    for (const auto& [name, count] : c.rejected) rejected[name] = count;
  }
  json bus_rejected = json::object();
  if (impl.options.bus_rejections) {
    for (const auto& [reason, count] : impl.options.bus_rejections()) bus_rejected[reason] = count;
  }
  return {{"clients", c.clients_connected.load()},
          {"clients_total", c.clients_total.load()},
          {"clients_refused", c.clients_refused.load()},
          {"http_unauthorized", c.http_unauthorized.load()},
          {"snapshots", c.snapshots_built.load()},
          {"messages_sent", c.messages_sent.load()},
          {"bytes_sent", c.bytes_sent.load()},
          {"snapshots_skipped", c.snapshots_skipped.load()},
          {"replies_dropped", c.replies_dropped.load()},
          {"commands_received", c.commands_received.load()},
          {"commands_forwarded", c.commands_forwarded.load()},
          {"rejected", rejected},
          {"bus_rejected", bus_rejected}};
}

ConsoleServer::ConsoleServer(ServerOptions options, ConsoleState& state, CommandSink sink,
                             RecorderSink recorder_sink, CalibrationSink calibration_sink, BodySink body_sink)
    : impl_(std::make_unique<Impl>(std::move(options), state, std::move(sink), std::move(recorder_sink),
                                   std::move(calibration_sink), std::move(body_sink))) {
  if (impl_->options.token.empty()) throw std::invalid_argument("the console needs an access token");
  if (!(impl_->options.update_hz > 0 && impl_->options.update_hz <= 240))
    throw std::invalid_argument("update rate must be in (0, 240] Hz");
  impl_->listen();
}

ConsoleServer::~ConsoleServer() = default;

unsigned short ConsoleServer::port() const {
  return impl_->acceptor.local_endpoint().port();
}

void ConsoleServer::run() {
  impl_->accept();
  impl_->tick();
  impl_->io.run();
}

void ConsoleServer::stop() {
  net::post(impl_->io, [impl = impl_.get()] {
    beast::error_code ignored;
    impl->acceptor.close(ignored);
    impl->timer.cancel();
    for (const auto& session : impl->sessions) session->close();
    impl->sessions.clear();
    impl->io.stop();
  });
}

json ConsoleServer::counters() const {
  return Impl::stats_of(*impl_);
}

}  // namespace panoptes::console
