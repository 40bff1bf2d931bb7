// SPDX-License-Identifier: Apache-2.0
// estimator_node: fuses the asynchronous 2D features of every camera into 3D tracks.
//   live:    subscribes to rt/panoptes/features and camera_info, publishes rt/panoptes/tracks
//   offline: --no-dds --in-features <files...> --out-tracks <file>   (architecture.md, Contracts)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/calibration.h"
#include "panoptes/cli.h"
#include "panoptes/config.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/estimator/inbox.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace {

using panoptes::TimeNs;
namespace est = panoptes::estimator;

struct Options {
  std::string calibration_file;
  std::string bodies_file;
  std::vector<std::string> in_features;
  bool no_dds = false;
  std::string out_tracks;
  std::string out_poses;
  std::string dds_profile;
  double latency_window_ms = 20.0;
  double duration_s = 0.0;
  double status_period_s = 1.0;
  bool quiet = false;
  std::size_t inbox_capacity = 4096;
  est::TrackerOptions tracker;
};

void log(const std::string& message) {
  std::fprintf(stderr, "estimator_node: %s\n", message.c_str());
}

// Warns once per camera about frames the tracker cannot use.
class UnknownCameraWarnings {
 public:
  void note(const std::string& camera_id) {
    if (warned_.insert(camera_id).second) {
      log("camera '" + camera_id + "' has no calibration (T_world_cam): its frames are counted and ignored");
    }
  }

 private:
  std::set<std::string> warned_;
};

int run_offline(const Options& options, est::Tracker& tracker) {
  std::vector<panoptes::FeatureFrame> frames;
  std::size_t bad_lines = 0;
  for (const auto& file : options.in_features) {
    std::vector<std::string> errors;
    std::vector<panoptes::FeatureFrame> part;
    try {
      part = panoptes::read_feature_frames(file, &errors);
    } catch (const std::exception& error) {
      log(error.what());
      return panoptes::kExitBadInput;
    }
    for (std::size_t i = 0; i < errors.size() && i < 5; ++i) log("skipped " + errors[i]);
    if (errors.size() > 5) log("... and " + std::to_string(errors.size() - 5) + " more malformed lines");
    bad_lines += errors.size();
    frames.insert(frames.end(), std::make_move_iterator(part.begin()), std::make_move_iterator(part.end()));
  }
  // Timestamp order; ties broken by camera and frame so the run is deterministic.
  std::stable_sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) {
    return std::tie(a.stamp_ns, a.camera_id, a.frame) < std::tie(b.stamp_ns, b.camera_id, b.frame);
  });

  std::optional<panoptes::JsonlWriter> out;
  if (!options.out_tracks.empty()) out.emplace(options.out_tracks);
  UnknownCameraWarnings warnings;
  std::size_t records = 0;
  const std::size_t progress_every = std::max<std::size_t>(frames.size() / 10, 1);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (tracker.process(frames[i]) == est::FrameOutcome::kUnknownCamera) {
      warnings.note(frames[i].camera_id);
      continue;
    }
    if (out) {
      for (const auto& track : tracker.current_tracks()) {
        out->write(track);
        ++records;
      }
    }
    if (!options.quiet && (i + 1) % progress_every == 0) {
      std::fprintf(stderr, "\restimator_node: %3zu%% (%zu/%zu frames, %zu live tracks)",
                   (i + 1) * 100 / frames.size(), i + 1, frames.size(), tracker.live_track_count());
    }
  }
  if (!options.quiet && !frames.empty()) std::fprintf(stderr, "\n");
  const auto& s = tracker.stats();
  log("processed " + std::to_string(s.frames) + " frames (" + std::to_string(s.frames_unknown_camera) +
      " from uncalibrated cameras, " + std::to_string(s.frames_late) + " late, " + std::to_string(bad_lines) +
      " malformed lines); tracks created " + std::to_string(s.tracks_created) + ", confirmed " +
      std::to_string(s.tracks_confirmed) + "; wrote " + std::to_string(records) + " track records");
  return panoptes::kExitOk;
}

