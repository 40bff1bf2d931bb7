// SPDX-License-Identifier: Apache-2.0
// panoptes_track_probe: an application on the bus, for the multi-host tests. Records one JSON line
// per TrackFrame received (wall-clock receive time, the frame's stamp, the camera whose frame
// produced it, confirmed tracks) and, with --status, one per EstimatorStatus, so that a test can
// measure from records when tracking stopped and when it came back.
#include <cstdio>
#include <exception>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/security_options.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace {

int run(int argc, char** argv) {
  std::string out_file;
  std::string dds_profile;
  panoptes::dds::SecurityOptions security;
  double duration_s = 0;
  bool with_status = false;
  CLI::App app{"panoptes_track_probe: records received TrackFrames (and EstimatorStatus) as JSON lines",
               "panoptes_track_probe"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--out", out_file, "JSONL file to write")->required();
  app.add_option("--dds-profile", dds_profile, "Fast DDS XML profile")
      ->default_str("$PANOPTES_DDS_PROFILE or deploy/dds/loopback.xml");
  panoptes::dds::add_security_options(app, security);
  app.add_option("--duration", duration_s, "stop after this many seconds (0 = until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--status", with_status, "also record EstimatorStatus (per-camera utilisation)");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();

  std::ofstream out(out_file);
  if (!out) {
    std::fprintf(stderr, "panoptes_track_probe: cannot write %s\n", out_file.c_str());
    return panoptes::kExitBadInput;
  }
  std::mutex mutex;
  try {
    panoptes::dds::BusOptions options;
    options.profile_file = dds_profile;
    options.security = security;
    options.participant_name = "panoptes_track_probe";
    panoptes::dds::Bus bus(options);
    auto tracks = bus.make_reader<panoptes::msg::TrackFrame>([&](panoptes::msg::TrackFrame&& frame) {
      const panoptes::TimeNs received = panoptes::wall_now_ns();
      int confirmed = 0;
      for (const auto& track : frame.tracks()) confirmed += track.status() == 1 ? 1 : 0;
      const nlohmann::json line = {{"type", "tracks"},
                                   {"recv_ns", received},
                                   {"stamp_ns", frame.stamp_ns()},
                                   {"publish_ns", frame.publish_ns()},
                                   {"camera", frame.source_camera()},
                                   {"frame", frame.source_frame()},
                                   {"tracks", frame.tracks().size()},
                                   {"confirmed", confirmed}};
      std::lock_guard lock(mutex);
      out << line.dump() << '\n';
    });
    std::unique_ptr<panoptes::dds::Reader<panoptes::msg::EstimatorStatus>> status;
    if (with_status) {
      status = bus.make_reader<panoptes::msg::EstimatorStatus>([&](panoptes::msg::EstimatorStatus&& message) {
        nlohmann::json cameras = nlohmann::json::object();
        for (const auto& c : message.cameras()) {
          cameras[c.camera_id()] = {{"frames", c.frames()},
                                    {"used", c.used()},
                                    {"utilisation", c.utilisation()},
                                    {"state", c.state()},  // 0 live, 1 lost, 2 unknown (issue 34)
                                    {"since_last_frame_s", c.since_last_frame_s()},
                                    {"refused_frames", c.refused_frames()}};
        }
        nlohmann::json counters = nlohmann::json::object();
        for (const auto& c : message.counters()) counters[c.name()] = c.value();
        const nlohmann::json line = {{"type", "status"},
                                     {"recv_ns", panoptes::wall_now_ns()},
                                     {"frames", message.frames()},
                                     {"cameras", cameras},
                                     {"cameras_live", message.cameras_live()},
                                     {"cameras_lost", message.cameras_lost()},
                                     {"tracks_unobserved", message.tracks_unobserved()},
                                     {"counters", counters}};
        std::lock_guard lock(mutex);
        out << line.dump() << '\n';
      });
    }
    std::fprintf(stderr, "panoptes_track_probe: recording to %s\n", out_file.c_str());
    const panoptes::TimeNs end = panoptes::wall_now_ns() + panoptes::seconds_to_ns(duration_s);
    while (!panoptes::stop_requested() && (duration_s <= 0 || panoptes::wall_now_ns() < end)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      std::lock_guard lock(mutex);
      out.flush();
    }
    std::fprintf(stderr, "panoptes_track_probe: %llu track frames received\n",
                 static_cast<unsigned long long>(tracks->received()));
  } catch (
      const panoptes::InputError& error) {  // e.g. the DDS profile or Security files: refused before joining
    std::fprintf(stderr, "panoptes_track_probe: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_track_probe: %s\n", error.what());
    return panoptes::kExitFailure;
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_track_probe", [&] { return run(argc, argv); });
}
