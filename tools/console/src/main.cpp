// SPDX-License-Identifier: Apache-2.0
// panoptes_console: the operator console. Joins the bus, serves the page and streams the cameras,
// tracks and bodies to browsers over a WebSocket; forwards checked commands (docs/console.md).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/console/server.h"
#include "panoptes/console_app/body_maker.h"
#include "panoptes/console_app/bus_bridge.h"
#include "panoptes/console_app/calibration_workflow.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/process.h"

namespace {

constexpr std::size_t kMinTokenLength = 16;

std::string generate_token() {
  std::random_device device;
  std::ostringstream out;
  for (int i = 0; i < 4; ++i) {
    char buffer[9];
    std::snprintf(buffer, sizeof buffer, "%08x", device());
    out << buffer;
  }
  return out.str();
}

// The first line of the file, without surrounding white space; throws naming the file.
std::string read_token(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::invalid_argument(path + ": cannot read the token file");
  std::string token;
  std::getline(file, token);
  const auto first = token.find_first_not_of(" \t\r");
  const auto last = token.find_last_not_of(" \t\r");
  token = first == std::string::npos ? "" : token.substr(first, last - first + 1);
  if (token.size() < kMinTokenLength)
    throw std::invalid_argument(path + ": the token must be at least " + std::to_string(kMinTokenLength) +
                                " characters");
  for (const char c : token) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_')
      throw std::invalid_argument(path + ": the token may hold letters, digits, '-' and '_' only");
  }
  return token;
}

// The command line's settings, resolved (addresses parsed, paths absolute, the token read).
struct ConsoleArgs {
  panoptes::console::ServerOptions options;
  std::string bind = "127.0.0.1:8080";
  std::string token_file;
  std::string dds_profile;
  std::string url_file;
  panoptes::console::CalibrationWorkflowOptions calibration;
  panoptes::console::BodyMakerOptions bodies;
};

void add_options(CLI::App& app, ConsoleArgs& args) {
  app.option_defaults()->always_capture_default();
  panoptes::dds::add_domain_option(app);
  app.add_option("--bind", args.bind, "address:port to serve on (0.0.0.0:8080 opens it on the LAN)");
  app.add_option("--token-file", args.token_file, "read the access token from this file")
      ->default_str("a new random token, printed at start");
  app.add_option("--web-root", args.options.web_root,
                 "the page's files (index.html, app.js, node_modules/three)");
  app.add_option("--dds-profile", args.dds_profile, "Fast DDS XML profile")
      ->default_str("$PANOPTES_DDS_PROFILE or deploy/dds/loopback.xml");
  app.add_option("--update-rate", args.options.update_hz, "snapshots per second sent to each browser")
      ->check(CLI::Range(1.0, 120.0));
  app.add_option("--command-rate", args.options.commands_per_s, "commands per second allowed per browser")
      ->check(CLI::Range(0.1, 1000.0));
  app.add_option("--url-file", args.url_file, "also write the URL (with the token) to this file");
  app.add_option("--calibration-dir", args.calibration.directory,
                 "where the calibration page's captures, calibration.yaml and its report go");
  app.add_option("--calibration-cameras", args.calibration.cameras_file,
                 "intrinsics file for the calibration page's solve (docs/calibration.md, step 1)")
      ->default_str("none: the page cannot solve");
  app.add_option("--estimator-node", args.calibration.estimator_node,
                 "the estimator_node program the calibration page runs");
  app.add_option("--calibration", args.calibration.calibration_file,
                 "the estimator's calibration file: the calibration page lists its versions and accepts or "
                 "reverts them (a running estimator_node reloads it; docs/continuous_calibration.md)")
      ->default_str("none: the page shows no versions");
  app.add_option("--bodies", args.bodies.bodies_file,
                 "the estimator's bodies file: bodies made from markers in the 3D view are appended to it "
                 "(the estimator reloads it; docs/bodies.md)")
      ->default_str("none: the page cannot make bodies");
  app.add_option("--ctl", args.bodies.ctl, "the panoptes_ctl program that makes those bodies");
}

