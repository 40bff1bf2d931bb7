// SPDX-License-Identifier: Apache-2.0
// ptz_guide: steers a pan/tilt/zoom camera at a tracked body or marker (seed 003 §2.3.3), aiming
// where the target will be when the command takes effect (docs/ptz.md). It reads Panoptes through
// the client library (live) or the estimator's track records (offline, --in-tracks), and writes
// one JSON line per command for a PTZ driver, or for `panoptes_sim ptz` to measure the framing.
//   ptz_guide --ptz ptz.yaml --body head [--out commands.jsonl]                  live, a body
//   ptz_guide --ptz ptz.yaml --track-near 0,0,1.6 --in-tracks tracks.jsonl ...   offline, a marker
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/client/client.h"
#include "panoptes/errors.h"
#include "panoptes/ptz/ptz_file.h"

namespace {

using panoptes::TimeNs;
namespace ptz = panoptes::ptz;

std::atomic<bool> g_stop{false};

struct Options {
  std::string ptz_file;
  std::string body;
  std::string track_near;
  std::string offset = "0,0,0";
  bool no_prediction = false;
  double lookahead_ms = -1.0;
  double framing_m = 0.5;
  double rate_hz = 30.0;
  std::string in_tracks;
  double delay_ms = 2.0;
  double duration_s = 0.0;
  std::string out;
};

// The followed target's latest measurement.
struct Target {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
};

Eigen::Vector3d parse_xyz(const std::string& text, const std::string& option) {
  std::stringstream stream(text);
  std::vector<double> values;
  for (std::string item; std::getline(stream, item, ',');) values.push_back(std::stod(item));
  if (values.size() != 3)
    throw panoptes::ConfigError(option, "", "expected x,y,z in metres, got '" + text + "'");
  return {values[0], values[1], values[2]};
}

// Follows one track id: the track nearest `near` at the start, and, when the followed one has been
// missing from the records for kLostAfterNs (ids change when a track is lost or merged), the track
// nearest to where it would be now.
class TrackFollower {
 public:
  explicit TrackFollower(const Eigen::Vector3d& near) : near_(near) {}

  void add(TimeNs stamp_ns, std::int64_t id, const Eigen::Vector3d& p, const Eigen::Vector3d& v) {
    latest_[id] = {stamp_ns, p, v};
    if (followed_ && id == *followed_) return;
    // The first pick waits a moment: new tracks include short-lived duplicates and ghosts.
    if (!first_stamp_) first_stamp_ = stamp_ns;
    if (!followed_ && stamp_ns - *first_stamp_ < kLostAfterNs) return;
    const bool pick = !followed_ || stamp_ns - latest_[*followed_].stamp_ns > kLostAfterNs;
    if (!pick) return;
    // Where the lost track would be now (its last position moved on at its last velocity).
    const Target* lost = followed_ ? &latest_[*followed_] : nullptr;
    const Eigen::Vector3d from =
        lost ? Eigen::Vector3d(lost->p + panoptes::ns_to_seconds(stamp_ns - lost->stamp_ns) * lost->v)
             : near_;
    if ((p - from).norm() < kPickRadiusM && (!candidate_ || (p - from).norm() < candidate_distance_)) {
      candidate_ = id;
      candidate_distance_ = (p - from).norm();
    }
  }
  // Ends a batch of records (one stamp): takes the nearest candidate if the target was lost.
  void end_batch() {
    if (candidate_) {
      if (followed_ != candidate_) {
        ++switches_;
        const Eigen::Vector3d& p = latest_[*candidate_].p;
        std::fprintf(stderr, "ptz_guide: following track %lld at (%.3f, %.3f, %.3f) m\n",
                     static_cast<long long>(*candidate_), p.x(), p.y(), p.z());
      }
      followed_ = candidate_;
    }
    candidate_.reset();
  }
  std::optional<Target> target() const {
    if (!followed_) return std::nullopt;
    return latest_.at(*followed_);
  }
  int switches() const { return switches_; }

