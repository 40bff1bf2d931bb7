// SPDX-License-Identifier: Apache-2.0
// panoptes_record: records every Panoptes topic into an MCAP file (ros2 profile; docs/recording.md).
// Starts at once (or, with --idle, on a "start" RecorderCommand) and stops after --duration, on
// SIGINT/SIGTERM, or on a "stop" RecorderCommand; the file is then closed with its summary.
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/process.h"
#include "panoptes/recorder/recorder.h"
#include "panoptes_msgs/panoptes.h"

namespace {

namespace dds = panoptes::dds;
namespace rec = panoptes::recorder;
namespace msg = panoptes::msg;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string out = "recording.mcap";
  double duration_s = 0;
  bool idle = false;
  std::string id = "recorder";
  std::vector<std::string> topics;
  std::string compression = "zstd";
  int chunk_kb = 1024;
  int chunk_ms = 1000;
  std::string dds_profile;
  bool quiet = false;
  bool out_given = false;
  std::string send;  // client mode: send this command to --target and exit
  std::string target;
};

// Commands from the bus, taken by the main loop.
class CommandQueue {
 public:
  void push(msg::RecorderCommand&& command) {
    const std::lock_guard<std::mutex> lock(mutex_);
    commands_.push_back(std::move(command));
  }
  std::deque<msg::RecorderCommand> take() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(commands_, {});
  }

 private:
  std::mutex mutex_;
  std::deque<msg::RecorderCommand> commands_;
};

panoptes::recording::Compression compression_of(const std::string& name) {
  if (name == "lz4") return panoptes::recording::Compression::kLz4;
  if (name == "none") return panoptes::recording::Compression::kNone;
  return panoptes::recording::Compression::kZstd;
}

class RecordLoop {
 public:
  RecordLoop(const Options& options, dds::Bus& bus, rec::Recorder& recorder)
      : options_(options),
        bus_(bus),
        recorder_(recorder),
        status_writer_(bus.make_writer<msg::RecorderStatus>()),
        command_reader_(bus.make_reader<msg::RecorderCommand>(
            [this](msg::RecorderCommand&& command) { commands_.push(std::move(command)); })) {}

  // Returns the exit code.
  int run() {
    if (!options_.idle) start(options_.out);
    const auto begin = Clock::now();
    auto next_status = begin;
    while (!panoptes::stop_requested() && !quit_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      handle_commands();
      pump();
      if (options_.duration_s > 0 &&
          Clock::now() - begin >= std::chrono::duration<double>(options_.duration_s))
        break;
      if (Clock::now() >= next_status) {
        report();
        next_status += std::chrono::seconds(1);
      }
      if (!options_.idle && !recorder_.recording()) break;  // stopped by a command or an error
    }
    stop();
    return failed_ ? panoptes::kExitFailure : panoptes::kExitOk;
  }

