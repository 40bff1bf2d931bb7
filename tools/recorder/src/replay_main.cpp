// SPDX-License-Identifier: Apache-2.0
// panoptes_replay: publishes an MCAP recording back onto the bus at the recorded pace
// (docs/recording.md); says whether it kept up.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/process.h"
#include "panoptes/recorder/replayer.h"
#include "panoptes/recording/mcap_types.h"

namespace {

int run(int argc, char** argv) {
  namespace rec = panoptes::recorder;
  std::string input;
  rec::ReplayOptions options;
  double discovery_s = 5.0;
  std::string dds_profile;
  CLI::App app{"panoptes_replay: publishes an MCAP recording back onto the bus at the recorded pace"};
  app.add_option("recording", input, "MCAP file written by panoptes_record")->required();
  panoptes::dds::add_domain_option(app);
  app.add_option("--rate", options.rate, "pace relative to the recording (0: as fast as possible)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--loop", options.loop, "start again at the end (until SIGINT)");
  app.add_option("--start", options.start_s, "skip the first seconds of the recording")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--end", options.end_s,
                 "stop this many seconds after the recording's first message (<0: at the end)")
      ->capture_default_str();
  app.add_option("--topics", options.topics, "topics to publish, DDS or ROS 2 names (default: all)");
  app.add_option("--late-ms", options.late_ms, "a message this far behind its schedule counts as late")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--discovery", discovery_s,
                 "wait at most this long for every topic to match a reader before publishing, s")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--dds-profile", dds_profile, "DDS XML profile (default: deploy/dds/loopback.xml)");
  app.add_flag(
      "!--no-restamp", options.restamp,
      "publish every message with its recorded times (default: every time shifted to now by one offset, as a "
      "live estimator and clients need)");
  app.add_flag("--quiet", options.quiet, "no progress lines");
  if (const auto code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (options.end_s >= 0 && options.end_s <= options.start_s)
          throw CLI::ValidationError("--end", "must be after --start");
      }))
    return *code;

  // A bad $PANOPTES_DOMAIN or DDS profile is refused before the recording is read.
  panoptes::dds::resolve_domain();
  panoptes::dds::resolve_profile_file(dds_profile);
  panoptes::install_stop_handlers();
  rec::Replayer replayer(input, options);
  for (const auto& problem : replayer.problems())
    std::fprintf(stderr, "panoptes_replay: %s\n", problem.c_str());
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = dds_profile;
  bus_options.participant_name = "panoptes_replay";
  panoptes::dds::Bus bus(bus_options);
  std::fprintf(stderr, "panoptes_replay: %s: %zu messages on %zu topics at rate %g\n", input.c_str(),
               replayer.messages().size(), replayer.topics().size(), options.rate);
  const auto report = replayer.run(bus, discovery_s, [] { return panoptes::stop_requested(); });
  if (options.restamp)
    std::fprintf(stderr, "panoptes_replay: times of every topic shifted by %lld ns\n",
                 static_cast<long long>(report.first_shift_ns));
  for (const auto& [topic, count] : report.per_topic)
    std::fprintf(stderr, "  %s: %llu\n", topic.c_str(), static_cast<unsigned long long>(count));
  const double achieved = report.wall_s > 0 ? report.recorded_s * report.passes / report.wall_s : 0;
  if (report.kept_up()) {
    std::fprintf(stderr, "panoptes_replay: published %llu messages; kept up (max lag %.1f ms, %.2fx)\n",
                 static_cast<unsigned long long>(report.published), report.max_lag_ms, achieved);
  } else {
    std::fprintf(
        stderr,
        "panoptes_replay: published %llu messages; could not keep up at --rate %g: %llu messages more "
        "than %g ms late, max lag %.1f ms, achieved %.2fx\n",
        static_cast<unsigned long long>(report.published), options.rate,
        static_cast<unsigned long long>(report.late), options.late_ms, report.max_lag_ms, achieved);
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  // panoptes_replay only reads recordings: every RecordingError is its input's.
  return panoptes::run_program<panoptes::recording::RecordingError>("panoptes_replay",
                                                                    [&] { return run(argc, argv); });
}
