// SPDX-License-Identifier: Apache-2.0
// bench_estimator: Tracker::process on one thread, offline, on precomputed simulated features.
// A ring of cameras around a 6 x 6 m room looking inward, markers on Lissajous paths, 0.1 px
// centroid noise. Reports observations (blobs) per second, per-frame latency p50/p99, the
// real-time factor (simulated time / processing time: above 1 the tracker keeps up with the rig),
// and the cost per observation as the marker count grows. Warm-up (track initiation and
// confirmation) is processed first and not timed.
//   bench_estimator [--json] [--seconds <s>] [--warmup <s>] [--cameras <n>] [--rate <hz>]
//                   [--markers <n>] [--sweep <n,n,...> | --no-sweep] [--bodies <n>] [--seed <n>]
//                   [--chain-frames <n>]
// The chain case (issue 21) times one camera frame's update of a 4-marker finger chain
// (ChainFilter::process: predict, gate, 4 sequential updates) side by side with a rigid body of the same 4
// markers through the body EKF (body_ekf.h, same gating and updates), on the same frames.
//                   [--inside-out-seconds <s>]
// With --json the last line of output is one JSON object (docs/benchmarks.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <CLI/CLI.hpp>

#include "chain_fixtures.h"
#include "inside_out_case.h"
#include "panoptes/cli.h"
#include "panoptes/estimator/body_ekf.h"
#include "panoptes/estimator/chain.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/simulator.h"
#include "ring_scene.h"

namespace {

using panoptes::Scene;
using panoptes::TimeNs;
namespace est = panoptes::estimator;

using panoptes::bench::kEpoch;
using panoptes::bench::RingConfig;
using panoptes::bench::scene_yaml;
using panoptes::bench::simulate;

// Markers with a published track within 1 cm at the tracker's last stamp.
int markers_tracked(const est::Tracker& tracker, const Scene& scene) {
  const auto tracks = tracker.current_tracks();
  int tracked = 0;
  for (const auto& marker : scene.markers_at(tracker.last_stamp_ns() - kEpoch)) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& track : tracks) nearest = std::min(nearest, (track.p - marker.p).norm());
    if (nearest < 0.01) ++tracked;
  }
  return tracked;
}

struct Result {
  int markers = 0;
  int cameras = 0;
  std::size_t frames = 0;   // timed
  std::uint64_t blobs = 0;  // timed observations
  double process_s = 0;     // sum of the timed Tracker::process calls
  double p50_us = 0, p99_us = 0, max_us = 0;
  int tracked_at_start = 0;  // markers with a confirmed track when timing starts
  int tracked_at_end = 0;
  std::size_t tracks_at_end = 0;  // published tracks (false ones included)
  double simulated_s = 0;
  double observations_per_s() const { return process_s > 0 ? static_cast<double>(blobs) / process_s : 0; }
  double us_per_observation() const { return blobs > 0 ? process_s * 1e6 / static_cast<double>(blobs) : 0; }
  double realtime_factor() const { return process_s > 0 ? simulated_s / process_s : 0; }
};

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// `calibration_mode`: the continuous calibration's mode (off | detect | correct; "": the default).
Result run(const RingConfig& config, std::uint64_t seed, bool track_bodies = false,
           std::size_t* bodies_tracked = nullptr, const std::string& calibration_mode = "") {
  const Scene scene = Scene::from_yaml_string(scene_yaml(config, seed), ".", "bench_estimator scene");
  const auto frames = simulate(scene);
  est::TrackerOptions options;
  if (!calibration_mode.empty()) options.calibration.mode = calibration_mode;
  est::Tracker tracker(options);
  tracker.set_calibration(scene.calibration());
  if (track_bodies) tracker.set_bodies(scene.body_definitions());
  const TimeNs timed_from = kEpoch + panoptes::seconds_to_ns(config.warmup_s);

  Result result;
  result.markers = config.markers;
  result.cameras = config.cameras;
  result.simulated_s = config.seconds;
  std::size_t i = 0;
  for (; i < frames.size() && frames[i].stamp_ns < timed_from; ++i) tracker.process(frames[i]);
  result.tracked_at_start = markers_tracked(tracker, scene);

  std::vector<double> latencies;
  latencies.reserve(frames.size() - i);
  for (; i < frames.size(); ++i) {
    const auto begin = std::chrono::steady_clock::now();
    tracker.process(frames[i]);
    const auto end = std::chrono::steady_clock::now();
    latencies.push_back(std::chrono::duration<double>(end - begin).count());
    result.blobs += frames[i].blobs.size();
  }
  result.frames = latencies.size();
  for (double latency : latencies) result.process_s += latency;
  result.p50_us = percentile(latencies, 0.5) * 1e6;
  result.p99_us = percentile(latencies, 0.99) * 1e6;
  result.max_us = latencies.empty() ? 0 : *std::max_element(latencies.begin(), latencies.end()) * 1e6;
  result.tracked_at_end = markers_tracked(tracker, scene);
  result.tracks_at_end = tracker.current_tracks().size();
  if (bodies_tracked) *bodies_tracked = tracker.current_poses().size();
  return result;
}

