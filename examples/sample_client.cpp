// SPDX-License-Identifier: Apache-2.0
// sample_client: prints every frame's bodies and markers, like NatNet's SampleClient
// (docs/clients.md). Uses only the installed client library: panoptes/client/client.h.
//   sample_client [--domain N] [--profile FILE] [--frames N] [--timeout-s S]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "panoptes/client/client.h"

namespace {

const char* const kUsage =
    "usage: sample_client [--domain N] [--profile FILE] [--frames N] [--timeout-s S]\n"
    "  --domain N     DDS domain, 0..232 (default: $PANOPTES_DOMAIN, else 0)\n"
    "  --profile FILE DDS XML profile (default: $PANOPTES_DDS_PROFILE, else the installed loopback.xml)\n"
    "  --frames N     exit after N frames (default 0: run until interrupted)\n"
    "  --timeout-s S  give up when no frame arrives for S seconds (default 5)\n";

int usage_error(const std::string& reason) {
  std::fprintf(stderr, "sample_client: %s\n%s", reason.c_str(), kUsage);
  return 2;
}

// --domain's value: a DDS domain id, 0..232 (the ids whose ports fit Fast DDS's port mapping);
// -1 for anything else (a sign, spaces, a fraction, a larger number).
int domain_id_of(const std::string& text) {
  if (text.empty() || text.size() > 3 || text.find_first_not_of("0123456789") != std::string::npos) return -1;
  const int id = std::stoi(text);
  return id <= 232 ? id : -1;
}

void print_frame(const panoptes::client::Frame& frame) {
  std::printf("frame %llu  stamp %.6f s  latency %.3f ms (capture->publish %.3f, publish->here %.3f)\n",
              static_cast<unsigned long long>(frame.frame_number), frame.stamp_ns * 1e-9,
              frame.latency.capture_to_receive_ns * 1e-6, frame.latency.capture_to_publish_ns * 1e-6,
              frame.latency.publish_to_receive_ns * 1e-6);
  for (const auto& b : frame.bodies) {
    std::printf(
        "  body %d %-10s %s  pos [%.4f %.4f %.4f] m  quat [%.4f %.4f %.4f %.4f]  mean error %.3f mm\n", b.id,
        b.name.c_str(), b.tracking_valid ? "tracked" : "LOST   ", b.position[0], b.position[1], b.position[2],
        b.orientation[0], b.orientation[1], b.orientation[2], b.orientation[3], b.mean_marker_error * 1e3);
  }
  for (const auto& m : frame.markers) {
    const std::string label =
        m.labelled() ? m.body + "[" + std::to_string(m.body_marker) + "]" : "unlabelled";
    std::printf("  marker %-5lld %-12s [%.4f %.4f %.4f] m%s\n", static_cast<long long>(m.id), label.c_str(),
                m.position[0], m.position[1], m.position[2], m.occluded ? "  (occluded)" : "");
  }
}

// The bodies the estimator describes, like NatNet's data descriptions. They come with the first
// frames (docs/clients.md, "Start in any order"); a publisher of frames alone sends none.
void print_descriptions(panoptes::client::Client& client) {
  const auto result = client.wait_for_descriptions(std::chrono::seconds(1));
  if (result.status != panoptes::client::Status::kOk) {
    std::fprintf(stderr, "sample_client: no body descriptions within 1 s\n");
    return;
  }
  std::printf("described bodies: %zu\n", result.descriptions.size());
  for (const auto& d : result.descriptions)
    std::printf("  description %d %-10s %s, %zu markers\n", d.id, d.name.c_str(), d.kind.c_str(),
                d.markers.size());
}

}  // namespace

int main(int argc, char** argv) {
  panoptes::client::ClientOptions options;
  long frames_wanted = 0;
  double timeout_s = 5.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") return std::printf("%s", kUsage), 0;
    if (i + 1 >= argc) return usage_error(arg + " needs a value");
    const std::string value = argv[++i];
    char* end = nullptr;
    if (arg == "--profile") {
      options.profile_file = value;
    } else if (arg == "--domain") {
      options.domain_id = domain_id_of(value);
      if (options.domain_id < 0)
        return usage_error("--domain " + value + ": not a DDS domain id (an integer 0..232)");
    } else if (arg == "--frames") {
      frames_wanted = std::strtol(value.c_str(), &end, 10);
      if (*end != '\0' || frames_wanted < 0) return usage_error("--frames " + value + ": not a count");
    } else if (arg == "--timeout-s") {
      timeout_s = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(timeout_s > 0))
        return usage_error("--timeout-s " + value + ": not a positive number");
    } else {
      return usage_error("unknown option " + arg);
    }
  }
  try {
    panoptes::client::Client client(options);
    std::fprintf(stderr, "sample_client: panoptes client %s, domain %d, DDS profile %s\n",
                 panoptes::client::version().c_str(), client.domain_id(), client.profile_file().c_str());
    const auto timeout = std::chrono::milliseconds(static_cast<long>(timeout_s * 1000));
    for (long received = 0; frames_wanted == 0 || received < frames_wanted; ++received) {
      const auto result = client.wait_for_frame(timeout);
      if (result.status != panoptes::client::Status::kOk) {
        std::fprintf(stderr, "sample_client: %s on domain %d (is estimator_node running?)\n",
                     client.status_text().c_str(), client.domain_id());
        return 1;
      }
      if (received == 0) print_descriptions(client);
      print_frame(result.frame);
    }
    const auto stats = client.stats();
    const auto rate = client.frame_rate();
    std::fprintf(stderr, "sample_client: frames at %.2f Hz (%s)\n", rate.hz,
                 rate.fixed ? "fixed rate" : "one per processed camera frame");
    if (const auto newest = client.latest()) {
      if (const auto timecode = client.timecode(*newest))  // fixed-rate frames only
        std::fprintf(stderr, "sample_client: the newest frame's timecode %s (%d frames a second)\n",
                     timecode->text.c_str(), timecode->rate_hz);
    }
    std::fprintf(stderr, "sample_client: received %llu frames, %llu missed, %llu malformed\n",
                 static_cast<unsigned long long>(stats.frames_received),
                 static_cast<unsigned long long>(stats.frames_missed),
                 static_cast<unsigned long long>(stats.frames_malformed));
    return 0;
  } catch (const panoptes::client::OptionError& e) {  // e.g. $PANOPTES_DOMAIN=abc: a usage error
    std::fprintf(stderr, "sample_client: %s\n", e.what());
    return 2;
  } catch (const panoptes::client::ClientError& e) {
    std::fprintf(stderr, "sample_client: %s\n", e.what());
    return 1;
  }
}
