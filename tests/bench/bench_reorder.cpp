// SPDX-License-Identifier: Apache-2.0
// bench_reorder: what waiting for late frames costs and what replaying them costs (issue 16).
// The ring rig of bench_estimator (32 cameras x 120 Hz, loose markers and rigid bodies) delivers
// its frames through a network that reorders them (the simulator's latency, latency_jitter and
// late_fraction keys). The estimator's own session (inbox + tracker, EstimatorSession::process_due:
// the live node's code path) takes them in arrival order on a virtual clock: frames that arrive
// while it is busy are taken together, as in the live loop. Each latency window is run on the
// same frames, one after the other in one process: tracker CPU time (this thread's), replays,
// frames replayed, the latency a frame's output adds after its arrival (window wait + queueing +
// update), and accuracy (loose-marker tracks and body positions against the truth).
//   bench_reorder [--json] [--cases 20/0,20,2,0] [--dense-ms <ms>] [--seconds <s>] ...
// A case is "window_ms" or "window_ms/dense_checkpoint_ms" (default --dense-ms), with ":full" when
// replayed frames are associated from scratch (tracker reuse_replay_associations off); the first
// case is the CPU reference: 20/0 is the estimator before issue 16 (20 ms window, sparse
// checkpoints).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <limits>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/simulator.h"
#include "ring_scene.h"

namespace {

using panoptes::FeatureFrame;
using panoptes::Scene;
using panoptes::TimeNs;
using panoptes::bench::kEpoch;
namespace est = panoptes::estimator;

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

struct Result {
  double window_ms = 0;
  double dense_ms = 0;
  bool full_replay = false;             // replayed frames associated from scratch
  std::size_t frames = 0, outputs = 0;  // measured frames; of those, in order (with an output)
  std::uint64_t late = 0, too_late = 0, replays = 0, replayed_frames = 0, reassociated = 0;
  double cpu_s = 0;  // this thread's CPU in the session's updates, measured part
  double simulated_s = 0;
  double added_p50_ms = 0, added_p99_ms = 0;  // output time minus arrival
  double track_rmse_mm = 0, body_rmse_mm = 0;
  double track_coverage = 0;  // markers with a published track within 1 cm, over checks
};

// Squared distance from `p` to the nearest of `tracks` (infinity when none).
double nearest_squared(const Eigen::Vector3d& p, const std::vector<panoptes::TrackRecord>& tracks) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& track : tracks) best = std::min(best, (track.p - p).squaredNorm());
  return best;
}

class Accuracy {
 public:
  explicit Accuracy(const Scene& scene) : scene_(scene) {}
  void check(const est::Tracker& tracker, panoptes::session::EstimatorSession& session) {
    const TimeNs stamp = tracker.last_stamp_ns();
    const auto tracks = tracker.current_tracks();
    for (const auto& marker : scene_.markers_at(stamp - kEpoch)) {
      const double d2 = nearest_squared(marker.p, tracks);
      ++marker_checks_;
      if (d2 < 1e-4) {
        ++markers_tracked_;
        track_sum_ += d2;
      }
    }
    const auto truth = scene_.bodies_at(stamp - kEpoch);
    for (const auto& pose : session.current_poses()) {
      for (const auto& body : truth) {
        if (body.name != pose.body) continue;
        body_sum_ += (pose.p - body.T_world_body.t).squaredNorm();
        ++body_checks_;
      }
    }
  }
  void fill(Result& r) const {
    r.track_rmse_mm =
        markers_tracked_ ? std::sqrt(track_sum_ / static_cast<double>(markers_tracked_)) * 1e3 : 0;
    r.body_rmse_mm = body_checks_ ? std::sqrt(body_sum_ / static_cast<double>(body_checks_)) * 1e3 : 0;
    r.track_coverage =
        marker_checks_ ? static_cast<double>(markers_tracked_) / static_cast<double>(marker_checks_) : 0;
  }

 private:
  const Scene& scene_;
  double track_sum_ = 0, body_sum_ = 0;
  std::size_t marker_checks_ = 0, markers_tracked_ = 0, body_checks_ = 0;
};

