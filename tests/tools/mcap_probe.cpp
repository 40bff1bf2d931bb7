// SPDX-License-Identifier: Apache-2.0
// panoptes_mcap_probe: reads an MCAP recording with panoptes_recording's reader (for
// tests/integration/test_recording.sh) and prints one JSON object: messages per topic, chunks read
// and skipped, problems, the last log time per topic and, with --until-ns T, how many messages per
// topic have a log time <= T. With --features-jsonl FILE it also writes the recording's
// FeatureFrames as the JSONL that estimator_node --in-features reads (the offline JSONL path).
#include <cstdio>
#include <exception>
#include <fstream>
#include <map>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/estimator_app/recording_input.h"
#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/recording/mcap_reader.h"

namespace {

int run(int argc, char** argv) {
  std::string input;
  std::string features_jsonl;
  std::uint64_t until_ns = 0;
  CLI::App app{"panoptes_mcap_probe: what panoptes_recording's reader recovers from an MCAP file, as JSON",
               "panoptes_mcap_probe"};
  app.add_option("recording", input, "MCAP file")->required();
  app.add_option("--until-ns", until_ns, "also count the messages with a log time <= this");
  app.add_option("--features-jsonl", features_jsonl, "write the FeatureFrames as JSONL here");
  if (const auto code = panoptes::parse_command_line(app, argc, argv)) return *code;
  try {
    panoptes::recording::McapReader reader(input);
    std::map<std::string, std::uint64_t> per_topic;
    std::map<std::string, std::uint64_t> until;
    std::map<std::string, std::uint64_t> last;
    const auto report = reader.read([&](const panoptes::recording::MessageView& m) {
      ++per_topic[m.channel->topic];
      if (m.log_time <= until_ns) ++until[m.channel->topic];
      last[m.channel->topic] = std::max(last[m.channel->topic], m.log_time);
    });
    nlohmann::json out = {{"messages", report.messages},
                          {"topics", per_topic},
                          {"until", until},
                          {"last_log_time", last},
                          {"chunks", report.chunks},
                          {"chunks_skipped", report.chunks_skipped},
                          {"records_skipped", report.records_skipped},
                          {"summary", report.summary},
                          {"problems", report.problems}};
    if (!features_jsonl.empty()) {
      const auto features = panoptes::estimator_app::read_recording_features(input);
      std::ofstream file(features_jsonl);
      for (const auto& frame : features.frames) file << panoptes::to_json_line(frame) << '\n';
      out["features_written"] = features.frames.size();
    }
    std::printf("%s\n", out.dump().c_str());
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "panoptes_mcap_probe: %s\n", error.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_mcap_probe", [&] { return run(argc, argv); });
}
