// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate capture`: records every camera's FeatureFrames over DDS
// while the wand is waved, showing per-camera progress and image coverage. The only calibration
// code that knows DDS; linked into estimator_node, not into panoptes_calib.
#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "panoptes/calib/calibrate_cli.h"
#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/convert.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/image_coverage.h"
#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::calib {

namespace {

struct CameraProgress {
  std::int64_t frames = 0;
  std::int64_t frames_with_blobs = 0;
  std::int64_t missing = 0;      // frame numbers skipped between received frames (lost or not sent)
  std::int64_t last_frame = -1;  // frame number of the newest frame received
  ImageCoverage coverage;        // sized from CameraInfo; else spans the blobs seen
};

}  // namespace

int run_calibrate_capture(int argc, char** argv) {
  std::string out, profile;
  double duration_s = 0;
  bool time_service = false;
  CLI::App app{"calibrate capture: record FeatureFrames of all cameras over DDS while the wand is waved",
               "estimator_node calibrate capture"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  panoptes::dds::add_domain_option(app);
  app.add_option("--out", out, "FeatureFrame JSONL file to write (all cameras)")->required();
  app.add_option("--duration", duration_s, "seconds to record")->default_str("until Ctrl-C");
  app.add_option("--dds-profile", profile, "Fast DDS XML profile")
      ->default_str("$PANOPTES_DDS_PROFILE or deploy/dds/loopback.xml");
  app.add_flag("--time-service", time_service,
               "serve the common time base (when no estimator_node is running during the capture)");
  if (auto exit = parse_command_line(app, argc, argv)) return *exit;
  namespace msg = panoptes::msg;
  install_stop_handlers();
  JsonlWriter writer(out);
  dds::BusOptions bus_options;
  bus_options.profile_file = profile;
  bus_options.participant_name = "calibrate_capture";
  dds::Bus bus(bus_options);
  std::unique_ptr<dds::TimeSyncServer> server;
  if (time_service) server = std::make_unique<dds::TimeSyncServer>(bus);
  std::mutex mutex;
  std::map<std::string, CameraProgress> progress;
  std::vector<FeatureFrame> queue;
  auto info_reader = bus.make_reader<msg::CameraInfo>([&](msg::CameraInfo&& info) {
    if (auto calibration = dds::calibration_from(info)) {
      std::lock_guard<std::mutex> lock(mutex);
      progress[calibration->id].coverage.set_size(calibration->intrinsics.width,
                                                  calibration->intrinsics.height);
    }
  });
  // Reliable: camera_node's feature writers offer reliability (the estimator asks for best effort
  // and gets it), so frames lost on a busy network are repaired from the writer's history. The
  // listener moves every sample out at once, so the reader's history never overflows. Gaps in the
  // frame numbers that remain are counted and shown
  // (tests/integration/test_calibration_capture.sh checks that none are missing).
  auto reader = bus.make_reader<msg::FeatureFrame>(
      [&](msg::FeatureFrame&& message) {
        auto frame = dds::from_message(message);
        frame.received_ns = wall_now_ns();
        std::lock_guard<std::mutex> lock(mutex);
        queue.push_back(std::move(frame));
      },
      dds::Qos::kReliable);
  std::fprintf(stderr, "recording to %s%s; wave the wand through the whole volume, Ctrl-C to stop\n",
               out.c_str(), duration_s > 0 ? (" for " + std::to_string(duration_s) + " s").c_str() : "");
  const auto start = std::chrono::steady_clock::now();
  auto last_print = start;
  std::int64_t written = 0;
  const auto drain = [&] {
    std::vector<FeatureFrame> batch;
    {
      std::lock_guard<std::mutex> lock(mutex);
      batch.swap(queue);
      for (const auto& frame : batch) {
        auto& p = progress[frame.camera_id];
        ++p.frames;
        if (p.last_frame >= 0 && frame.frame > p.last_frame + 1) p.missing += frame.frame - p.last_frame - 1;
        p.last_frame = std::max(p.last_frame, frame.frame);
        if (!frame.blobs.empty()) ++p.frames_with_blobs;
        for (const auto& blob : frame.blobs) p.coverage.add(blob.x, blob.y);
      }
    }
    for (const auto& frame : batch) writer.write(frame);
    written += static_cast<std::int64_t>(batch.size());
  };
  while (!stop_requested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    drain();
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (now - last_print > std::chrono::seconds(1)) {
      last_print = now;
      std::lock_guard<std::mutex> lock(mutex);
      std::string line = "[" + std::to_string(static_cast<int>(elapsed)) + " s]";
      for (const auto& [id, p] : progress)
        line += "  " + id + ": " + std::to_string(p.frames_with_blobs) + "/" + std::to_string(p.frames) +
                " frames with blobs, coverage " + std::to_string(p.coverage.percent()) + "%" +
                (p.missing > 0 ? ", " + std::to_string(p.missing) + " missing" : "");
      if (progress.empty()) line += "  waiting for cameras...";
      std::fprintf(stderr, "%s\n", line.c_str());
    }
    if (duration_s > 0 && elapsed >= duration_s) break;
  }
  reader.reset();
  drain();  // frames that arrived after the last pass would otherwise be lost
  writer.flush();
  std::printf("wrote %lld frames from %zu cameras to %s\n", static_cast<long long>(written), progress.size(),
              out.c_str());
  for (const auto& [id, p] : progress)
    std::printf("  %s: %lld frames, %lld with blobs, %lld missing, image coverage %d%%\n", id.c_str(),
                static_cast<long long>(p.frames), static_cast<long long>(p.frames_with_blobs),
                static_cast<long long>(p.missing), p.coverage.percent());
  return written > 0 ? kExitOk : kExitFailure;
}

}  // namespace panoptes::calib
