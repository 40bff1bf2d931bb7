// SPDX-License-Identifier: Apache-2.0
// bench_client: the latency the client library adds on top of a raw DDS reader of the same topic
// (issue 15, docs/benchmarks.md). A child process (this program with --publish) writes the two
// bodies' BodyDescriptions, then MocapFrames (two tracked bodies, 8 labelled and 4 unlabelled
// markers) at --rate through a Bus writer, each stamped publish_ns just before write(). This process reads
// them twice, on two participants:
//   raw     a Bus::make_reader<msg::MocapFrame> (reliable, as the client by default): publish -> its callback
//   client  a panoptes::client::Client: publish -> a callback added with add_callback, and
//           publish -> wait_for_frame() returning in a thread that pulls
// and prints JSON: p50/p99/max of each, of the per-frame differences client - raw, and of the time
// the library itself spends (its receive_ns stamp -> delivery to the application).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/cli.h"
#include "panoptes/client/client.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace {

using panoptes::TimeNs;
using panoptes::wall_now_ns;
namespace msg = panoptes::msg;

msg::MocapFrame synthetic_frame(std::uint64_t number, TimeNs now) {
  msg::MocapFrame f;
  f.frame_number(number);
  f.stamp_ns(now - 3'000'000);
  f.source_camera("cam0");
  f.source_frame(static_cast<long long>(number));
  f.stages().feature_publish_ns(now - 2'000'000);
  f.stages().received_ns(now - 1'900'000);
  f.stages().dequeued_ns(now - 500'000);
  f.stages().updated_ns(now - 100'000);
  for (int b = 0; b < 2; ++b) {
    msg::FrameBody body;
    body.name(b == 0 ? "head" : "tool");
    body.id(b + 1);
    body.tracking_valid(true);
    body.pose().position({0.1 * b, 0.2, 1.5 + 1e-6 * static_cast<double>(number % 1000)});
    body.pose().orientation({0, 0, 0, 1});
    body.sigma({1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3});
    body.quality(1.0F);
    body.cameras(4);
    f.bodies().push_back(body);
  }
  for (int m = 0; m < 12; ++m) {
    msg::FrameMarker marker;
    marker.state().id(m + 1);
    marker.state().position({0.01 * m, 0.2, 1.5});
    marker.state().status(1);
    marker.state().cameras(4);
    marker.body(m < 4 ? "head" : m < 8 ? "tool" : "");
    marker.body_marker(m < 8 ? m % 4 : -1);
    f.markers().push_back(marker);
  }
  return f;
}

// The bodies of synthetic_frame, four markers each, as an estimator describes them.
msg::BodyDescriptions synthetic_descriptions() {
  msg::BodyDescriptions d;
  d.generation(1);
  for (int b = 0; b < 2; ++b) {
    msg::BodyDescription body;
    body.name(b == 0 ? "head" : "tool");
    body.id(b + 1);
    body.kind("passive");
    for (int m = 0; m < 4; ++m) {
      msg::MarkerPosition p;
      p.position({0.05 * m, 0.03 * (m % 2), 0.0});
      body.markers().push_back(p);
    }
    d.bodies().push_back(body);
  }
  return d;
}

int publish(double rate_hz, double duration_s, int readers) {
  panoptes::dds::Bus bus;
  auto descriptions = bus.make_writer<msg::BodyDescriptions>();
  descriptions->write(synthetic_descriptions());  // transient-local: readers get it when they match
  auto writer = bus.make_writer<msg::MocapFrame>();
  if (!writer->wait_for_readers(readers, std::chrono::seconds(10))) {
    std::fprintf(stderr, "bench_client --publish: %d readers did not match\n", readers);
    return panoptes::kExitFailure;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the readers fully matched
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  const auto start = std::chrono::steady_clock::now();
  const auto count = static_cast<std::uint64_t>(rate_hz * duration_s);
  for (std::uint64_t n = 1; n <= count && !panoptes::stop_requested(); ++n) {
    std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                              period * static_cast<double>(n)));
    msg::MocapFrame frame = synthetic_frame(n, wall_now_ns());
    frame.publish_ns(wall_now_ns());
    writer->write(frame);
  }
  writer->wait_for_acknowledgments(std::chrono::seconds(2));
  return panoptes::kExitOk;
}

// Per frame number, one slot per observer, each written by one thread only: no lock on the paths
// being measured.
struct Times {
  explicit Times(std::size_t frames)
      : publish(frames), raw(frames), callback(frames), pull(frames), library_receive(frames) {}
  std::vector<std::atomic<TimeNs>> publish, raw, callback, pull, library_receive;
  static void set(std::vector<std::atomic<TimeNs>>& slots, std::uint64_t n, TimeNs value) {
    if (n < slots.size()) slots[n].store(value, std::memory_order_relaxed);
  }
};

nlohmann::json summary(std::vector<double> us) {
  if (us.empty()) return nullptr;
  std::sort(us.begin(), us.end());
  auto at = [&](double q) { return us[static_cast<std::size_t>(q * static_cast<double>(us.size() - 1))]; };
  auto round3 = [](double v) { return std::round(v * 1000) / 1000; };
  return {{"p50_us", round3(at(0.5))}, {"p99_us", round3(at(0.99))}, {"max_us", round3(us.back())}};
}

int measure(double rate_hz, double duration_s, double warmup_s, bool client_first, const std::string& self) {
  const auto published = static_cast<std::uint64_t>(rate_hz * duration_s);
  Times times(published + 1);
  // Whichever participant matches first may be served first by the writer: --client-first swaps them.
  std::unique_ptr<panoptes::dds::Bus> raw_bus;
  std::unique_ptr<panoptes::dds::Reader<msg::MocapFrame>> raw;
  auto make_raw = [&] {
    panoptes::dds::BusOptions raw_options;
    raw_options.participant_name = "bench_client_raw";
    raw_bus = std::make_unique<panoptes::dds::Bus>(raw_options);
    raw = raw_bus->make_reader<msg::MocapFrame>(
        [&](msg::MocapFrame&& f) {
          const TimeNs now = wall_now_ns();
          Times::set(times.raw, f.frame_number(), now);
          Times::set(times.publish, f.frame_number(), f.publish_ns());
        },
        panoptes::dds::Qos::kReliable);
  };
  if (!client_first) make_raw();
  panoptes::client::Client client;
  client.add_callback([&](const panoptes::client::Frame& f) {
    const TimeNs now = wall_now_ns();
    Times::set(times.callback, f.frame_number, now);
    Times::set(times.library_receive, f.frame_number, f.receive_ns);
  });
  if (client_first) make_raw();
  std::atomic<bool> done{false};
  std::thread puller([&] {
    while (!done) {
      const auto result = client.wait_for_frame(std::chrono::milliseconds(100));
      const TimeNs now = wall_now_ns();
      if (result.status == panoptes::client::Status::kOk)
        Times::set(times.pull, result.frame.frame_number, now);
    }
  });
  const std::string log =
      (std::filesystem::temp_directory_path() / ("bench_client_" + std::to_string(getpid()) + ".log"))
          .string();
  {
    panoptes::ChildProcess publisher(
        "bench_client --publish",
        {self, "--publish", "--rate", std::to_string(rate_hz), "--duration", std::to_string(duration_s),
         "--domain", std::to_string(client.domain_id())},
        log);
    while (publisher.running() && !panoptes::stop_requested())
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::filesystem::remove(log);
  done = true;
  puller.join();
  std::vector<double> raw_us, callback_us, pull_us, added_callback_us, added_pull_us, library_callback_us,
      library_pull_us;
  std::size_t complete = 0;
  const auto skip = static_cast<std::uint64_t>(rate_hz * warmup_s);
  for (std::uint64_t n = skip + 1; n <= published; ++n) {
    const TimeNs publish = times.publish[n].load(), raw = times.raw[n].load(),
                 callback = times.callback[n].load(), pull = times.pull[n].load(),
                 library = times.library_receive[n].load();
    if (publish == 0 || raw == 0 || callback == 0 || pull == 0) continue;
    ++complete;
    raw_us.push_back((raw - publish) * 1e-3);
    callback_us.push_back((callback - publish) * 1e-3);
    pull_us.push_back((pull - publish) * 1e-3);
    added_callback_us.push_back((callback - raw) * 1e-3);
    added_pull_us.push_back((pull - raw) * 1e-3);
    library_callback_us.push_back((callback - library) * 1e-3);
    library_pull_us.push_back((pull - library) * 1e-3);
  }
  const auto stats = client.stats();
  nlohmann::json out = {
      {"benchmark", "client_latency"},
      {"rate_hz", rate_hz},
      {"created_first", client_first ? "client" : "raw"},
      {"duration_s", duration_s},
      {"frames_published", published},
      {"frames_measured", complete},
      {"client_frames_received", stats.frames_received},
      {"client_frames_missed", stats.frames_missed},
      {"client_frames_dropped", stats.frames_dropped},
      {"raw_reader", summary(raw_us)},
      {"client_callback", summary(callback_us)},
      {"client_wait_for_frame", summary(pull_us)},
      {"added_by_client_callback", summary(added_callback_us)},
      {"added_by_client_wait_for_frame", summary(added_pull_us)},
      {"library_receive_to_callback", summary(library_callback_us)},
      {"library_receive_to_wait_for_frame", summary(library_pull_us)},
  };
  if (!raw_us.empty() && !callback_us.empty()) {
    const auto p = [](const nlohmann::json& j, const char* k) { return j.at(k).get<double>(); };
    out["added_p50_us"] = p(out["client_callback"], "p50_us") - p(out["raw_reader"], "p50_us");
    out["added_p99_us"] = p(out["client_callback"], "p99_us") - p(out["raw_reader"], "p99_us");
  }
  std::printf("%s\n", out.dump(2).c_str());
  return complete > published / 2 ? panoptes::kExitOk : panoptes::kExitFailure;
}

int run(int argc, char** argv) {
  double rate_hz = 1000;
  double duration_s = 10;
  double warmup_s = 1;
  int domain = -1;
  bool publisher = false;
  bool client_first = false;
  int readers = 2;
  CLI::App app{"bench_client: latency the client library adds on top of a raw DDS reader (JSON on stdout)",
               "bench_client"};
  app.option_defaults()->always_capture_default();
  app.add_option("--rate", rate_hz, "MocapFrames per second")->check(CLI::Range(1.0, 20000.0));
  app.add_option("--duration", duration_s, "seconds of publishing")->check(CLI::PositiveNumber);
  app.add_option("--warmup", warmup_s, "seconds of frames left out of the statistics")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--domain", domain, "DDS domain (-1: $PANOPTES_DOMAIN, else 0)");
  app.add_flag("--client-first", client_first, "create the client's participant before the raw reader's");
  app.add_flag("--publish", publisher,
               "only publish (the measuring process starts one); also a frame source for tests");
  app.add_option("--readers", readers, "with --publish: start once this many readers matched")
      ->check(CLI::PositiveNumber);
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();
  // The publishing child gets the same domain; a bad one (or $PANOPTES_DOMAIN) is a usage error.
  setenv(panoptes::dds::kDomainVariable, std::to_string(panoptes::dds::resolve_domain(domain)).c_str(), 1);
  try {
    if (publisher) return publish(rate_hz, duration_s, readers);
    return measure(rate_hz, duration_s, warmup_s, client_first,
                   std::filesystem::read_symlink("/proc/self/exe").string());
  } catch (const panoptes::InputError& e) {  // e.g. the DDS profile
    std::fprintf(stderr, "bench_client: %s\n", e.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_client: %s\n", e.what());
    return panoptes::kExitFailure;
  }
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_client", [&] { return run(argc, argv); });
}