// Runs the frames (sorted by arrival) through a session with the given latency window on a
// virtual clock that advances by the measured wall time of each update.
Result run(const Scene& scene, const std::vector<FeatureFrame>& by_arrival, double window_ms, double dense_ms,
           bool full_replay, double warmup_s) {
  panoptes::session::EstimatorConfig config;
  config.node.latency_window_ms = window_ms;
  config.node.inbox_capacity = 1 << 16;
  config.tracker.dense_checkpoint_window_ns = panoptes::seconds_to_ns(dense_ms * 1e-3);
  config.tracker.reuse_replay_associations = !full_replay;
  panoptes::session::EstimatorSession session(config);
  est::Tracker& tracker = session.tracker();
  tracker.set_calibration(scene.calibration());
  tracker.set_bodies(scene.body_definitions());
  auto& inbox = session.inbox();
  const TimeNs measure_from = kEpoch + panoptes::seconds_to_ns(warmup_s);

  Result result;
  result.window_ms = window_ms;
  Accuracy accuracy(scene);
  std::vector<double> added_ms;
  std::uint64_t outputs_seen = 0;
  const auto stats_before = [&] { return tracker.stats(); };
  est::TrackerStats at_start{};
  bool measuring = false;
  TimeNs now = by_arrival.front().received_ns;
  std::size_t next = 0;
  while (next < by_arrival.size() || inbox.size() > 0) {
    while (next < by_arrival.size() && by_arrival[next].received_ns <= now) inbox.push(by_arrival[next++]);
    auto due = inbox.pop_due(now);
    if (due.empty()) {
      // Idle until the next arrival or until the oldest waiting frame falls due.
      TimeNs wake =
          next < by_arrival.size() ? by_arrival[next].received_ns : std::numeric_limits<TimeNs>::max();
      if (const auto oldest = inbox.next_due_ns()) wake = std::min(wake, *oldest);
      if (wake == std::numeric_limits<TimeNs>::max()) break;
      now = std::max(now + 1, wake);
      continue;
    }
    if (!measuring && now >= measure_from) {
      measuring = true;
      at_start = stats_before();
    }
    // The virtual clock advances by this thread's CPU time: the update times of an estimator
    // that has a core to itself, whatever else the machine is doing.
    const double cpu_begin = thread_cpu_s();
    session.process_due(due, [&](FeatureFrame& frame, est::FrameOutcome outcome) {
      if (!measuring) return;
      ++result.frames;
      if (outcome != est::FrameOutcome::kProcessed) return;
      ++result.outputs;
      const double elapsed_s = thread_cpu_s() - cpu_begin;
      added_ms.push_back(static_cast<double>(now - frame.received_ns) * 1e-6 + elapsed_s * 1e3);
      if (++outputs_seen % 16 == 0) accuracy.check(tracker, session);
    });
    const double cpu_s = thread_cpu_s() - cpu_begin;
    if (measuring) result.cpu_s += cpu_s;
    now += std::max<TimeNs>(1, panoptes::seconds_to_ns(cpu_s));
  }
  const auto& end = tracker.stats();
  result.late = end.frames_late - at_start.frames_late;
  result.too_late = end.frames_too_late - at_start.frames_too_late;
  result.replays = end.replays - at_start.replays;
  result.replayed_frames = end.replayed_frames - at_start.replayed_frames;
  result.reassociated = end.replayed_reassociated - at_start.replayed_reassociated;
  result.simulated_s = panoptes::ns_to_seconds(scene.duration_ns()) - warmup_s;
  result.added_p50_ms = percentile(added_ms, 0.5);
  result.added_p99_ms = percentile(added_ms, 0.99);
  accuracy.fill(result);
  return result;
}