std::string to_json(const Result& r) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer,
                "{\"markers\": %d, \"cameras\": %d, \"frames\": %zu, \"observations\": %llu, "
                "\"observations_per_s\": %.0f, \"us_per_observation\": %.4f, \"frame_p50_us\": %.2f, "
                "\"frame_p99_us\": %.2f, \"frame_max_us\": %.1f, \"realtime_factor\": %.3f, "
                "\"tracked_at_start\": %d, \"tracked_at_end\": %d, \"tracks_at_end\": %zu}",
                r.markers, r.cameras, r.frames, static_cast<unsigned long long>(r.blobs),
                r.observations_per_s(), r.us_per_observation(), r.p50_us, r.p99_us, r.max_us,
                r.realtime_factor(), r.tracked_at_start, r.tracked_at_end, r.tracks_at_end);
  return buffer;
}

void print_row(const Result& r) {
  std::printf("  %7d %8zu %11llu %12.0f %10.3f %9.1f %9.1f %9.2f %6d/%-4d %6d/%-4d %6zu\n", r.markers,
              r.frames, static_cast<unsigned long long>(r.blobs), r.observations_per_s(),
              r.us_per_observation(), r.p50_us, r.p99_us, r.realtime_factor(), r.tracked_at_start, r.markers,
              r.tracked_at_end, r.markers, r.tracks_at_end);
}

// ---- Chain case (issue 21) ----

struct ChainCost {
  int frames = 0;
  double chain_us = 0.0;  // per camera frame
  double body_us = 0.0;
  long chain_updates = 0;
  long body_updates = 0;
};

// The rigid-body counterpart of update_chain_frame: the same gate and sequential updates.
int update_body_frame(est::BodyState& state, const std::vector<Eigen::Vector3d>& markers,
                      const panoptes::CameraModel& camera, const std::vector<Eigen::Vector2d>& blobs,
                      double sigma_px, double gate_chi2) {
  int updated = 0;
  for (const Eigen::Vector3d& marker : markers) {
    const auto projection = est::project_marker(state, marker, camera, sigma_px);
    if (!projection) continue;
    int chosen = -1, in_gate = 0;
    for (std::size_t b = 0; b < blobs.size(); ++b) {
      if (est::mahalanobis2(*projection, blobs[b]) > gate_chi2) continue;
      ++in_gate;
      chosen = static_cast<int>(b);
    }
    if (in_gate != 1) continue;
    est::update(state, *projection, blobs[chosen], sigma_px);
    ++updated;
  }
  return updated;
}

