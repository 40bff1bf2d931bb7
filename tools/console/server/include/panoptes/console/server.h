// SPDX-License-Identifier: Apache-2.0
// panoptes_console's server: one port, HTTP for the page and its files, a WebSocket (/ws) that
// streams the ConsoleState to every browser and takes commands (docs/console.md). Everything needs
// the access token (query `token=` or the cookie the page sets): HTTP 401 without it, the
// WebSocket refused. One thread (run()) does all the networking; DDS threads only touch the state.
//
// Back-pressure: a snapshot is built ~30 times a second once and shared; a client whose previous
// write has not finished keeps only the latest snapshot (the skipped ones are counted), so a slow
// browser costs memory for one snapshot and never slows the bus.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/command_gate.h"
#include "panoptes/console/console_state.h"

namespace panoptes::console {

struct ServerOptions {
  std::string bind_address = "127.0.0.1";
  unsigned short port = 8080;  // 0: any free port (tests)
  std::string token;
  std::filesystem::path web_root;         // index.html, app.js, style.css and node_modules/three
  std::filesystem::path calibration_dir;  // the calibration page's plots, served as /calibration/<name>.png
  double update_hz = 30;
  int full_every = 15;                    // every n-th snapshot carries info, geometry, status
  std::size_t max_message_bytes = 16384;  // larger client messages are rejected (counted)
  std::size_t max_frame_bytes = 1 << 20;  // larger ones close the WebSocket
  double commands_per_s = 10;             // per client, token bucket
  double command_burst = 20;
  std::size_t max_clients = 32;
  // Received DDS samples the console's bus dropped, by reason (dds::Bus::receive_rejections:
  // malformed, or naming another camera than their writer's partition); in the console's counters.
  std::function<std::map<std::string, std::uint64_t>()> bus_rejections;
};

// Forwards a checked command to the camera; false if it could not be sent.
using CommandSink = std::function<bool(const CameraCommandRequest&)>;
// Forwards a checked recorder command; false if no recorder listens.
using RecorderSink = std::function<bool(const RecorderCommandRequest&)>;
// Runs a checked calibration step; returns "" when it started, else why it cannot.
using CalibrationSink = std::function<std::string(const CalibrationRequest&)>;

// Starts making a checked body from live tracks for browser `client` (its outcome comes later
// through ConsoleState::on_outcome); returns "" when it started, else why not.
using BodySink = std::function<std::string(const BodyCreateRequest&, std::uint64_t client)>;

// Loads the page's files; throws std::runtime_error naming the missing file.
std::map<std::string, std::pair<std::string, std::string>> load_web_files(
    const std::filesystem::path& web_root);

class ConsoleServer {
 public:
  // Without a recorder, calibration or body sink, those commands are rejected (not_sent).
  ConsoleServer(ServerOptions options, ConsoleState& state, CommandSink sink, RecorderSink recorder_sink = {},
                CalibrationSink calibration_sink = {}, BodySink body_sink = {});
  ~ConsoleServer();
  ConsoleServer(const ConsoleServer&) = delete;
  ConsoleServer& operator=(const ConsoleServer&) = delete;

  unsigned short port() const;  // the bound port
  void run();                   // serves until stop()
  void stop();                  // from any thread
  // Counters: clients, messages and bytes sent, snapshots skipped, commands forwarded and
  // rejected by reason. Thread-safe.
  nlohmann::json counters() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace panoptes::console