std::string to_json(const Result& r, double cpu_reference_s) {
  char buffer[768];
  std::snprintf(
      buffer, sizeof buffer,
      "{\"window_ms\": %.3f, \"dense_ms\": %.3f, \"full_replay\": %s, \"frames\": %zu, \"outputs\": %zu, "
      "\"late\": "
      "%llu, \"too_late\": %llu, "
      "\"replays\": %llu, \"replayed_frames\": %llu, \"reassociated\": %llu, \"replays_per_s\": %.1f, "
      "\"replayed_frames_per_s\": %.1f, \"cpu_s\": %.4f, \"cpu_percent_of_core\": %.2f, "
      "\"cpu_ratio\": %.4f, \"added_latency_p50_ms\": %.4f, \"added_latency_p99_ms\": %.4f, "
      "\"track_rmse_mm\": %.4f, \"track_coverage\": %.5f, \"body_rmse_mm\": %.4f}",
      r.window_ms, r.dense_ms, r.full_replay ? "true" : "false", r.frames, r.outputs,
      static_cast<unsigned long long>(r.late), static_cast<unsigned long long>(r.too_late),
      static_cast<unsigned long long>(r.replays), static_cast<unsigned long long>(r.replayed_frames),
      static_cast<unsigned long long>(r.reassociated), static_cast<double>(r.replays) / r.simulated_s,
      static_cast<double>(r.replayed_frames) / r.simulated_s, r.cpu_s, 100.0 * r.cpu_s / r.simulated_s,
      cpu_reference_s > 0 ? r.cpu_s / cpu_reference_s : 0, r.added_p50_ms, r.added_p99_ms, r.track_rmse_mm,
      r.track_coverage, r.body_rmse_mm);
  return buffer;
}