ChainCost run_chain_case(int frame_count, std::uint64_t seed) {
  const panoptes::ChainDefinition finger = est::test_finger();
  const est::FingerScene scene(30.0, static_cast<unsigned>(seed));
  const std::vector<panoptes::CameraModel> cameras = est::make_ring_cameras(4, 1.9, 1.6);
  std::mt19937 rng(static_cast<unsigned>(seed));
  // The rigid body: the finger's markers frozen at rest, tracked through the same frames.
  const est::FingerTruth rest = scene.truth(0.0);
  const est::ChainShape rest_shape = est::chain_shape(finger, rest.angles);
  const std::vector<Eigen::Vector3d> body_markers(rest_shape.markers.begin(), rest_shape.markers.begin() + 4);
  struct Frame {
    int camera;
    TimeNs stamp_ns;
    std::vector<Eigen::Vector2d> chain_blobs, body_blobs;
  };
  std::vector<Frame> frames;
  for (const est::SimFrame& frame : est::asynchronous_frames(4, 100.0, scene.duration_s())) {
    if (static_cast<int>(frames.size()) >= frame_count) break;
    const est::FingerTruth truth = scene.truth(panoptes::ns_to_seconds(frame.stamp_ns));
    std::vector<Eigen::Vector3d> chain_points = est::FingerScene::markers(finger, truth);
    std::vector<Eigen::Vector3d> body_points;
    for (const Eigen::Vector3d& marker : body_markers) body_points.push_back(truth.base.apply(marker));
    for (const Eigen::Vector3d& reflection : est::FingerScene::reflections()) {
      chain_points.push_back(reflection);
      body_points.push_back(reflection);
    }
    frames.push_back({frame.camera, frame.stamp_ns,
                      est::observe(cameras[frame.camera], chain_points, 0.1, rng),
                      est::observe(cameras[frame.camera], body_points, 0.1, rng)});
  }
  est::ChainIdentification identification;
  identification.base_pose = rest.base;
  identification.angles = rest.angles;
  est::ChainFilter chain(finger,
                         est::chain_state_from_identification(identification, 0, est::test_chain_prior(), 2),
                         est::ChainMotionNoise{}, est::ChainUpdateOptions{});
  est::BodyState body;
  body.p = rest.base.t;
  body.q = rest.base.q;
  body.P = est::body_prior(est::test_chain_prior().base);
  const est::ChainMotionNoise chain_noise;
  const est::ChainUpdateOptions options;
  ChainCost cost;
  cost.frames = static_cast<int>(frames.size());
  using Clock = std::chrono::steady_clock;
  // Interleaved per frame, so both see the same machine state.
  Clock::duration chain_time{}, body_time{};
  for (const Frame& frame : frames) {
    const auto t0 = Clock::now();
    cost.chain_updates +=
        chain.process(cameras[frame.camera], frame.stamp_ns, frame.chain_blobs).markers_updated;
    const auto t1 = Clock::now();
    est::predict(body, frame.stamp_ns, chain_noise.base);
    cost.body_updates += update_body_frame(body, body_markers, cameras[frame.camera], frame.body_blobs,
                                           options.measurement_sigma_px, options.gate_chi2);
    const auto t2 = Clock::now();
    chain_time += t1 - t0;
    body_time += t2 - t1;
  }
  cost.chain_us = std::chrono::duration<double, std::micro>(chain_time).count() / cost.frames;
  cost.body_us = std::chrono::duration<double, std::micro>(body_time).count() / cost.frames;
  return cost;
}

std::string chain_case_json(const ChainCost& cost) {
  char buffer[256];
  std::snprintf(
      buffer, sizeof buffer,
      "{\"frames\": %d, \"chain_us_per_frame\": %.3f, \"body_us_per_frame\": %.3f, \"ratio\": %.3f, "
      "\"chain_marker_updates\": %ld, \"body_marker_updates\": %ld}",
      cost.frames, cost.chain_us, cost.body_us, cost.chain_us / cost.body_us, cost.chain_updates,
      cost.body_updates);
  return buffer;
}

