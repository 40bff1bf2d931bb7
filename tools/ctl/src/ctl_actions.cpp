// SPDX-License-Identifier: Apache-2.0
#include "panoptes/ctl_actions/ctl_actions.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <istream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "panoptes/dds/bus.h"
#include "panoptes/errors.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::ctl {
namespace {

using Clock = std::chrono::steady_clock;

dds::Bus open_bus(const CtlOptions& options, const std::string& name) {
  dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.security = options.security;
  bus_options.participant_name = "panoptes_ctl/" + name;
  return dds::Bus(bus_options);
}

std::unique_ptr<dds::Writer<msg::CameraCommand>> command_writer(dds::Bus& bus, const CtlOptions& options) {
  // In the target's DDS partition: only that camera (or with '*', every camera) receives it.
  auto writer = bus.make_writer<msg::CameraCommand>(dds::Qos::kDefault, {}, options.target);
  // Reliable, volatile: a command only reaches readers already matched, so wait for them.
  if (!writer->wait_for_readers(1, std::chrono::milliseconds(static_cast<long>(options.timeout_s * 1000)))) {
    std::fprintf(stderr, "panoptes_ctl: no camera node is listening for commands (waited %.0f s)\n",
                 options.timeout_s);
    return nullptr;
  }
  // Discovery completes reader by reader: give the others a moment to match too.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  return writer;
}

// `partition`: the DDS partition of `writer` ("*": every camera), printed with the command.
void write_command(dds::Writer<msg::CameraCommand>& writer, const CtlOptions& options,
                   const std::string& partition) {
  msg::CameraCommand command;
  command.target(options.target);
  command.seq(static_cast<unsigned long long>(wall_now_ns()));
  command.command(options.command);
  command.arguments(options.arguments);
  writer.write(command);
  std::printf("sent %s to %s (seq %llu, %d node(s) matched, partition %s)\n", options.command.c_str(),
              options.target.c_str(), static_cast<unsigned long long>(command.seq()),
              writer.matched_readers(), partition.c_str());
}

int send_command(const CtlOptions& options) {
  auto bus = open_bus(options, "command");
  auto writer = command_writer(bus, options);
  if (!writer) return kExitFailure;
  write_command(*writer, options, options.target);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let reliable delivery finish
  return kExitOk;
}

// Carries out a pause line: false (after a message) when malformed.
bool script_pause(const std::vector<std::string>& tokens, dds::Writer<msg::CameraCommand>& writer,
                  const std::string& where) {
  const std::optional<ScriptPause> pause = parse_pause(tokens);
  if (!pause) {
    std::fprintf(stderr, "panoptes_ctl: %s: expected '%s'\n", where.c_str(), pause_usage(tokens).c_str());
    return false;
  }
  const auto timeout =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::duration<double>(pause->seconds));
  if (!pause->wait_nodes) {
    std::this_thread::sleep_for(timeout);
  } else if (!writer.wait_for_readers(pause->nodes, timeout)) {
    // At most: a camera that never matches must not stall the script (the later commands still
    // reach every node that did match), but the operator is told.
    std::fprintf(stderr, "panoptes_ctl: %s: %d of %d node(s) matched after %.1f s; going on\n", where.c_str(),
                 writer.matched_readers(), pause->nodes, pause->seconds);
  }
  return true;
}

// A script's command writers: one in "*" for commands to every camera (and wait_nodes), and one
// in each named camera's DDS partition, so that only that camera reads its commands
// (docs/security.md, "Camera-scoped permissions"). All are made before the first command, so
// they match while the script starts.
class ScriptWriters {
 public:
  ScriptWriters(dds::Bus& bus, const std::vector<std::vector<std::string>>& lines) : bus_(bus) {
    for (const auto& tokens : lines) {
      if (tokens.size() < 2 || !dds::names_one_partition(tokens[0]) || tokens[0] == "sleep" ||
          tokens[0] == "wait_nodes")
        continue;
      if (!per_camera_.contains(tokens[0]))
        per_camera_.emplace(tokens[0],
                            bus_.make_writer<msg::CameraCommand>(dds::Qos::kDefault, {}, tokens[0]));
    }
  }

