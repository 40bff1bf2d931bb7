// SPDX-License-Identifier: Apache-2.0
// panoptes_feature_probe: a subscriber to FeatureFrames and CameraStatus, as the console and the
// estimator read them, for the subscriber-restart stress script (tests/stress/subscriber_restart.sh).
// Every --period seconds it appends one JSON line: the samples received so far per camera on each
// topic, the writers each reader matched, and the samples the bus rejected, by reason.
#include <chrono>
#include <cstdio>
#include <exception>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace {

struct PerCamera {
  std::mutex mutex;
  std::map<std::string, std::uint64_t> features;
  std::map<std::string, std::uint64_t> status;
  std::map<std::string, panoptes::TimeNs> first_feature_ns;
};

int run(int argc, char** argv) {
  std::string out_file;
  std::string dds_profile;
  double period_s = 1.0;
  double duration_s = 0;
  CLI::App app{"panoptes_feature_probe: counts FeatureFrames and CameraStatus per camera as JSON lines",
               "panoptes_feature_probe"};
  app.option_defaults()->always_capture_default();
  app.add_option("--out", out_file, "JSONL file to append to")->required();
  app.add_option("--dds-profile", dds_profile, "Fast DDS XML profile")
      ->default_str("$PANOPTES_DDS_PROFILE or deploy/dds/loopback.xml");
  app.add_option("--period", period_s, "seconds between lines")->check(CLI::PositiveNumber);
  app.add_option("--duration", duration_s, "stop after this many seconds (0 = until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();

  std::ofstream out(out_file, std::ios::app);
  if (!out) {
    std::fprintf(stderr, "panoptes_feature_probe: cannot write %s\n", out_file.c_str());
    return panoptes::kExitBadInput;
  }
  PerCamera counts;
  try {
    panoptes::dds::BusOptions options;
    options.profile_file = dds_profile;
    options.participant_name = "panoptes_feature_probe";
    panoptes::dds::Bus bus(options);
    const panoptes::TimeNs started_ns = panoptes::wall_now_ns();
    auto features = bus.make_reader<panoptes::msg::FeatureFrame>([&](panoptes::msg::FeatureFrame&& frame) {
      std::lock_guard lock(counts.mutex);
      if (counts.features[frame.camera_id()]++ == 0)
        counts.first_feature_ns[frame.camera_id()] = panoptes::wall_now_ns();
    });
    auto status = bus.make_reader<panoptes::msg::CameraStatus>([&](panoptes::msg::CameraStatus&& message) {
      std::lock_guard lock(counts.mutex);
      ++counts.status[message.camera_id()];
    });
    const auto period = std::chrono::duration<double>(period_s);
    const panoptes::TimeNs end = started_ns + panoptes::seconds_to_ns(duration_s);
    while (!panoptes::stop_requested() && (duration_s <= 0 || panoptes::wall_now_ns() < end)) {
      std::this_thread::sleep_for(period);
      nlohmann::json line = {{"t_s", static_cast<double>(panoptes::wall_now_ns() - started_ns) * 1e-9},
                             {"features_writers", features->matched_writers()},
                             {"status_writers", status->matched_writers()},
                             {"rejected", bus.receive_rejections()}};
      {
        std::lock_guard lock(counts.mutex);
        line["features"] = counts.features;
        line["status"] = counts.status;
        nlohmann::json first = nlohmann::json::object();
        for (const auto& [id, ns] : counts.first_feature_ns)
          first[id] = static_cast<double>(ns - started_ns) * 1e-9;
        line["first_feature_s"] = first;
      }
      out << line.dump() << '\n';
      out.flush();
    }
  } catch (const panoptes::InputError& error) {  // e.g. $PANOPTES_DOMAIN=abc, the DDS profile, Security files
    std::fprintf(stderr, "panoptes_feature_probe: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_feature_probe: %s\n", error.what());
    return panoptes::kExitFailure;
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_feature_probe", [&] { return run(argc, argv); });
}