 private:
  static constexpr TimeNs kLostAfterNs = 50'000'000;
  static constexpr double kPickRadiusM = 0.3;
  Eigen::Vector3d near_;
  std::map<std::int64_t, Target> latest_;
  std::optional<std::int64_t> followed_;
  std::optional<TimeNs> first_stamp_;
  std::optional<std::int64_t> candidate_;
  double candidate_distance_ = 0.0;
  int switches_ = 0;
};

// Offline: the estimator's records arrive `delay_ms` after their stamp; a command every 1/rate s.
int run_offline(const Options& options, const ptz::PtzModel& model, const ptz::GuideOptions& guide,
                std::ostream& out) {
  std::ifstream in(options.in_tracks);
  if (!in) throw panoptes::ConfigError(options.in_tracks, "", "cannot read");
  TrackFollower follower(parse_xyz(options.track_near, "--track-near"));
  const TimeNs delay = panoptes::seconds_to_ns(options.delay_ms * 1e-3);
  const TimeNs period = panoptes::seconds_to_ns(1.0 / options.rate_hz);
  std::optional<TimeNs> next_command, batch_stamp;
  long long commands = 0, bad = 0;
  for (std::string line; std::getline(in, line);) {
    const nlohmann::json record = nlohmann::json::parse(line, nullptr, false);
    if (!record.is_object() || !record.contains("stamp_ns") || !record.contains("id") ||
        !record.contains("p") || !record.contains("v")) {
      ++bad;
      continue;
    }
    // Tentative tracks (status other than confirmed) are not followed: most are ghosts.
    if (record.contains("status") && record["status"] != "confirmed") continue;
    const TimeNs stamp = record["stamp_ns"].get<TimeNs>();
    if (batch_stamp && stamp != *batch_stamp) follower.end_batch();
    batch_stamp = stamp;
    if (!next_command) next_command = stamp + delay;
    // Commands due before this record arrives use what had arrived until then.
    while (*next_command < stamp + delay) {
      if (const auto target = follower.target()) {
        out << ptz::command_to_json(
                   ptz::guide_command(model, guide, *next_command, target->stamp_ns, target->p, target->v))
            << "\n";
        ++commands;
      }
      *next_command += period;
    }
    const auto p = record["p"].get<std::vector<double>>(), v = record["v"].get<std::vector<double>>();
    follower.add(stamp, record["id"].get<std::int64_t>(), {p[0], p[1], p[2]}, {v[0], v[1], v[2]});
  }
  std::cerr << "ptz_guide: " << commands << " commands from " << options.in_tracks << " (" << bad
            << " bad lines, " << follower.switches() << " track picks)\n";
  return commands > 0 ? 0 : 1;
}

// Live: the client's callback keeps the newest measurement; the loop issues commands at the rate.
int run_live(const Options& options, const ptz::PtzModel& model, const ptz::GuideOptions& guide,
             std::ostream& out) {
  panoptes::client::Client client;
  std::mutex mutex;
  std::optional<Target> latest;
  TrackFollower follower(options.track_near.empty() ? Eigen::Vector3d::Zero()
                                                    : parse_xyz(options.track_near, "--track-near"));
  client.add_callback([&](const panoptes::client::Frame& frame) {
    std::lock_guard lock(mutex);
    if (!options.body.empty()) {
      const auto* body = frame.body(options.body);
      if (body == nullptr || !body->tracking_valid) return;
      latest = Target{frame.stamp_ns + body->prediction_horizon_ns,
                      {body->position[0], body->position[1], body->position[2]},
                      {body->linear_velocity[0], body->linear_velocity[1], body->linear_velocity[2]}};
      return;
    }
    for (const auto& marker : frame.markers)
      follower.add(frame.stamp_ns, marker.id, {marker.position[0], marker.position[1], marker.position[2]},
                   {marker.velocity[0], marker.velocity[1], marker.velocity[2]});
    follower.end_batch();
    latest = follower.target();
  });
  const auto period = std::chrono::duration<double>(1.0 / options.rate_hz);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.duration_s);
  while (!g_stop && (options.duration_s <= 0 || std::chrono::steady_clock::now() < until)) {
    std::this_thread::sleep_for(period);
    std::optional<Target> target;
    {
      std::lock_guard lock(mutex);
      target = latest;
    }
    if (!target) continue;
    const TimeNs now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                           std::chrono::system_clock::now().time_since_epoch())
                           .count();
    out << ptz::command_to_json(ptz::guide_command(model, guide, now, target->stamp_ns, target->p, target->v))
        << "\n";
    out.flush();
  }
  std::cerr << "ptz_guide: " << client.status_text() << "\n";
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"ptz_guide: steer a pan/tilt/zoom camera at a tracked body or marker (docs/ptz.md)"};
  app.option_defaults()->always_capture_default();
  Options options;
  app.add_option("--ptz", options.ptz_file, "PTZ camera file (YAML)")->required();
  auto* body = app.add_option("--body", options.body, "Follow this rigid body (live only)");
  auto* near = app.add_option("--track-near", options.track_near, "Follow the marker track nearest x,y,z m");
  body->excludes(near);
  app.add_option("--offset", options.offset, "Aim this far from the target, x,y,z m (e.g. marker -> head)");
  app.add_flag("--no-prediction", options.no_prediction,
               "Aim at the last measured position (for comparison)");
  app.add_option("--lookahead-ms", options.lookahead_ms,
                 "Predict this far past now (< 0: the command latency)");
  app.add_option("--framing", options.framing_m, "Width of scene the image spans at the target, m")
      ->check(CLI::Range(0.01, 100.0));
  app.add_option("--rate", options.rate_hz, "Commands per second")->check(CLI::Range(1.0, 1000.0));
  app.add_option("--in-tracks", options.in_tracks, "Offline: the estimator's track records (JSON Lines)");
  app.add_option("--delay-ms", options.delay_ms, "Offline: a record arrives this long after its stamp")
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--duration", options.duration_s, "Live: seconds to run (0: until interrupted)");
  app.add_option("--out", options.out, "Commands file (JSON Lines; stdout if empty)");
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, [](int) { g_stop = true; });
  std::signal(SIGTERM, [](int) { g_stop = true; });
  try {
    if (options.body.empty() && options.track_near.empty())
      throw panoptes::ConfigError("ptz_guide", "", "choose a target: --body NAME or --track-near x,y,z");
    if (!options.in_tracks.empty() && !options.body.empty())
      throw panoptes::ConfigError("ptz_guide", "", "--in-tracks follows a marker track: use --track-near");
    const ptz::PtzModel model = ptz::load_ptz_model(options.ptz_file);
    ptz::GuideOptions guide;
    guide.predict = !options.no_prediction;
    guide.lookahead_s = options.lookahead_ms < 0 ? -1.0 : options.lookahead_ms * 1e-3;
    guide.framing_m = options.framing_m;
    guide.aim_offset = parse_xyz(options.offset, "--offset");
    std::ofstream file;
    if (!options.out.empty()) {
      file.open(options.out, std::ios::trunc);
      if (!file) throw panoptes::ConfigError(options.out, "", "cannot write");
    }
    std::ostream& out = options.out.empty() ? std::cout : file;
    return options.in_tracks.empty() ? run_live(options, model, guide, out)
                                     : run_offline(options, model, guide, out);
  } catch (const panoptes::ConfigError& error) {
    std::cerr << "ptz_guide: " << error.what() << "\n";
    return 2;
  } catch (const panoptes::client::OptionError& error) {  // e.g. $PANOPTES_DOMAIN=abc: a usage error
    std::cerr << "ptz_guide: " << error.what() << "\n";
    return 2;
  } catch (const std::exception& error) {
    std::cerr << "ptz_guide: " << error.what() << "\n";
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {  // e.g. out of memory while setting up the parser
    std::cerr << "ptz_guide: " << error.what() << "\n";
    return 1;
  }
}
