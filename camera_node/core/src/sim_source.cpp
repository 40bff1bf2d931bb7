// SPDX-License-Identifier: Apache-2.0
#include "sim_source.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "panoptes/simulator.h"
#include "stop_signal.h"

namespace panoptes::camera {
namespace {

TimeNs next_whole_second(TimeNs wall_ns) {
  return (wall_ns + kNsPerSecond - 1) / kNsPerSecond * kNsPerSecond;
}

class SimSource final : public FrameSource {
 public:
  // simulator_ points into scene_: the object must stay where it was built.
  SimSource(const SimSource&) = delete;
  SimSource& operator=(const SimSource&) = delete;
  SimSource(Scene scene, const std::string& camera_id, const SourceOptions& options)
      : scene_(std::move(scene)),
        simulator_(scene_, camera_id),
        epoch_ns_(options.sim_epoch_ns != 0 ? options.sim_epoch_ns : next_whole_second(wall_now_ns())),
        paced_(options.paced),
        max_frames_(options.max_frames),
        frames_(simulator_.frames_in(0, scene_.duration_ns())),
        next_k_(frames_.first) {
    static_assert(!std::is_copy_constructible_v<SimSource> && !std::is_move_constructible_v<SimSource>);
    const SimCameraConfig& config = simulator_.config();
    info_.camera_id = options.camera_id.empty() ? camera_id : options.camera_id;
    info_.backend = "sim";
    info_.model = "panoptes-sim";
    info_.serial = camera_id;
    info_.width = config.calibration.intrinsics.width;
    info_.height = config.calibration.intrinsics.height;
    info_.nominal_rate_hz = config.rate_hz;
    info_.calibration = config.calibration;
    info_.calibration->id = info_.camera_id;
  }

  const SourceInfo& info() const override { return info_; }

  std::optional<CapturedFrame> next() override {
    if (stop_.stopped()) return std::nullopt;
    if (max_frames_ >= 0 && delivered_ >= max_frames_) return std::nullopt;
    if (paced_) skip_frames_already_read_out();
    if (next_k_ >= frames_.end) return std::nullopt;
    if (paced_ && !stop_.sleep_until_wall(readout_wall_ns(next_k_))) return std::nullopt;

    CapturedFrame frame;
    frame.image = simulator_.render(next_k_);
    frame.sequence = next_k_;
    frame.stamp_ns = epoch_ns_ + simulator_.frame_stamp_ns(next_k_);
    frame.arrival_ns = wall_now_ns();
    ++next_k_;
    ++delivered_;
    return frame;
  }

  SourceCounters counters() const override {
    const std::uint64_t overwritten = overwritten_.load(std::memory_order_relaxed);
    if (overwritten == 0) return {};
    return {{"overwritten", overwritten}};  // frames not collected before the next readout
  }

  void stop() override { stop_.stop(); }

 private:
  // A frame exists once its exposure has ended: the sensor reads it out then.
  TimeNs readout_wall_ns(std::int64_t k) const {
    return epoch_ns_ + simulator_.frame_time_ns(k) + simulator_.config().exposure_ns / 2;
  }

  // A real camera whose frames are not collected in time overwrites them; doing the same keeps
  // latency bounded when rendering or the consumer falls behind, and a node started after the
  // epoch begins with the next frame instead of a burst of old ones.
  void skip_frames_already_read_out() {
    const TimeNs now = wall_now_ns();
    if (readout_wall_ns(next_k_) > now) return;
    if (delivered_ == 0) {
      const double period_ns = 1e9 / simulator_.config().rate_hz;
      const double behind_ns = static_cast<double>(now - readout_wall_ns(next_k_));
      next_k_ += std::max<std::int64_t>(0, static_cast<std::int64_t>(behind_ns / period_ns) - 1);
      while (readout_wall_ns(next_k_) <= now) ++next_k_;
      return;
    }
    // Mid-stream: deliver the newest frame already read out, dropping older ones.
    while (readout_wall_ns(next_k_ + 1) <= now) {
      ++next_k_;
      overwritten_.fetch_add(1, std::memory_order_relaxed);
    }
  }

  Scene scene_;  // declared before simulator_, which points into it
  CameraSimulator simulator_;
  TimeNs epoch_ns_;
  bool paced_;
  std::int64_t max_frames_;
  // Mid-exposure in [0, duration), like panoptes_sim features (docs/simulator.md).
  CameraSimulator::FrameRange frames_;
  std::int64_t next_k_;
  std::int64_t delivered_ = 0;
  SourceInfo info_;
  StopSignal stop_;
  std::atomic<std::uint64_t> overwritten_{0};
};

}  // namespace

std::unique_ptr<FrameSource> open_sim_source(const std::string& target, const SourceOptions& options) {
  const std::string spec = "sim:" + target;
  const auto hash = target.rfind('#');
  if (hash == std::string::npos || hash + 1 == target.size() || hash == 0) {
    throw std::runtime_error(spec + ": expected sim:<scene.yaml>#<camera id>");
  }
  const std::string scene_path = target.substr(0, hash);
  const std::string camera_id = target.substr(hash + 1);
  Scene scene = Scene::load(scene_path);
  if (scene.find_camera(camera_id) == nullptr) {
    std::string known;
    for (const SimCameraConfig& camera : scene.cameras()) {
      known += (known.empty() ? "" : ", ") + camera.calibration.id;
    }
    throw std::runtime_error(spec + ": scene " + scene_path + " has no camera '" + camera_id +
                             "' (it has: " + known + ")");
  }
  return std::make_unique<SimSource>(std::move(scene), camera_id, options);
}

}  // namespace panoptes::camera
