// SPDX-License-Identifier: Apache-2.0
// panoptes_client_probe: an application built on the client library (panoptes/client/client.h
// only), for tests/integration/test_client.sh. Pulls frames with wait_for_frame() and writes one
// JSON line per frame (numbers, stamps, every body with full double precision, marker counts), one
// per change of the body descriptions, and the client's Stats at the end.
#include <chrono>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/client/client.h"
#include "panoptes/process.h"

namespace {

using nlohmann::json;
namespace pc = panoptes::client;

json frame_line(const pc::Frame& frame) {
  json bodies = json::array();
  for (const auto& b : frame.bodies) {
    bodies.push_back({{"name", b.name},
                      {"id", b.id},
                      {"valid", b.tracking_valid},
                      {"p", b.position},
                      {"q", b.orientation},
                      {"v", b.linear_velocity},
                      {"w", b.angular_velocity},
                      {"sigma", b.sigma},
                      {"horizon_ns", b.prediction_horizon_ns},
                      {"cameras", b.cameras},
                      {"mean_marker_error", b.mean_marker_error}});
  }
  int labelled = 0;
  int named = 0;
  for (const auto& m : frame.markers) {
    labelled += m.labelled() ? 1 : 0;
    named += m.named() ? 1 : 0;
  }
  return {{"type", "frame"},
          {"frame", frame.frame_number},
          {"stamp_ns", frame.stamp_ns},
          {"publish_ns", frame.publish_ns},
          {"receive_ns", frame.receive_ns},
          {"capture_to_receive_ns", frame.latency.capture_to_receive_ns},
          {"update_ns", frame.latency.update_ns},
          {"output_ns", frame.latency.output_ns},
          {"bodies", bodies},
          {"markers", frame.markers.size()},
          {"labelled", labelled},
          {"named", named}};
}

// The frame's markers as estimator_node --out-labels writes them (tests/integration/score_labels.py):
// every confirmed marker with its position, and the subject's name on the named ones.
json labels_line(const pc::Frame& frame) {
  json tracks = json::array();
  for (const auto& m : frame.markers) {
    if (m.occluded) continue;
    json entry{{"track", m.id}, {"p", m.position}};
    if (m.named()) {
      entry["subject"] = m.subject;
      entry["marker"] = m.name;
    }
    tracks.push_back(std::move(entry));
  }
  return {{"stamp_ns", frame.stamp_ns}, {"tracks", tracks}};
}

json descriptions_line(const std::vector<pc::BodyDescription>& descriptions, std::int64_t at_ns) {
  json bodies = json::array();
  for (const auto& d : descriptions)
    bodies.push_back({{"name", d.name}, {"id", d.id}, {"kind", d.kind}, {"markers", d.markers}});
  return {{"type", "descriptions"}, {"receive_ns", at_ns}, {"bodies", bodies}};
}

json stats_line(const pc::Stats& s) {
  return {{"type", "stats"},
          {"frames_received", s.frames_received},
          {"frames_dropped", s.frames_dropped},
          {"frames_missed", s.frames_missed},
          {"frames_malformed", s.frames_malformed},
          {"descriptions_received", s.descriptions_received},
          {"descriptions_malformed", s.descriptions_malformed},
          {"estimator_restarts", s.estimator_restarts},
          {"labels_received", s.labels_received},
          {"labels_malformed", s.labels_malformed},
          {"callback_errors", s.callback_errors},
          {"last_error", s.last_error}};
}

std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int run(int argc, char** argv) {
  std::string out_file;
  std::string out_labels;
  double duration_s = 10;
  pc::ClientOptions options;
  CLI::App app{"panoptes_client_probe: records the frames a panoptes::client::Client receives as JSON lines",
               "panoptes_client_probe"};
  app.option_defaults()->always_capture_default();
  app.add_option("--out", out_file, "JSONL file to write")->required();
  app.add_option("--out-labels", out_labels,
                 "also the frames' named markers as JSONL (estimator_node --out-labels' format)");
  app.add_option("--duration", duration_s, "stop after this many seconds")->check(CLI::PositiveNumber);
  app.add_option("--domain", options.domain_id, "DDS domain")
      ->check(CLI::Range(0, 232))  // the client library's ids; a negative one is not "the environment"
      ->default_str("$PANOPTES_DOMAIN, else 0");
  app.add_option("--dds-profile", options.profile_file, "Fast DDS XML profile (empty: the client's default)");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();
  std::ofstream out(out_file);
  if (!out) {
    std::fprintf(stderr, "panoptes_client_probe: cannot write %s\n", out_file.c_str());
    return panoptes::kExitBadInput;
  }
  std::ofstream labels_out;
  if (!out_labels.empty()) {
    labels_out.open(out_labels);
    if (!labels_out) {
      std::fprintf(stderr, "panoptes_client_probe: cannot write %s\n", out_labels.c_str());
      return panoptes::kExitBadInput;
    }
  }
  try {
    pc::Client client(options);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
    std::uint64_t descriptions_seen = 0;
    while (!panoptes::stop_requested() && std::chrono::steady_clock::now() < end) {
      const pc::FrameResult result = client.wait_for_frame(std::chrono::milliseconds(100));
      if (result.status == pc::Status::kOk) {
        json line = frame_line(result.frame);
        if (const auto timecode = client.timecode(result.frame)) {  // fixed-rate frames (docs/frames.md)
          line["timecode"] = {timecode->hours, timecode->minutes, timecode->seconds, timecode->frames};
          line["timecode_text"] = timecode->text;
        }
        out << line.dump() << '\n';
        if (labels_out.is_open()) labels_out << labels_line(result.frame).dump() << '\n';
      }
      const std::uint64_t received = client.stats().descriptions_received;
      if (received != descriptions_seen) {
        descriptions_seen = received;
        out << descriptions_line(client.body_descriptions(), wall_ns()).dump() << '\n';
      }
    }
    out << stats_line(client.stats()).dump() << '\n';
    std::fprintf(stderr, "panoptes_client_probe: %s\n", client.status_text().c_str());
  } catch (const pc::OptionError& e) {  // e.g. $PANOPTES_DOMAIN=abc
    std::fprintf(stderr, "panoptes_client_probe: %s\n", e.what());
    return panoptes::kExitBadInput;
  } catch (const pc::ClientError& e) {
    std::fprintf(stderr, "panoptes_client_probe: %s\n", e.what());
    return panoptes::kExitFailure;
  }
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_client_probe", [&] { return run(argc, argv); });
}