// The inside-out case (inside_out_case.h), printed; returns its JSON.
std::string print_inside_out_case(double seconds, std::uint64_t seed) {
  const auto r = panoptes::bench::run_inside_out_case(
      std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/inside_out.yaml", 0.5, seconds, seed);
  std::printf(
      "inside-out: head camera, %d landmarks, %.1f blobs per frame, %zu frames timed: %.2f us per frame "
      "(p50 %.1f, p99 %.1f us; cold start %.1f ms)\n"
      "  a %d-marker rigid body from the same pixels (plus a second camera): Tracker::process %.2f us per "
      "frame "
      "(p50 %.1f, p99 %.1f us), %.2f us without the body: the body costs %.2f us per frame; posed after "
      "%zu/%zu frames, %llu (re-)identifications while timed\n",
      r.landmarks, r.blobs_per_frame, r.frames, r.inside_out_us, r.inside_out_p50_us, r.inside_out_p99_us,
      r.cold_start_ms, r.landmarks, r.tracker_us, r.tracker_p50_us, r.tracker_p99_us, r.points_only_us,
      r.tracker_us - r.points_only_us, r.body_frames, r.frames,
      static_cast<unsigned long long>(r.body_identifications));
  char buffer[640];
  std::snprintf(
      buffer, sizeof buffer,
      "{\"landmarks\": %d, \"frames\": %zu, \"blobs_per_frame\": %.2f, \"us_per_frame\": %.3f, "
      "\"p50_us\": %.2f, \"p99_us\": %.2f, \"cold_start_ms\": %.2f, \"body_tracker_us_per_frame\": %.3f, "
      "\"body_tracker_p50_us\": %.2f, \"body_tracker_p99_us\": %.2f, \"points_only_us_per_frame\": %.3f, "
      "\"body_frames\": %zu, \"body_identifications\": %llu}",
      r.landmarks, r.frames, r.blobs_per_frame, r.inside_out_us, r.inside_out_p50_us, r.inside_out_p99_us,
      r.cold_start_ms, r.tracker_us, r.tracker_p50_us, r.tracker_p99_us, r.points_only_us, r.body_frames,
      static_cast<unsigned long long>(r.body_identifications));
  return buffer;
}

// The continuous calibration's cost (issue 36: with `correct` at most 1.1x `off`): one tracker per
// mode, fed the same simulated frames, every frame processed by all three in turn (the order
// rotating from frame to frame) and each call timed, so that the machine's load, its clock and the
// allocator's state weigh on every mode alike (running each mode's whole case in turn, the ratio
// went from 0.95 to 1.37 between calls); `rounds` repeats the interleaved run.
std::string print_calibration_case(const RingConfig& config, std::uint64_t seed, int rounds) {
  const std::vector<std::string> modes = {"off", "detect", "correct"};
  std::vector<double> seconds(modes.size(), 0.0);
  std::vector<std::size_t> frames(modes.size(), 0);
  const Scene scene = Scene::from_yaml_string(scene_yaml(config, seed), ".", "bench_estimator scene");
  const auto simulated = simulate(scene);
  const TimeNs timed_from = kEpoch + panoptes::seconds_to_ns(config.warmup_s);
  for (int round = 0; round < rounds; ++round) {
    std::vector<std::unique_ptr<est::Tracker>> trackers;
    for (const auto& mode : modes) {
      est::TrackerOptions options;
      options.calibration.mode = mode;
      trackers.push_back(std::make_unique<est::Tracker>(options));
      trackers.back()->set_calibration(scene.calibration());
    }
    for (std::size_t i = 0; i < simulated.size(); ++i) {
      const bool timed = simulated[i].stamp_ns >= timed_from;
      for (std::size_t k = 0; k < modes.size(); ++k) {
        const std::size_t m = (i + k) % modes.size();
        const auto begin = std::chrono::steady_clock::now();
        trackers[m]->process(simulated[i]);
        const auto end = std::chrono::steady_clock::now();
        if (!timed) continue;
        seconds[m] += std::chrono::duration<double>(end - begin).count();
        ++frames[m];
      }
    }
  }
  const auto us = [&](std::size_t m) {
    return seconds[m] * 1e6 / static_cast<double>(std::max<std::size_t>(frames[m], 1));
  };
  std::printf(
      "continuous calibration: %d cameras x %.0f Hz, %d markers, %d rounds, frame by frame in turn: "
      "Tracker::process "
      "%.2f us per frame with off, %.2f with detect (%.3fx), %.2f with correct (%.3fx)\n",
      config.cameras, config.rate_hz, config.markers, rounds, us(0), us(1), us(1) / us(0), us(2),
      us(2) / us(0));
  char buffer[320];
  std::snprintf(buffer, sizeof buffer,
                "{\"rounds\": %d, \"off_us_per_frame\": %.3f, \"detect_us_per_frame\": %.3f, "
                "\"correct_us_per_frame\": %.3f, \"detect_over_off\": %.4f, \"correct_over_off\": %.4f}",
                rounds, us(0), us(1), us(2), us(1) / us(0), us(2) / us(0));
  return buffer;
}

int run_command_line(int argc, char** argv) {
  RingConfig config;
  bool json = false;
  std::vector<int> sweep = {10, 25, 50, 100, 200};
  std::uint64_t seed = 7;
  CLI::App app{"bench_estimator: Tracker::process speed on simulated features, one thread",
               "bench_estimator"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_flag("--json", json, "print one JSON object on the last line");
  app.add_option("--seconds", config.seconds, "simulated seconds timed per case (after the warm-up)")
      ->check(CLI::Range(0.05, 3600.0));
  app.add_option("--warmup", config.warmup_s, "simulated seconds processed before timing (tracks confirm)")
      ->check(CLI::Range(0.1, 60.0));
  app.add_option("--cameras", config.cameras, "cameras on the ring")->check(CLI::Range(2, 1000));
  app.add_option("--rate", config.rate_hz, "frame rate of every camera, Hz")->check(CLI::Range(1.0, 2000.0));
  app.add_option("--markers", config.markers, "markers of the main case")->check(CLI::Range(1, 100000));
  bool no_sweep = false;
  app.add_option("--sweep", sweep, "marker counts of the scaling cases")
      ->delimiter(',')
      ->check(CLI::Range(1, 100000));
  app.add_flag("--no-sweep", no_sweep, "only the main case");
  int bodies = 10;
  app.add_option("--bodies", bodies, "rigid bodies (4 markers each) of the body case; 0: no body case")
      ->check(CLI::Range(0, 1000));
  app.add_option("--seed", seed, "scene seed");
  int chain_frames = 12000;
  app.add_option("--chain-frames", chain_frames, "camera frames of the chain case; 0: no chain case")
      ->check(CLI::Range(0, 10000000));
  double inside_out_seconds = 5.0;
  app.add_option(
         "--inside-out-seconds", inside_out_seconds,
         "simulated seconds of the inside-out case (deploy/scenes/inside_out.yaml); 0: no inside-out case")
      ->check(CLI::Range(0.0, 20.0));
  int calibration_rounds = 3;
  app.add_option(
         "--calibration-rounds", calibration_rounds,
         "rounds of the continuous-calibration case (off, detect, correct, frame by frame in turn); 0: none")
      ->check(CLI::Range(0, 100));
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  if (no_sweep) sweep.clear();

  std::printf(
      "bench_estimator: %d cameras x %.0f Hz on a 3 m ring, Lissajous markers, 0.1 px noise;\n"
      "warm-up %.2f s not timed, then %.2f s simulated, Tracker::process timed per frame, one thread\n",
      config.cameras, config.rate_hz, config.warmup_s, config.seconds);
  std::printf("  %7s %8s %11s %12s %10s %9s %9s %9s %11s %11s %6s\n", "markers", "frames", "observ.",
              "observ./s", "us/observ", "p50 us", "p99 us", "realtime", "tracked@0", "tracked@end", "tracks");
  const Result main_case = run(config, seed);
  print_row(main_case);
  std::fflush(stdout);
  std::vector<Result> scaling;
  if (!sweep.empty()) std::printf("scaling (same rig):\n");
  for (int markers : sweep) {
    RingConfig c = config;
    c.markers = markers;
    scaling.push_back(run(c, seed));
    print_row(scaling.back());
    std::fflush(stdout);
  }
  if (!scaling.empty()) {
    std::printf("  us/observation at %d markers / at %d markers: %.3f\n", scaling.back().markers,
                scaling.front().markers,
                scaling.back().us_per_observation() / scaling.front().us_per_observation());
  }
  // Body update cost: the same scene (loose markers + bodies) run with and without the body
  // definitions, side by side; the difference is what the bodies cost per camera frame.
  std::string bodies_json = "null";
  if (bodies > 0) {
    RingConfig c = config;
    c.bodies = bodies;
    std::size_t tracked = 0;
    const Result without = run(c, seed);
    const Result with = run(c, seed, true, &tracked);
    const double extra_us = (with.process_s - without.process_s) * 1e6 / static_cast<double>(with.frames);
    std::printf(
        "bodies: %d bodies x 4 markers + %d loose markers, %d cameras: per camera frame %.2f us without body "
        "tracking, %.2f us with (p99 %.1f / %.1f us): bodies cost %.2f us per frame (%.3f us per body); "
        "%zu/%d bodies tracked at the end\n",
        bodies, config.markers, config.cameras, without.process_s * 1e6 / static_cast<double>(without.frames),
        with.process_s * 1e6 / static_cast<double>(with.frames), without.p99_us, with.p99_us, extra_us,
        extra_us / bodies, tracked, bodies);
    char buffer[512];
    std::snprintf(buffer, sizeof buffer,
                  "{\"bodies\": %d, \"us_per_frame_without\": %.3f, \"us_per_frame_with\": %.3f, "
                  "\"p99_us_without\": %.2f, \"p99_us_with\": %.2f, \"body_us_per_frame\": %.3f, "
                  "\"body_us_per_frame_per_body\": %.4f, \"bodies_tracked\": %zu}",
                  bodies, without.process_s * 1e6 / static_cast<double>(without.frames),
                  with.process_s * 1e6 / static_cast<double>(with.frames), without.p99_us, with.p99_us,
                  extra_us, extra_us / bodies, tracked);
    bodies_json = buffer;
  }
  std::string chain_json = "null";
  if (chain_frames > 0) {
    const ChainCost cost = run_chain_case(chain_frames, seed);
    std::printf(
        "chain: 4-marker finger chain vs rigid body of 4 markers, %d camera frames (4 cameras, reflections): "
        "%.3f us per frame for the chain, %.3f us for the body (ratio %.2f); marker updates %ld / %ld\n",
        cost.frames, cost.chain_us, cost.body_us, cost.chain_us / cost.body_us, cost.chain_updates,
        cost.body_updates);
    chain_json = chain_case_json(cost);
  }
  const std::string inside_out_json =
      inside_out_seconds > 0 ? print_inside_out_case(inside_out_seconds, seed) : "null";
  const std::string calibration_json =
      calibration_rounds > 0 ? print_calibration_case(config, seed, calibration_rounds) : "null";
  if (json) {
    std::string sweep_json;
    for (const Result& r : scaling) sweep_json += (sweep_json.empty() ? "" : ", ") + to_json(r);
    const double flatness =
        scaling.empty() ? 0 : scaling.back().us_per_observation() / scaling.front().us_per_observation();
    std::printf(
        "{\"cameras\": %d, \"rate_hz\": %.1f, \"warmup_s\": %.3f, \"seconds\": %.3f, \"main\": %s, "
        "\"scaling\": [%s], \"us_per_observation_ratio_last_to_first\": %.4f, \"bodies\": %s, \"chain\": "
        "%s, \"inside_out\": %s, \"calibration\": %s}\n",
        config.cameras, config.rate_hz, config.warmup_s, config.seconds, to_json(main_case).c_str(),
        sweep_json.c_str(), flatness, bodies_json.c_str(), chain_json.c_str(), inside_out_json.c_str(),
        calibration_json.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_estimator", [&] { return run_command_line(argc, argv); });
}