 private:
  void start(const std::string& path) {
    try {
      recorder_.start(path);
      error_.clear();
      std::fprintf(stderr, "panoptes_record: recording to %s\n", path.c_str());
    } catch (const std::exception& e) {
      fail(e.what());
    }
    report();
  }
  void stop() {
    if (!recorder_.recording()) return;
    try {
      recorder_.stop();
    } catch (const std::exception& e) {
      fail(e.what());
    }
    const auto p = recorder_.progress();
    std::fprintf(stderr, "panoptes_record: closed %s: %u topics, %llu messages (%llu received), %.2f MB\n",
                 p.path.c_str(), p.topics, static_cast<unsigned long long>(p.messages),
                 static_cast<unsigned long long>(p.received), static_cast<double>(p.bytes) / 1e6);
    for (const auto& [topic, count] : p.per_topic)
      std::fprintf(stderr, "  %s: %llu\n", topic.c_str(), static_cast<unsigned long long>(count));
    // Samples the bus dropped instead of recording them (docs/hostile_input.md, docs/security.md).
    for (const auto& [reason, count] : bus_.receive_rejections())
      std::fprintf(stderr, "  dropped (%s): %llu\n", reason.c_str(), static_cast<unsigned long long>(count));
    report();
  }
  void pump() {
    try {
      recorder_.pump();
    } catch (const std::exception& e) {
      fail(e.what());
    }
  }
  void fail(const std::string& what) {
    error_ = what;
    failed_ = true;
    std::fprintf(stderr, "panoptes_record: error: %s\n", what.c_str());
  }
  // A relative path in a start command names a file next to --out (the recordings directory), so a
  // console on another host need not know the recorder's working directory.
  std::string path_for(const std::string& requested) const {
    if (requested.empty()) return options_.out;
    const std::filesystem::path path(requested);
    if (path.is_absolute()) return requested;
    return (std::filesystem::path(options_.out).parent_path() / path).string();
  }
  void handle_commands() {
    for (auto& command : commands_.take()) {
      if (!command.target().empty() && command.target() != "*" && command.target() != options_.id) continue;
      if (command.command() == "start") {
        if (!recorder_.recording()) start(path_for(command.path()));
      } else if (command.command() == "stop") {
        stop();
      } else if (command.command() == "quit") {
        quit_ = true;
      } else {
        error_ = "unknown recorder command '" + command.command() + "' (start | stop | quit)";
        std::fprintf(stderr, "panoptes_record: %s\n", error_.c_str());
      }
    }
  }
  void report() {
    const auto p = recorder_.progress();
    const auto now = Clock::now();
    const double dt = std::chrono::duration<double>(now - last_report_).count();
    const double rate = dt > 0 ? static_cast<double>(p.messages - last_messages_) / dt : 0;
    last_report_ = now;
    last_messages_ = p.messages;
    msg::RecorderStatus status;
    status.recorder_id(options_.id);
    status.stamp_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::system_clock::now().time_since_epoch())
                        .count());
    status.recording(p.recording);
    status.path(p.path.string());
    status.topics(p.topics);
    status.messages(p.messages);
    status.bytes(p.bytes);
    status.messages_per_s(rate);
    status.error(error_);
    for (const auto& [reason, count] : bus_.receive_rejections()) {
      msg::Counter counter;
      counter.name(reason);
      counter.value(count);
      status.counters().push_back(std::move(counter));
    }
    status_writer_->write(status);
    if (!options_.quiet && p.recording)
      std::fprintf(stderr, "panoptes_record: %s: %u topics, %llu messages, %.2f MB, %.0f msg/s\n",
                   p.path.c_str(), p.topics, static_cast<unsigned long long>(p.messages),
                   static_cast<double>(p.bytes) / 1e6, rate);
  }

  const Options& options_;
  dds::Bus& bus_;
  rec::Recorder& recorder_;
  CommandQueue commands_;
  std::unique_ptr<dds::Writer<msg::RecorderStatus>> status_writer_;
  std::unique_ptr<dds::Reader<msg::RecorderCommand>> command_reader_;
  std::string error_;
  bool failed_ = false;
  bool quit_ = false;
  Clock::time_point last_report_ = Clock::now();
  std::uint64_t last_messages_ = 0;
};

