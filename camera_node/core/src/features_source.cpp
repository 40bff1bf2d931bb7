// SPDX-License-Identifier: Apache-2.0
// Replay of recorded FeatureFrames (architecture.md, "Offline modes"): frames come out with their
// recorded spacing (divided by the rate scale), re-stamped so the replay happens now.
#include "features_source.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "panoptes/jsonl.h"
#include "stop_signal.h"

namespace panoptes::camera {
namespace {

namespace fs = std::filesystem;

struct FrameSize {
  int width = 0;
  int height = 0;
};

// The contract's FeatureFrame has no image size, but "extra keys allowed": a recorder may add
// "width"/"height", and then the replay reports them.
FrameSize recorded_size(const std::string& line) {
  const nlohmann::json json = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
  FrameSize size;
  if (!json.is_object()) return size;
  const auto read = [&json](const char* key) {
    const auto found = json.find(key);
    return found != json.end() && found->is_number_integer() ? found->get<int>() : 0;
  };
  size.width = std::max(0, read("width"));
  size.height = std::max(0, read("height"));
  return size;
}

struct Recording {
  std::vector<FeatureFrame> frames;
  std::vector<std::string> camera_ids;  // in order of first appearance
  std::vector<FrameSize> first_sizes;   // per camera_ids entry
  std::vector<std::string> malformed;   // "<file>:<line>: <reason>"
};

Recording read_recording(const fs::path& path) {
  std::error_code error;
  if (!fs::exists(path, error)) throw std::runtime_error("no such file");
  if (fs::is_directory(path, error)) throw std::runtime_error("is a directory, expected a JSONL file");
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open for reading");
  Recording recording;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    Parsed<FeatureFrame> parsed = parse_feature_frame(line);
    if (!parsed.value) {
      recording.malformed.push_back(path.string() + ":" + std::to_string(line_number) + ": " + parsed.error);
      continue;
    }
    const std::string& id = parsed.value->camera_id;
    if (std::find(recording.camera_ids.begin(), recording.camera_ids.end(), id) ==
        recording.camera_ids.end()) {
      recording.camera_ids.push_back(id);
      recording.first_sizes.push_back(recorded_size(line));
    }
    recording.frames.push_back(std::move(*parsed.value));
  }
  if (in.bad()) throw std::runtime_error("read error");
  return recording;
}

std::string join(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
  return text;
}

class FeaturesSource final : public FrameSource {
 public:
  FeaturesSource(std::vector<FeatureFrame> frames, SourceInfo info, std::vector<std::string> malformed,
                 const SourceOptions& options)
      : frames_(std::move(frames)),
        info_(std::move(info)),
        paced_(options.paced),
        rate_scale_(options.rate_scale),
        max_frames_(options.max_frames),
        anchor_ns_(options.sim_epoch_ns),
        epoch_file_(options.sim_epoch_file) {
    if (!malformed.empty()) {
      counters_["malformed"] = malformed.size();
      // The first line that failed says most about a wrong file; the count says how much.
      last_error_ = malformed.front();
      if (malformed.size() > 1)
        last_error_ += " (and " + std::to_string(malformed.size() - 1) + " more malformed lines)";
    }
  }

  const SourceInfo& info() const override { return info_; }

  std::optional<CapturedFrame> next() override {
    apply_rewind();
    if (stop_.stopped()) return std::nullopt;
    if (next_index_ >= frames_.size()) return std::nullopt;
    if (max_frames_ >= 0 && static_cast<std::int64_t>(next_index_) >= max_frames_) return std::nullopt;
    if (!epoch_file_.empty() && !epoch_file_read_) {  // once: a rewound replay starts from now
      anchor_ns_ = wait_for_epoch_file();
      if (anchor_ns_ == 0) return std::nullopt;  // stopped while waiting
      epoch_file_read_ = true;
    }
    const FeatureFrame& recorded = frames_[next_index_];
    // Anchored (--sim-epoch-ns), the recording's epoch (its first stamp rounded down to a whole
    // second, as panoptes_sim writes it) maps to the anchor, so nodes replaying the cameras of one
    // recording stay aligned whenever each one started. Otherwise the replay starts now.
    TimeNs origin_ns = frames_.front().stamp_ns;
    if (next_index_ == 0) replay_start_ns_ = wall_now_ns();
    if (anchor_ns_ != 0) {
      origin_ns = frames_.front().stamp_ns / kNsPerSecond * kNsPerSecond;
      replay_start_ns_ = anchor_ns_;
    }
    const TimeNs offset_ns =
        static_cast<TimeNs>(std::llround(static_cast<double>(recorded.stamp_ns - origin_ns) / rate_scale_));
    const TimeNs stamp_ns = replay_start_ns_ + offset_ns;
    if (paced_ && !stop_.sleep_until_wall(stamp_ns)) return std::nullopt;

    CapturedFrame frame;
    frame.sequence = recorded.frame;
    frame.stamp_ns = stamp_ns;
    frame.arrival_ns = wall_now_ns();
    frame.blobs = recorded.blobs;
    ++next_index_;
    return frame;
  }