  // Writes `command` with the target camera's writer once it has matched the camera (waiting for
  // that up to a second, once per camera); else with the one in "*", which every camera reads.
  void write(const CtlOptions& command, dds::Writer<msg::CameraCommand>& every_camera) {
    const auto found = per_camera_.find(command.target);
    if (found != per_camera_.end()) {
      dds::Writer<msg::CameraCommand>& writer = *found->second;
      if (writer.matched_readers() == 0 && waited_.insert(command.target).second)
        writer.wait_for_readers(1, std::chrono::seconds(1));
      if (writer.matched_readers() > 0) {
        write_command(writer, command, command.target);
        return;
      }
      std::fprintf(stderr, "panoptes_ctl: no camera '%s' matched its own writer; sending to every camera\n",
                   command.target.c_str());
    }
    write_command(every_camera, command, "*");
  }

 private:
  dds::Bus& bus_;
  std::map<std::string, std::unique_ptr<dds::Writer<msg::CameraCommand>>> per_camera_;
  std::set<std::string> waited_;
};

// Lines "<target> <command> [arguments...]", "sleep <seconds>" or "wait_nodes <n> <seconds>"
// (until n camera nodes listen for commands, at most that long); '#' starts a comment.
int run_script(const CtlOptions& options) {
  std::ifstream file(options.out);
  if (!file) {
    std::fprintf(stderr, "panoptes_ctl: cannot read %s\n", options.out.c_str());
    return kExitBadInput;
  }
  const std::vector<std::vector<std::string>> lines = read_script_lines(file);
  auto bus = open_bus(options, "script");
  ScriptWriters writers(bus, lines);
  auto writer = command_writer(bus, options);
  if (!writer) return kExitFailure;
  for (std::size_t index = 0; index < lines.size() && !stop_requested(); ++index) {
    const std::vector<std::string>& tokens = lines[index];
    const std::string where = options.out + ":" + std::to_string(index + 1);
    if (tokens.empty()) continue;
    if (is_pause(tokens)) {
      if (!script_pause(tokens, *writer, where)) return kExitBadInput;
      continue;
    }
    if (tokens.size() < 2) {
      std::fprintf(stderr, "panoptes_ctl: %s: expected '<target> <command> [arguments...]'\n", where.c_str());
      return kExitBadInput;
    }
    CtlOptions command = options;
    command.target = tokens[0];
    command.command = tokens[1];
    command.arguments.assign(tokens.begin() + 2, tokens.end());
    writers.write(command, *writer);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  return kExitOk;
}

int show_status(const CtlOptions& options) {
  auto bus = open_bus(options, "status");
  std::mutex mutex;
  std::atomic<int> printed{0};
  auto reader = bus.make_reader<msg::CameraStatus>([&](msg::CameraStatus&& status) {
    if (!options.camera.empty() && status.camera_id() != options.camera) return;
    const nlohmann::json line = status_json(status);
    std::lock_guard lock(mutex);
    if (printed.load() >= options.count) return;
    std::printf("%s\n", line.dump().c_str());
    std::fflush(stdout);
    ++printed;
  });
  const auto deadline = Clock::now() + std::chrono::milliseconds(static_cast<long>(options.timeout_s * 1000));
  while (printed.load() < options.count && Clock::now() < deadline && !stop_requested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // Samples the bus dropped (docs/hostile_input.md): malformed, or naming another camera than their writer.
  for (const auto& [reason, count] : bus.receive_rejections())
    std::fprintf(stderr, "panoptes_ctl: dropped %llu status messages (%s)\n",
                 static_cast<unsigned long long>(count), reason.c_str());
  if (printed.load() < options.count) {
    std::fprintf(stderr, "panoptes_ctl: received %d of %d status messages within %.0f s\n", printed.load(),
                 options.count, options.timeout_s);
    return kExitFailure;
  }
  return kExitOk;
}

int get_preview(CtlOptions options) {
  auto bus = open_bus(options, "preview");
  std::mutex mutex;
  std::optional<msg::CameraPreview> received;
  auto reader = bus.make_reader<msg::CameraPreview>([&](msg::CameraPreview&& preview) {
    if (preview.camera_id() != options.camera) return;
    std::lock_guard lock(mutex);
    received = std::move(preview);
  });
  options.target = options.camera;
  options.command = "preview";
  options.arguments = {std::to_string(options.width)};
  if (const int code = send_command(options); code != kExitOk) return code;
  const auto deadline = Clock::now() + std::chrono::milliseconds(static_cast<long>(options.timeout_s * 1000));
  while (Clock::now() < deadline) {
    {
      std::lock_guard lock(mutex);
      if (received) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::lock_guard lock(mutex);
  if (!received) {
    std::fprintf(stderr, "panoptes_ctl: no preview from %s within %.0f s\n", options.camera.c_str(),
                 options.timeout_s);
    return kExitFailure;
  }
  const std::size_t expected = static_cast<std::size_t>(received->width()) * received->height();
  if (received->pixels().size() != expected) {
    std::fprintf(stderr, "panoptes_ctl: preview from %s has %zu pixels, expected %ux%u\n",
                 options.camera.c_str(), received->pixels().size(), received->width(), received->height());
    return kExitFailure;
  }
  std::ofstream file(options.out, std::ios::binary);
  file << "P5\n" << received->width() << " " << received->height() << "\n255\n";
  file.write(reinterpret_cast<const char*>(received->pixels().data()),
             static_cast<std::streamsize>(expected));
  if (!file) {
    std::fprintf(stderr, "panoptes_ctl: cannot write %s\n", options.out.c_str());
    return kExitFailure;
  }
  std::printf("wrote %ux%u preview of %s to %s\n", received->width(), received->height(),
              options.camera.c_str(), options.out.c_str());
  return kExitOk;
}

// Publishes a fixed window for a camera at `rate_hz`, stamped now: a stand-in for the estimator's
// predictions when testing the guided search.
int publish_predictions(const CtlOptions& options) {
  auto bus = open_bus(options, "predict");
  auto writer = bus.make_writer<msg::Predictions>(dds::Qos::kDefault, {}, options.camera);
  msg::PredictedWindow window;
  window.track_id(0);
  window.x(static_cast<float>(options.window[0]));
  window.y(static_cast<float>(options.window[1]));
  window.half_width(static_cast<float>(options.window[2]));
  window.half_height(static_cast<float>(options.window[3]));
  const auto end = Clock::now() + std::chrono::milliseconds(static_cast<long>(options.duration_s * 1000));
  const auto period = std::chrono::nanoseconds(static_cast<long>(1e9 / options.rate_hz));
  std::uint64_t sent = 0;
  for (auto next = Clock::now(); next < end && !stop_requested(); next += period) {
    std::this_thread::sleep_until(next);
    msg::Predictions predictions;
    predictions.camera_id(options.camera);
    predictions.stamp_ns(wall_now_ns());
    predictions.windows({window});
    writer->write(predictions);
    ++sent;
  }
  std::printf("published %llu predictions for %s\n", static_cast<unsigned long long>(sent),
              options.camera.c_str());
  return kExitOk;
}

}  // namespace

std::vector<std::vector<std::string>> read_script_lines(std::istream& file) {
  std::vector<std::vector<std::string>> lines;
  for (std::string line; std::getline(file, line);) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string word; words >> word;) tokens.push_back(word);
    lines.push_back(std::move(tokens));
  }
  return lines;
}

bool is_pause(const std::vector<std::string>& tokens) {
  return !tokens.empty() && (tokens[0] == "sleep" || tokens[0] == "wait_nodes");
}

std::optional<ScriptPause> parse_pause(const std::vector<std::string>& tokens) {
  if (!is_pause(tokens)) return std::nullopt;
  ScriptPause pause;
  pause.wait_nodes = tokens[0] == "wait_nodes";
  double seconds = -1;
  try {
    if (pause.wait_nodes && tokens.size() == 3) {
      pause.nodes = std::stoi(tokens[1]);
      seconds = std::stod(tokens[2]);
    } else if (!pause.wait_nodes && tokens.size() == 2) {
      seconds = std::stod(tokens[1]);
    }
  } catch (const std::exception&) {
    seconds = -1;
  }
  if (!(seconds >= 0) || pause.nodes < 1) return std::nullopt;
  pause.seconds = seconds;
  return pause;
}

std::string pause_usage(const std::vector<std::string>& tokens) {
  return !tokens.empty() && tokens[0] == "wait_nodes" ? "wait_nodes <nodes >= 1> <seconds>"
                                                      : "sleep <seconds>";
}

nlohmann::json status_json(const msg::CameraStatus& status) {
  nlohmann::json counters = nlohmann::json::object();
  for (const msg::Counter& counter : status.counters()) counters[counter.name()] = counter.value();
  return {{"camera_id", status.camera_id()},
          {"stamp_ns", status.stamp_ns()},
          {"fps", status.fps()},
          {"frames", status.frames()},
          {"drops_queue", status.drops_queue()},
          {"drops_source", status.drops_source()},
          {"detect_p50_ms", status.detect_p50_ms()},
          {"detect_p99_ms", status.detect_p99_ms()},
          {"queue_depth", status.queue_depth()},
          {"threshold", status.threshold()},
          {"exposure_us", status.exposure_us()},
          {"gain_db", status.gain_db()},
          {"clock_offset_ns", status.clock_offset_ns()},
          {"clock_drift_ppm", status.clock_drift_ppm()},
          {"last_error", status.last_error()},
          {"counters", counters}};
}

// Averages each track over the MocapFrames that show it confirmed, until one track has been
// confirmed in `body_frames` of them (or the timeout); tracks confirmed in fewer than 80 % as many
// frames as that one are left out (a blinking track is no base for a layout). Counted against the
// best track, not the frames received: while the cameras stall (a loaded machine, test_body_create)
// the fixed-rate frames show every track coasting, and collection simply goes on.
std::optional<TrackPositions> averaged_tracks(const CtlOptions& options, int& frames_seen) {
  auto bus = open_bus(options, "body");
  std::mutex mutex;
  std::map<std::int64_t, std::pair<Eigen::Vector3d, int>> sums;
  int frames = 0, best = 0;
  auto reader = bus.make_reader<msg::MocapFrame>([&](msg::MocapFrame&& frame) {
    std::lock_guard lock(mutex);
    if (best >= options.body_frames) return;
    ++frames;
    for (const auto& marker : frame.markers()) {
      const auto& state = marker.state();
      if (state.status() != 1) continue;  // confirmed only: not tentative, not coasting
      auto& [sum, count] = sums.try_emplace(state.id(), Eigen::Vector3d::Zero(), 0).first->second;
      sum += Eigen::Vector3d(state.position()[0], state.position()[1], state.position()[2]);
      best = std::max(best, ++count);
    }
  });
  const auto deadline = Clock::now() + std::chrono::milliseconds(static_cast<long>(options.timeout_s * 1000));
  const auto done = [&] {
    std::lock_guard lock(mutex);
    return best >= options.body_frames;
  };
  while (!done() && Clock::now() < deadline && !stop_requested())
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  reader.reset();
  std::lock_guard lock(mutex);
  frames_seen = best;
  if (frames == 0) return std::nullopt;
  TrackPositions positions;
  for (const auto& [id, entry] : sums)
    if (5 * entry.second >= 4 * best) positions[id] = entry.first / entry.second;
  return positions;
}

int create_body(const CtlOptions& options) {
  // The name first: once the estimator tracks a body of these markers they are no loose tracks.
  check_body_name(options.body.bodies_file, options.body.name);
  int frames = 0;
  const auto seen = averaged_tracks(options, frames);
  if (!seen) {
    std::fprintf(stderr, "panoptes_ctl: no MocapFrame from an estimator within %.0f s (rt/panoptes/frames)\n",
                 options.timeout_s);
    return kExitFailure;
  }
  const auto ids = select_tracks(options.body, *seen);
  const BodyDefinition body = make_body(options.body, ids, *seen);
  append_body(options.body.bodies_file, body);
  nlohmann::json markers = nlohmann::json::array();
  for (const auto& marker : body.markers) markers.push_back({marker.x(), marker.y(), marker.z()});
  const nlohmann::json line{{"body", body.name},
                            {"tracks", ids},
                            {"frames", frames},
                            {"markers", markers},
                            {"file", options.body.bodies_file.string()}};
  std::printf("%s\n", line.dump().c_str());
  return kExitOk;
}

int run_action(Action action, const CtlOptions& options) {
  try {
    switch (action) {
      case Action::kCommand:
        return send_command(options);
      case Action::kScript:
        return run_script(options);
      case Action::kStatus:
        return show_status(options);
      case Action::kPreview:
        return get_preview(options);
      case Action::kBodyCreate:
        return create_body(options);
      case Action::kPredict:
        break;
    }
    return publish_predictions(options);
  } catch (const InputError&) {  // e.g. the DDS profile or Security files: refused before joining
    throw;
  } catch (const std::exception& error) {  // anything else is a run-time failure (exit 1)
    throw std::runtime_error(error.what());
  }
}

}  // namespace panoptes::ctl