// --bind parsed, paths made absolute, the token generated or read; an exit code on bad input.
std::optional<int> resolve(ConsoleArgs& args) {
  const auto colon = args.bind.rfind(':');
  int port = -1;
  try {
    if (colon != std::string::npos) port = std::stoi(args.bind.substr(colon + 1));
  } catch (const std::exception&) {
  }
  if (colon == std::string::npos || port < 0 || port > 65535) {
    std::fprintf(stderr, "panoptes_console: --bind: expected <address>:<port>, got '%s'\n",
                 args.bind.c_str());
    return panoptes::kExitBadInput;
  }
  args.options.bind_address = args.bind.substr(0, colon);
  args.options.port = static_cast<unsigned short>(port);
  args.calibration.directory = std::filesystem::absolute(args.calibration.directory);
  args.calibration.dds_profile = args.dds_profile;
  args.options.calibration_dir = args.calibration.directory;
  args.bodies.dds_profile = args.dds_profile;
  args.bodies.work_dir = args.calibration.directory;
  if (!args.calibration.calibration_file.empty())
    args.calibration.calibration_file = std::filesystem::absolute(args.calibration.calibration_file);
  if (!args.bodies.bodies_file.empty())
    args.bodies.bodies_file = std::filesystem::absolute(args.bodies.bodies_file);
  try {
    args.options.token = args.token_file.empty() ? generate_token() : read_token(args.token_file);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_console: --token-file %s\n", error.what());
    return panoptes::kExitBadInput;
  }
  return std::nullopt;
}

int run(int argc, char** argv) {
  ConsoleArgs args;
  args.options.web_root = PANOPTES_CONSOLE_WEB_DIR;
  const auto programs = std::filesystem::canonical("/proc/self/exe").parent_path();
  args.calibration.directory = "panoptes_calibration";
  args.calibration.estimator_node = programs / "estimator_node";
  args.bodies.ctl = programs / "panoptes_ctl";
  CLI::App app{"panoptes_console: the operator console in the browser (Panoptes, docs/console.md)",
               "panoptes_console"};
  add_options(app, args);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  if (const auto exit_code = resolve(args)) return *exit_code;
  auto& options = args.options;
  const std::string& bind = args.bind;

  panoptes::install_stop_handlers();
  panoptes::console::ConsoleState state;
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = args.dds_profile;
  bus_options.participant_name = "panoptes_console";
  panoptes::dds::Bus bus(bus_options);
  panoptes::console::BusBridge bridge(bus, state);
  options.bus_rejections = [&bus] { return bus.receive_rejections(); };
  panoptes::console::CalibrationWorkflow workflow(args.calibration, state);
  panoptes::console::BodyMaker body_maker(args.bodies, state);
  std::unique_ptr<panoptes::console::ConsoleServer> server;
  try {
    server = std::make_unique<panoptes::console::ConsoleServer>(
        options, state,
        [&bridge](const panoptes::console::CameraCommandRequest& command) { return bridge.send(command); },
        [&bridge](const panoptes::console::RecorderCommandRequest& command) { return bridge.send(command); },
        [&workflow](const panoptes::console::CalibrationRequest& request) {
          return workflow.handle(request);
        },
        [&body_maker](const panoptes::console::BodyCreateRequest& request, std::uint64_t client) {
          return body_maker.handle(request, client);
        });
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_console: cannot serve on %s: %s\n", bind.c_str(), error.what());
    return panoptes::kExitFailure;
  }
  const std::string host = options.bind_address == "0.0.0.0" ? "<this host>" : options.bind_address;
  const std::string url =
      "http://" + host + ":" + std::to_string(server->port()) + "/?token=" + options.token;
  std::printf("panoptes_console: open %s\n", url.c_str());
  std::fflush(stdout);
  if (!args.url_file.empty()) std::ofstream(args.url_file) << url << "\n";

  std::thread watcher([&server, &workflow, &bridge, &body_maker] {
    for (int tick = 0; !panoptes::stop_requested(); ++tick) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (tick % 4 == 0) workflow.poll();
      if (tick % 4 == 1) body_maker.poll();
      if (tick % 4 == 2) bridge.poll();
    }
    server->stop();
  });
  server->run();
  panoptes::request_stop();
  watcher.join();
  std::printf("panoptes_console: stopped; %s\n", server->counters().dump().c_str());
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_console", [&] { return run(argc, argv); });
}