  void stop() override { stop_.stop(); }

  // Rewinds: the replay starts again from the first frame, stamped from the next frame's time.
  void restart() override {
    std::lock_guard lock(mutex_);
    rewind_requested_ = true;
  }

  SourceCounters counters() const override {
    std::lock_guard lock(mutex_);
    return counters_;
  }

  std::string last_error() const override {
    std::lock_guard lock(mutex_);
    return last_error_;
  }

 private:
  // The epoch from --sim-epoch-file, once the file holds it (polled every 10 ms); 0 if stopped
  // first. Throws (the source fails, naming the file) if it holds anything but a positive integer.
  TimeNs wait_for_epoch_file() {
    while (!stop_.stopped()) {
      std::ifstream in(epoch_file_);
      std::string text;
      if (in && std::getline(in, text) && !text.empty()) {
        TimeNs epoch_ns = 0;
        const auto result = std::from_chars(text.data(), text.data() + text.size(), epoch_ns);
        if (result.ec != std::errc() || result.ptr != text.data() + text.size() || epoch_ns <= 0)
          throw std::runtime_error(
              epoch_file_ + ": expected the epoch as a positive integer of nanoseconds, got '" + text + "'");
        return epoch_ns;
      }
      if (!stop_.sleep_until_wall(wall_now_ns() + 10'000'000)) break;
    }
    return 0;
  }

  void apply_rewind() {
    std::lock_guard lock(mutex_);
    if (rewind_requested_) {
      rewind_requested_ = false;
      next_index_ = 0;
      anchor_ns_ = 0;  // a rewound replay starts from now
    }
  }

  const std::vector<FeatureFrame> frames_;
  const SourceInfo info_;
  const bool paced_;
  const double rate_scale_;
  const std::int64_t max_frames_;
  TimeNs anchor_ns_;              // wall time of the recording's epoch; 0: the replay starts when it starts
  const std::string epoch_file_;  // --sim-epoch-file ("" = none)
  bool epoch_file_read_ = false;
  std::size_t next_index_ = 0;  // capture thread (and restart(), under mutex_, applied by next())
  TimeNs replay_start_ns_ = 0;

  StopSignal stop_;
  mutable std::mutex mutex_;
  bool rewind_requested_ = false;
  SourceCounters counters_;
  std::string last_error_;
};

}  // namespace

std::unique_ptr<FrameSource> open_features_source(const std::string& target, const SourceOptions& options) {
  const std::string spec = "features:" + target;
  if (!(options.rate_scale > 0) || !std::isfinite(options.rate_scale)) {
    throw std::runtime_error(spec + ": rate scale must be a positive number (got " +
                             std::to_string(options.rate_scale) + ")");
  }
  Recording recording;
  try {
    recording = read_recording(target);
  } catch (const std::exception& error) {
    throw std::runtime_error(spec + ": " + error.what());
  }
  if (recording.frames.empty()) {
    throw std::runtime_error(spec + ": no feature frames in the file" +
                             (recording.malformed.empty()
                                  ? std::string()
                                  : " (" + std::to_string(recording.malformed.size()) +
                                        " malformed lines, first: " + recording.malformed.front() + ")"));
  }

  std::string camera_id;
  if (!options.camera_id.empty()) {
    camera_id = options.camera_id;
    if (std::find(recording.camera_ids.begin(), recording.camera_ids.end(), camera_id) ==
        recording.camera_ids.end()) {
      throw std::runtime_error(spec + ": no frames of camera '" + camera_id +
                               "' (the file has: " + join(recording.camera_ids) + ")");
    }
  } else if (recording.camera_ids.size() > 1) {
    throw std::runtime_error(spec + ": the file holds frames of several cameras (" +
                             join(recording.camera_ids) + "); choose one with --camera-id");
  } else {
    camera_id = recording.camera_ids.front();
  }

  std::vector<FeatureFrame> frames;
  for (FeatureFrame& frame : recording.frames) {
    if (frame.camera_id == camera_id) frames.push_back(std::move(frame));
  }
  const auto camera_index = static_cast<std::size_t>(
      std::find(recording.camera_ids.begin(), recording.camera_ids.end(), camera_id) -
      recording.camera_ids.begin());

  SourceInfo info;
  info.camera_id = camera_id;
  info.backend = "features";
  info.model = "feature replay";
  info.serial = target;
  info.width = recording.first_sizes[camera_index].width;
  info.height = recording.first_sizes[camera_index].height;
  if (frames.size() > 1 && frames.back().stamp_ns > frames.front().stamp_ns) {
    info.nominal_rate_hz = static_cast<double>(frames.size() - 1) /
                           ns_to_seconds(frames.back().stamp_ns - frames.front().stamp_ns) *
                           options.rate_scale;
  }
  return std::make_unique<FeaturesSource>(std::move(frames), std::move(info), std::move(recording.malformed),
                                          options);
}

}  // namespace panoptes::camera