int run_command_line(int argc, char** argv) {
  panoptes::bench::RingConfig config;
  config.bodies = 10;
  config.seconds = 3.0;
  config.network = {0.0003, 0.0012, 0.00015, 0.005, 0.002, 0.030};
  std::vector<std::string> cases = {"20/0", "20", "2", "0"};
  double dense_ms = panoptes::ns_to_seconds(est::TrackerOptions{}.dense_checkpoint_window_ns) * 1e3;
  std::uint64_t seed = 7;
  bool json = false;
  CLI::App app{"bench_reorder: cost and latency of late frames, by latency window (issue 16)",
               "bench_reorder"};
  app.option_defaults()->always_capture_default();
  app.add_flag("--json", json, "print one JSON object on the last line");
  app.add_option(
         "--cases", cases,
         "cases to compare: window_ms or window_ms/dense_checkpoint_ms, :full to associate replayed frames "
         "from scratch (the first is the CPU reference)")
      ->delimiter(',');
  app.add_option("--dense-ms", dense_ms, "tracker: a checkpoint before every frame this recent, ms (0: none)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--seconds", config.seconds, "simulated seconds measured (after the warm-up)")
      ->check(CLI::Range(0.1, 600.0));
  app.add_option("--warmup", config.warmup_s, "simulated seconds not measured")->check(CLI::Range(0.2, 60.0));
  app.add_option("--cameras", config.cameras, "cameras on the ring")->check(CLI::Range(2, 1000));
  app.add_option("--rate", config.rate_hz, "frame rate of every camera, Hz")->check(CLI::Range(1.0, 2000.0));
  app.add_option("--markers", config.markers, "loose markers")->check(CLI::Range(0, 10000));
  app.add_option("--bodies", config.bodies, "rigid bodies of 4 markers")->check(CLI::Range(0, 1000));
  app.add_option("--latency-min", config.network.latency_min_s, "per-camera latency, lowest, s");
  app.add_option("--latency-max", config.network.latency_max_s, "per-camera latency, highest, s");
  app.add_option("--jitter", config.network.jitter_s, "mean of the exponential per-frame jitter, s");
  app.add_option("--late-fraction", config.network.late_fraction, "frames held up much longer")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--late-min", config.network.late_min_s, "a held-up frame's extra delay, lowest, s");
  app.add_option("--late-max", config.network.late_max_s, "a held-up frame's extra delay, highest, s");
  app.add_option("--seed", seed, "scene seed");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  struct Case {
    double window_ms, dense_ms;
    bool full_replay;
  };
  std::vector<Case> parsed;
  for (const auto& spec : cases) {
    const auto colon = spec.find(':');
    const std::string text = spec.substr(0, colon);
    const std::string suffix = colon == std::string::npos ? "" : spec.substr(colon + 1);
    const auto slash = text.find('/');
    try {
      const double window = std::stod(text.substr(0, slash));
      const double dense = slash == std::string::npos ? dense_ms : std::stod(text.substr(slash + 1));
      if (window < 0 || dense < 0) throw std::invalid_argument("negative");
      if (!suffix.empty() && suffix != "full") throw std::invalid_argument("suffix");
      parsed.push_back({window, dense, suffix == "full"});
    } catch (const std::exception&) {
      std::fprintf(stderr, "bench_reorder: --cases: '%s' is not window_ms[/dense_ms][:full]\n", spec.c_str());
      return 2;
    }
  }
  if (parsed.empty()) parsed = {{20, 0, false}, {0, dense_ms, false}};

  const Scene scene =
      Scene::from_yaml_string(panoptes::bench::scene_yaml(config, seed), ".", "bench_reorder scene");
  auto frames = panoptes::bench::simulate(scene);
  std::stable_sort(frames.begin(), frames.end(), [](const FeatureFrame& a, const FeatureFrame& b) {
    return a.received_ns < b.received_ns;
  });
  std::size_t out_of_order = 0;
  TimeNs newest = 0;
  for (const auto& f : frames) {
    if (f.stamp_ns < newest) ++out_of_order;
    newest = std::max(newest, f.stamp_ns);
  }
  std::printf(
      "bench_reorder: %d cameras x %.0f Hz, %d markers + %d bodies; latency %.2f-%.2f ms per camera, jitter "
      "%.2f ms, %.2f%% held up %.0f-%.0f ms: %.1f%% of %zu frames arrive after a newer one; "
      "%.1f s measured after %.1f s\n",
      config.cameras, config.rate_hz, config.markers, config.bodies, config.network.latency_min_s * 1e3,
      config.network.latency_max_s * 1e3, config.network.jitter_s * 1e3, config.network.late_fraction * 100,
      config.network.late_min_s * 1e3, config.network.late_max_s * 1e3,
      100.0 * static_cast<double>(out_of_order) / static_cast<double>(frames.size()), frames.size(),
      config.seconds, config.warmup_s);
  std::printf("  %9s %8s %7s %8s %7s %8s %10s %9s %8s %8s %9s %9s %9s %9s %8s\n", "window ms", "dense ms",
              "replay", "late", "replays", "replay/s", "replayed/s", "reused/s", "cpu %", "cpu x",
              "added p50", "added p99", "track mm", "coverage", "body mm");
  std::vector<Result> results;
  std::string json_cases;
  for (const Case& c : parsed) {
    results.push_back(run(scene, frames, c.window_ms, c.dense_ms, c.full_replay, config.warmup_s));
    results.back().dense_ms = c.dense_ms;
    results.back().full_replay = c.full_replay;
    const Result& r = results.back();
    const double reference = results.front().cpu_s;
    std::printf(
        "  %9.1f %8.1f %7s %8llu %7llu %8.0f %10.0f %9.0f %8.1f %8.3f %9.3f %9.3f %9.4f %9.4f %8.4f\n",
        r.window_ms, r.dense_ms, r.full_replay ? "full" : "reuse", static_cast<unsigned long long>(r.late),
        static_cast<unsigned long long>(r.replays), static_cast<double>(r.replays) / r.simulated_s,
        static_cast<double>(r.replayed_frames) / r.simulated_s,
        static_cast<double>(r.reassociated) / r.simulated_s, 100.0 * r.cpu_s / r.simulated_s,
        r.cpu_s / reference, r.added_p50_ms, r.added_p99_ms, r.track_rmse_mm, r.track_coverage,
        r.body_rmse_mm);
    std::fflush(stdout);
    json_cases += (json_cases.empty() ? "" : ", ") + to_json(r, reference);
  }
  if (json) {
    std::printf(
        "{\"cameras\": %d, \"rate_hz\": %.1f, \"markers\": %d, \"bodies\": %d, "
        "\"out_of_order_fraction\": %.5f, \"cases\": [%s]}\n",
        config.cameras, config.rate_hz, config.markers, config.bodies,
        static_cast<double>(out_of_order) / static_cast<double>(frames.size()), json_cases.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_reorder", [&] { return run_command_line(argc, argv); });
}