// Client mode (--command): sends one RecorderCommand and waits for a recorder's status to show it
// took effect. Returns the exit code.
int send_command(const Options& options, dds::Bus& bus) {
  std::mutex mutex;
  msg::RecorderStatus last;
  bool seen = false;
  auto status_reader = bus.make_reader<msg::RecorderStatus>([&](msg::RecorderStatus&& status) {
    if (!options.target.empty() && options.target != "*" && status.recorder_id() != options.target) return;
    const std::lock_guard<std::mutex> lock(mutex);
    last = std::move(status);
    seen = true;
  });
  auto writer = bus.make_writer<msg::RecorderCommand>();
  if (!writer->wait_for_readers(1, std::chrono::seconds(5))) {
    std::fprintf(stderr,
                 "panoptes_record: no recorder on the bus (domain $PANOPTES_DOMAIN or --domain) after 5 s\n");
    return panoptes::kExitFailure;
  }
  // Sent again every second until a status confirms it (a reader may match a moment after the
  // writer does); the commands are idempotent: a start while recording is ignored.
  msg::RecorderCommand command;
  command.target(options.target);
  command.command(options.send);
  command.path(options.out_given ? options.out : std::string());
  const bool want_recording = options.send == "start";
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  auto next_send = Clock::now();
  std::uint64_t seq = 0;
  while (Clock::now() < deadline) {
    if (Clock::now() >= next_send) {
      command.seq(++seq);
      writer->write(command);
      next_send += std::chrono::seconds(1);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const std::lock_guard<std::mutex> lock(mutex);
    if ((options.send == "quit" && seq >= 2) || (seen && last.recording() == want_recording)) {
      if (seen) {
        std::string dropped;  // what the recorder's bus dropped on receipt, by reason
        for (const msg::Counter& counter : last.counters())
          dropped += (dropped.empty() ? " (dropped: " : ", ") + counter.name() + " " +
                     std::to_string(counter.value());
        std::fprintf(stderr, "panoptes_record: %s: %s %s%s\n", last.recorder_id().c_str(),
                     last.recording() ? "recording" : "stopped", last.path().c_str(),
                     dropped.empty() ? "" : (dropped + ")").c_str());
      }
      writer->wait_for_acknowledgments(std::chrono::seconds(2));
      return panoptes::kExitOk;
    }
  }
  std::fprintf(stderr, "panoptes_record: sent '%s' but no recorder status confirmed it within 5 s\n",
               options.send.c_str());
  return panoptes::kExitFailure;
}

int run(int argc, char** argv) {
  Options options;
  CLI::App app{
      "panoptes_record: records every Panoptes topic into an MCAP file (ros2 profile, CDR as received)"};
  app.add_option("--out", options.out, "MCAP file to write (or the default for a 'start' command)")
      ->capture_default_str();
  app.add_option("--duration", options.duration_s, "stop after this many seconds (0: on a signal or command)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--idle", options.idle, "wait for a 'start' RecorderCommand instead of recording at once");
  app.add_option("--id", options.id, "recorder id that RecorderCommand.target addresses")
      ->capture_default_str();
  app.add_option(
      "--topics", options.topics,
      "DDS topics to record (default: every Panoptes topic and rt/tf, rt/rigid_bodies, rt/markers); also "
      "namespaced or per-body ROS 2 topics (rt/lab1/markers, rt/panoptes/head/pose)");
  app.add_option("--compression", options.compression, "chunk compression")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}))
      ->capture_default_str();
  app.add_option("--chunk-kb", options.chunk_kb, "uncompressed chunk size that closes a chunk, KiB")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  app.add_option("--chunk-ms", options.chunk_ms,
                 "a chunk is also closed this long after its first message (bounds what SIGKILL loses), ms")
      ->check(CLI::Range(0, 3'600'000))
      ->capture_default_str();
  app.add_option("--dds-profile", options.dds_profile, "DDS XML profile (default: deploy/dds/loopback.xml)");
  app.add_flag("--quiet", options.quiet, "no progress lines");
  panoptes::dds::add_domain_option(app);
  app.add_option(
         "--command", options.send,
         "client mode: send this RecorderCommand to running recorders and exit (start uses --out if given)")
      ->check(CLI::IsMember({"start", "stop", "quit"}));
  app.add_option("--target", options.target,
                 "client mode: the recorder id to address (default: every recorder)");
  if (const auto code = panoptes::parse_command_line(app, argc, argv)) return *code;
  options.out_given = app.count("--out") > 0;

  panoptes::install_stop_handlers();
  ::signal(SIGXFSZ, SIG_IGN);  // a file size limit fails the write (EFBIG) instead of killing us
  dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.participant_name = "panoptes_record";
  dds::Bus bus(bus_options);
  if (!options.send.empty()) return send_command(options, bus);
  rec::RecorderOptions recorder_options;
  recorder_options.topics = options.topics;
  recorder_options.mcap.compression = compression_of(options.compression);
  recorder_options.mcap.chunk_size = static_cast<std::size_t>(options.chunk_kb) * 1024;
  recorder_options.mcap.chunk_duration_ns = static_cast<std::uint64_t>(options.chunk_ms) * 1'000'000ULL;
  rec::Recorder recorder(bus, recorder_options);
  RecordLoop loop(options, bus, recorder);
  return loop.run();
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_record", [&] { return run(argc, argv); });
}
