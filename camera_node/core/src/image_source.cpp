// SPDX-License-Identifier: Apache-2.0
#include "image_source.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "panoptes/glob.h"
#include "panoptes/image_file.h"

namespace panoptes::camera {
namespace {

namespace fs = std::filesystem;

bool has_image_extension(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".pgm" || extension == ".pnm" || extension == ".png";
}

bool has_glob_magic(const std::string& pattern) {
  return pattern.find_first_of("*?[") != std::string::npos;
}

std::vector<fs::path> list_files(const std::string& pattern) {
  const std::string spec = "images:" + pattern;
  std::vector<fs::path> files;
  std::error_code error;
  if (fs::is_directory(pattern, error)) {
    for (const auto& entry : fs::directory_iterator(pattern, error)) {
      if (entry.is_regular_file(error) && has_image_extension(entry.path())) files.push_back(entry.path());
    }
    if (error) throw std::runtime_error(spec + ": cannot list directory: " + error.message());
    // Name order is the frame order (the offline contract); directory order is arbitrary.
    std::sort(files.begin(), files.end());
  } else {
    if (!has_glob_magic(pattern) && !fs::exists(pattern, error)) {
      throw std::runtime_error(spec + ": no such directory");
    }
    // In name order; throws naming the pattern if glob(3) fails.
    for (fs::path& path : glob_files(pattern))
      if (fs::is_regular_file(path, error)) files.push_back(std::move(path));
  }
  if (files.empty()) throw std::runtime_error(spec + ": no PGM/PNG files match");
  return files;
}

class ImageFileSource final : public FrameSource {
 public:
  ImageFileSource(std::vector<fs::path> files, const SourceOptions& options)
      : files_(std::move(files)), max_frames_(options.max_frames) {
    // The first readable file sets the image size the node announces; if none can be read,
    // the source cannot start.
    while (!first_ && first_index_ < files_.size()) {
      try {
        first_ = read_grey_image(files_[first_index_]);
      } catch (const std::runtime_error& error) {
        skip(error.what());
        ++first_index_;
      }
    }
    if (!first_)
      throw std::runtime_error("none of the " + std::to_string(files_.size()) + " files can be read (" +
                               last_error_ + ")");
    next_index_ = first_index_;
    info_.camera_id = options.camera_id.empty() ? "images" : options.camera_id;
    info_.backend = "images";
    info_.model = "image files";
    info_.width = first_->width;
    info_.height = first_->height;
  }

  const SourceInfo& info() const override { return info_; }

  std::optional<CapturedFrame> next() override {
    if (stopped_ || next_index_ >= files_.size()) return std::nullopt;
    if (max_frames_ >= 0 && static_cast<std::int64_t>(next_index_) >= max_frames_) return std::nullopt;
    CapturedFrame frame;
    if (first_) {
      frame.image = std::move(*first_);
      first_.reset();
    } else {
      // A corrupt, truncated or colour file is counted and skipped; the stream goes on.
      while (true) {
        if (next_index_ >= files_.size()) return std::nullopt;
        try {
          frame.image = read_grey_image(files_[next_index_]);
          break;
        } catch (const std::runtime_error& error) {
          skip(error.what());
          ++next_index_;
        }
      }
    }
    frame.sequence = static_cast<std::int64_t>(next_index_);
    frame.stamp_ns = 0;  // files carry no capture time
    frame.arrival_ns = wall_now_ns();
    ++next_index_;
    return frame;
  }

  void stop() override { stopped_ = true; }

  SourceCounters counters() const override {
    std::lock_guard lock(mutex_);
    if (unreadable_ == 0) return {};
    return {{"unreadable", unreadable_}};
  }
  std::string last_error() const override {
    std::lock_guard lock(mutex_);
    return last_error_;
  }

 private:
  void skip(const std::string& error) {
    std::lock_guard lock(mutex_);
    ++unreadable_;
    last_error_ = error;
  }

  mutable std::mutex mutex_;
  std::uint64_t unreadable_ = 0;
  std::string last_error_;
  std::size_t first_index_ = 0;
  std::vector<fs::path> files_;
  std::int64_t max_frames_;
  std::optional<Image> first_;  // loaded up front for info(); handed out by the first next()
  std::size_t next_index_ = 0;
  SourceInfo info_;
  std::atomic<bool> stopped_{false};
};

}  // namespace

std::unique_ptr<FrameSource> open_image_source(const std::string& pattern, const SourceOptions& options) {
  std::vector<fs::path> files = list_files(pattern);
  try {
    return std::make_unique<ImageFileSource>(std::move(files), options);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error("images:" + pattern + ": " + error.what());
  }
}

}  // namespace panoptes::camera
