// SPDX-License-Identifier: Apache-2.0
// panoptes_feature_flood: one process that publishes, for N cameras at R Hz each, FeatureFrames with
// B blobs moving on circles, plus each camera's CameraInfo and a CameraStatus once a second; and a
// TrackFrame with T tracks at R Hz; with --chains C, a ChainFrame of C 4-marker finger chains after
// every camera frame (as estimator_node publishes them). A controlled bus load for the console benchmark
// (tests/bench/bench_console.sh) that does not need N camera processes. With --partition and
// --camera-ids it is also a camera that writes as others (tests/integration/test_security.sh).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/process.h"
#include "panoptes/time.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"

namespace {

namespace msg = panoptes::msg;

msg::CameraInfo info_of(const std::string& id, double rate_hz) {
  msg::CameraInfo info;
  info.camera_id(id);
  info.model("flood");
  info.backend("features");
  info.width(640);
  info.height(480);
  info.nominal_rate_hz(rate_hz);
  info.K({600, 600, 319.5, 239.5});
  return info;
}

// `chains` fingers curling and opening at t s, one frame's sample; every 10th grabs.
msg::ChainFrame chain_frame(int chains, const std::string& camera, long long frame, double t,
                            panoptes::TimeNs now) {
  msg::ChainFrame message;
  message.source_camera(camera);
  message.source_frame(frame);
  message.stamp_ns(now);
  message.publish_ns(now);
  for (int c = 0; c < chains; ++c) {
    msg::ChainState state;
    state.name("finger" + std::to_string(c));
    state.chain_id(static_cast<std::uint32_t>(c + 1));
    state.stamp_ns(now);
    const double bend = 0.7 + 0.6 * std::sin(t + c);
    state.angles({bend, bend});
    double x = 0.1 * c;
    double z = 1.0;
    double heading = 0;
    for (const double link : {0.0, 0.045, 0.03, 0.025}) {
      x += link * std::cos(heading);
      z -= link * std::sin(heading);
      if (link > 0) heading += bend;
      msg::ChainMarker marker;
      marker.position({x, 0.0, z});
      state.markers().push_back(marker);
      state.marker_valid().push_back(true);
    }
    state.tip({x + 0.012, 0.0, z});
    state.predicted_tip({x + 0.013, 0.0, z});
    state.prediction_horizon_ns(80'000'000);
    state.grabbing(bend > 1.2);
    message.chains().push_back(state);
  }
  return message;
}

int run(int argc, char** argv) {
  int cameras = 32;
  double rate_hz = 120;
  int blobs = 3;
  int tracks = 3;
  int chains = 0;
  double duration_s = 20;
  std::string dds_profile;
  std::string partition;
  std::vector<std::string> camera_ids;
  CLI::App app{"panoptes_feature_flood: publishes N cameras' features at R Hz (console benchmark)",
               "panoptes_feature_flood"};
  app.option_defaults()->always_capture_default();
  app.add_option("--cameras", cameras, "cameras")->check(CLI::Range(1, 256));
  app.add_option("--rate", rate_hz, "frames per second per camera")->check(CLI::Range(1.0, 1000.0));
  app.add_option("--blobs", blobs, "blobs per frame")->check(CLI::Range(0, 1000));
  app.add_option("--tracks", tracks, "tracks per TrackFrame")->check(CLI::Range(0, 1000));
  app.add_option("--chains", chains, "chains per ChainFrame, one ChainFrame per camera frame")
      ->check(CLI::Range(0, 64));
  app.add_option("--duration", duration_s, "seconds")->check(CLI::PositiveNumber);
  app.add_option("--dds-profile", dds_profile, "Fast DDS XML profile");
  app.add_option("--partition", partition,
                 "camera id whose DDS partition the camera topics are written in (default: every camera's)");
  app.add_option("--camera-ids", camera_ids, "camera ids to write as (default: cam0, cam1, ...)")
      ->delimiter(',');
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();

  panoptes::dds::BusOptions bus_options;
  bus_options.profile_file = dds_profile;
  bus_options.participant_name = "panoptes_feature_flood";
  panoptes::dds::Bus bus(bus_options);
  const auto scoped = panoptes::dds::Qos::kDefault;
  auto info_writer = bus.make_writer<msg::CameraInfo>(scoped, {}, partition);
  auto feature_writer = bus.make_writer<msg::FeatureFrame>(scoped, {}, partition);
  auto status_writer = bus.make_writer<msg::CameraStatus>(scoped, {}, partition);
  auto track_writer = tracks > 0 ? bus.make_writer<msg::TrackFrame>() : nullptr;
  auto chain_writer = chains > 0 ? bus.make_writer<msg::ChainFrame>() : nullptr;
  if (camera_ids.empty()) {
    for (int c = 0; c < cameras; ++c) camera_ids.push_back("cam" + std::to_string(c));
  }
  cameras = static_cast<int>(camera_ids.size());
  for (const std::string& id : camera_ids) info_writer->write(info_of(id, rate_hz));

  // Cameras take turns: one tick per camera frame, spread evenly over the period.
  const auto tick = std::chrono::nanoseconds(static_cast<long long>(1e9 / (rate_hz * cameras)));
  const auto start = std::chrono::steady_clock::now();
  const auto end =
      start + std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(duration_s));
  long long frame = 0;
  std::uint64_t written = 0;
  auto next = start;
  for (long long step = 0; next < end && !panoptes::stop_requested(); ++step, next += tick) {
    std::this_thread::sleep_until(next);
    const int camera = static_cast<int>(step % cameras);
    if (camera == 0) ++frame;
    const double t = static_cast<double>(frame) / rate_hz;
    const panoptes::TimeNs now = panoptes::wall_now_ns();
    msg::FeatureFrame features;
    features.camera_id(camera_ids[static_cast<std::size_t>(camera)]);
    features.frame(frame);
    features.stamp_ns(now);
    features.publish_ns(now);
    std::vector<msg::Blob> list(static_cast<std::size_t>(blobs));
    for (int b = 0; b < blobs; ++b) {
      const double angle = t + 2.0 * M_PI * b / std::max(1, blobs) + camera;
      list[b].x(static_cast<float>(320 + 150 * std::cos(angle)));
      list[b].y(static_cast<float>(240 + 150 * std::sin(angle)));
      list[b].area(12.5F);
    }
    features.blobs(std::move(list));
    feature_writer->write(features);
    ++written;
    if (chain_writer) chain_writer->write(chain_frame(chains, features.camera_id(), frame, t, now));
    if (camera == 0 && tracks > 0) {
      msg::TrackFrame frame_message;
      frame_message.stamp_ns(now);
      std::vector<msg::Track> list_tracks(static_cast<std::size_t>(tracks));
      for (int k = 0; k < tracks; ++k) {
        list_tracks[k].id(k + 1);
        list_tracks[k].position({std::cos(t + k), std::sin(t + k), 1.0});
        list_tracks[k].status(1);
      }
      frame_message.tracks(std::move(list_tracks));
      track_writer->write(frame_message);
    }
    if (camera == 0 && frame % static_cast<long long>(rate_hz) == 0) {
      for (int c = 0; c < cameras; ++c) {
        msg::CameraStatus status;
        status.camera_id(camera_ids[static_cast<std::size_t>(c)]);
        status.stamp_ns(now);
        status.fps(rate_hz);
        status.frames(static_cast<unsigned long long>(frame));
        status_writer->write(status);
      }
    }
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("panoptes_feature_flood: %llu FeatureFrames in %.1f s (%.0f/s, target %.0f/s)\n",
              static_cast<unsigned long long>(written), elapsed, static_cast<double>(written) / elapsed,
              cameras * rate_hz);
  return panoptes::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_feature_flood", [&] { return run(argc, argv); });
}
