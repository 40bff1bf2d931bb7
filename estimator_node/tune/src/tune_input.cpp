// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/tune_input.h"

#include <set>

#include "panoptes/calibration_file.h"
#include "panoptes/session/offline_replay.h"
#include "panoptes/simulator.h"

namespace panoptes::tune {

TuneInput load_feature_input(const std::string& calibration_file,
                             const std::vector<std::string>& feature_files) {
  TuneInput input;
  input.calibration = load_calibration(calibration_file);
  session::FeatureFiles files = session::read_feature_files(feature_files);
  input.frames = std::move(files.frames);
  input.bad_lines = files.bad_lines;
  session::sort_by_stamp(input.frames);
  return input;
}

TuneInput simulated_input(const Scene& scene, TimeNs epoch_ns) {
  TuneInput input;
  input.calibration = scene.calibration();
  for (const SimCameraConfig& config : scene.cameras()) {
    const CameraSimulator camera(scene, config.calibration.id);
    const CameraSimulator::FrameRange range = camera.frames_in(0, scene.duration_ns());
    for (std::int64_t k = range.first; k < range.end; ++k) {
      FeatureFrame frame = camera.features(k);
      frame.stamp_ns += epoch_ns;
      frame.received_ns += epoch_ns;
      input.frames.push_back(std::move(frame));
    }
  }
  session::sort_by_stamp(input.frames);
  return input;
}

std::vector<std::string> cameras_with_frames(const TuneInput& input) {
  std::set<std::string> posed;
  for (const auto& camera : input.calibration.cameras)
    if (camera.T_world_cam) posed.insert(camera.id);
  std::set<std::string> seen;
  for (const auto& frame : input.frames)
    if (posed.count(frame.camera_id) > 0) seen.insert(frame.camera_id);
  return {seen.begin(), seen.end()};
}

}  // namespace panoptes::tune