int run_live(const Options& options, est::Tracker& tracker) {
  namespace msg = panoptes::msg;
  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = options.dds_profile;
  bus_options.participant_name = "estimator_node";
  panoptes::dds::Bus bus(bus_options);
  if (!options.quiet) log("DDS profile " + bus.profile_file().string());

  est::FrameInbox inbox(options.inbox_capacity, panoptes::seconds_to_ns(options.latency_window_ms * 1e-3));
  std::mutex info_mutex;
  std::vector<panoptes::CameraCalibration> announced;  // from CameraInfo, applied on the estimator thread
  std::mutex frames_mutex;
  std::map<std::string, std::uint64_t> frames_per_camera;

  auto info_reader = bus.make_reader<msg::CameraInfo>([&](msg::CameraInfo&& info) {
    if (auto calibration = panoptes::dds::calibration_from(info); calibration && calibration->T_world_cam) {
      std::lock_guard<std::mutex> lock(info_mutex);
      announced.push_back(*calibration);
    }
  });
  auto feature_reader = bus.make_reader<msg::FeatureFrame>([&](msg::FeatureFrame&& message) {
    auto frame = panoptes::dds::from_message(message);
    frame.arrival_ns = panoptes::wall_now_ns();
    {
      std::lock_guard<std::mutex> lock(frames_mutex);
      ++frames_per_camera[frame.camera_id];
    }
    inbox.push(std::move(frame));
  });
  auto track_writer = bus.make_writer<msg::TrackFrame>();

  std::optional<panoptes::JsonlWriter> out;
  if (!options.out_tracks.empty()) out.emplace(options.out_tracks);
  UnknownCameraWarnings warnings;
  std::set<std::string> from_file;
  if (!options.calibration_file.empty()) {
    for (const auto& camera : panoptes::load_calibration(options.calibration_file).cameras)
      from_file.insert(camera.id);
  }

  const TimeNs start = panoptes::wall_now_ns();
  TimeNs next_status = start + panoptes::seconds_to_ns(options.status_period_s);
  std::map<std::string, std::uint64_t> last_counts;
  auto handle = [&](const panoptes::FeatureFrame& frame) {
    const auto outcome = tracker.process(frame);
    if (outcome == est::FrameOutcome::kUnknownCamera) {
      warnings.note(frame.camera_id);
      return;
    }
    if (outcome != est::FrameOutcome::kProcessed) return;
    const auto tracks = tracker.current_tracks();
    msg::TrackFrame message;
    message.stamp_ns(frame.stamp_ns);
    message.source_camera(frame.camera_id);
    message.source_frame(frame.frame);
    for (const auto& track : tracks) message.tracks().push_back(panoptes::dds::to_message(track));
    message.publish_ns(panoptes::wall_now_ns());
    track_writer->write(message);
    if (out) {
      for (const auto& track : tracks) out->write(track);
    }
  };

  while (!panoptes::stop_requested()) {
    {
      std::lock_guard<std::mutex> lock(info_mutex);
      for (const auto& camera : announced) {
        // The calibration file wins over what a camera announces about itself.
        if (from_file.count(camera.id) == 0 && !tracker.has_camera(camera.id)) {
          tracker.set_camera(camera);
          log("camera '" + camera.id + "' calibrated from its CameraInfo");
        }
      }
      announced.clear();
    }
    const TimeNs now = panoptes::wall_now_ns();
    for (const auto& frame : inbox.pop_due(now)) handle(frame);
    if (now >= next_status) {
      next_status += panoptes::seconds_to_ns(options.status_period_s);
      if (!options.quiet) {
        std::string line =
            "t=" + std::to_string(static_cast<int>(panoptes::ns_to_seconds(now - start))) + "s fps:";
        std::lock_guard<std::mutex> lock(frames_mutex);
        for (const auto& [camera, count] : frames_per_camera) {
          char buffer[64];
          std::snprintf(buffer, sizeof buffer, " %s %.0f", camera.c_str(),
                        static_cast<double>(count - last_counts[camera]) / options.status_period_s);
          line += buffer;
          last_counts[camera] = count;
        }
        const auto& s = tracker.stats();
        line += " | tracks " + std::to_string(tracker.current_tracks().size()) + " | late " +
                std::to_string(s.frames_late) + " | inbox drops " + std::to_string(inbox.drops());
        log(line);
      }
    }
    if (options.duration_s > 0 && now - start >= panoptes::seconds_to_ns(options.duration_s)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (const auto& frame : inbox.drain()) handle(frame);
  const auto& s = tracker.stats();
  log("stopped: " + std::to_string(s.frames) + " frames, " + std::to_string(s.frames_late) + " late, " +
      std::to_string(s.frames_unknown_camera) + " from uncalibrated cameras, inbox drops " +
      std::to_string(inbox.drops()) + ", tracks created " + std::to_string(s.tracks_created) +
      ", confirmed " + std::to_string(s.tracks_confirmed));
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"estimator_node: fuses asynchronous camera features into 3D tracks (Panoptes)",
               "estimator_node"};
  app.add_option("--calibration", options.calibration_file, "calibration YAML (cameras with T_world_cam)");
  app.add_option("--bodies", options.bodies_file,
                 "rigid-body definitions YAML (validated; body tracking is not built yet)");
  app.add_option("--in-features", options.in_features, "offline: FeatureFrame JSONL files (one per camera)")
      ->expected(1, -1);
  app.add_flag("--no-dds", options.no_dds, "offline: do not use DDS; requires --in-features");
  app.add_option("--out-tracks", options.out_tracks, "write every published TrackFrame as Track JSONL");
  app.add_option("--out-poses", options.out_poses, "write body poses as Pose JSONL (needs --bodies)");
  app.add_option("--dds-profile", options.dds_profile,
                 "Fast DDS XML profile (default: deploy/dds/loopback.xml)");
  app.add_option("--latency-window-ms", options.latency_window_ms,
                 "live: how long frames wait to be ordered by stamp")
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--duration", options.duration_s, "live: stop after this many seconds (0 = until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--status-period", options.status_period_s, "live: seconds between progress lines")
      ->check(CLI::PositiveNumber);
  app.add_flag("--quiet", options.quiet, "no progress output");
  app.add_option("--process-noise", options.tracker.process_noise,
                 "σ² of white acceleration, m²/s³ (seed 003 A.48)")
      ->check(CLI::PositiveNumber);
  app.add_option("--measurement-noise-px", options.tracker.measurement_noise_px, "σ of a centroid, px")
      ->check(CLI::PositiveNumber);
  app.add_option("--confirm-cameras", options.tracker.confirm_cameras,
                 "distinct cameras that must see a new track before it is published")
      ->check(CLI::Range(2, 64));
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv, [&] {
        if (options.no_dds && options.in_features.empty())
          throw CLI::ValidationError("--no-dds needs --in-features");
        if (!options.in_features.empty() && !options.no_dds) {
          throw CLI::ValidationError(
              "--in-features runs offline: add --no-dds (replaying onto DDS is camera_node's job)");
        }
        if (options.no_dds && options.calibration_file.empty()) {
          throw CLI::ValidationError("offline mode needs --calibration");
        }
        if (!options.out_poses.empty() && options.bodies_file.empty())
          throw CLI::ValidationError("--out-poses needs --bodies");
      })) {
    return *exit_code;
  }

  panoptes::install_stop_handlers();
  est::Tracker tracker(options.tracker);
  try {
    if (!options.calibration_file.empty()) {
      const auto calibration = panoptes::load_calibration(options.calibration_file);
      tracker.set_calibration(calibration);
      for (const auto& camera : calibration.cameras) {
        if (!camera.T_world_cam)
          log("camera '" + camera.id + "' in " + options.calibration_file + " has no T_world_cam: ignored");
      }
    }
    if (!options.bodies_file.empty()) {
      const auto bodies = panoptes::load_bodies(options.bodies_file);
      log("loaded " + std::to_string(bodies.size()) +
          " body definition(s); rigid-body tracking is not built yet, so no poses are produced");
      if (!options.out_poses.empty()) panoptes::JsonlWriter poses(options.out_poses);  // empty but present
    }
    if (!options.quiet) {
      std::ostringstream printed;
      options.tracker.print(printed);
      std::fprintf(stderr, "%s", printed.str().c_str());
    }
  } catch (const panoptes::ConfigError& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  }

  try {
    return options.no_dds ? run_offline(options, tracker) : run_live(options, tracker);
  } catch (const panoptes::ConfigError& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "estimator_node: %s\n", error.what());
    return panoptes::kExitFailure;
  }
}
