// SPDX-License-Identifier: Apache-2.0
// An in-memory V4L2 capture device for tests (these machines have no /dev/video*). One
// FakeV4l2Camera is the hardware; every open() makes a V4l2Device on it, so a source that
// reconnects finds the same camera again. The camera follows the V4L2 rules the source relies on
// and checks them: buffers cycle application -> queued -> filled -> application, formats are
// adjusted rather than refused, an absolute exposure is refused while auto exposure is on.
#pragma once

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/image_file.h"
#include "panoptes/time.h"
#include "v4l2_device.h"
#include "v4l2_source.h"

namespace panoptes::camera::testing {

// One format the camera offers at one size; rows are padded by `padding` bytes.
struct FakeFormat {
  std::uint32_t fourcc = V4L2_PIX_FMT_GREY;
  int width = 64;
  int height = 48;
  int padding = 0;
};

// Faults applied to the frames the camera produces next, one per frame, in order.
enum class FakeFault { kNone, kErrorFlag, kShortBuffer, kSkipThreeSequences, kCorruptJpeg, kDisconnect };

class FakeV4l2Camera : public std::enable_shared_from_this<FakeV4l2Camera> {
 public:
  struct Config {
    std::vector<FakeFormat> formats{FakeFormat{}};
    bool monotonic_timestamps = true;
    bool start_of_exposure_timestamps = false;  // V4L2_BUF_FLAG_TSTAMP_SRC_SOE (uvcvideo) vs EOF
    bool has_exposure = true;
    bool has_exposure_auto = true;
    bool has_gain = true;
    bool timeperframe = true;
    std::vector<std::uint32_t> frame_rates{30, 60, 120};  // the intervals the sensor can do
    int max_buffers = 32;
  };

  static constexpr std::int32_t kExposureMin = 1;  // 100 µs units
  static constexpr std::int32_t kExposureMax = 5000;
  static constexpr std::int32_t kExposureDefault = 100;
  static constexpr std::int32_t kGainMin = 0;
  static constexpr std::int32_t kGainMax = 255;
  static constexpr std::int32_t kGainDefault = 32;

  explicit FakeV4l2Camera(Config config) : config_(std::move(config)) { reset_controls(); }

  // What the camera shows in frame `sequence` at (x, y): a background ramp that moves with the
  // sequence, plus three bright 5x5 spots. 8-bit formats use `bits` 8, Y16 uses 16.
  static int pixel(int x, int y, std::uint32_t sequence, int bits, int width, int height) {
    const int spots[3][2] = {{width / 4, height / 4}, {width / 2, height / 2}, {3 * width / 4, height / 3}};
    for (const auto& spot : spots) {
      if (std::abs(x - spot[0]) <= 2 && std::abs(y - spot[1]) <= 2) return bits > 8 ? 60000 : 250;
    }
    if (bits > 8) return static_cast<int>((x * 257u + y * 97u + sequence * 13u) % 50000u);
    return static_cast<int>((x + 2u * y + sequence) % 50u);
  }

  // The factory a V4l2Source is given.
  V4l2DeviceFactory factory() {
    std::weak_ptr<FakeV4l2Camera> weak = weak_from_this();
    return [weak](const std::string& path) -> std::unique_ptr<V4l2Device> {
      const auto camera = weak.lock();
      return camera->open(path);
    };
  }

  std::unique_ptr<V4l2Device> open(const std::string& path);

  // --- test controls (any thread) --------------------------------------------------------------
  void inject(std::vector<FakeFault> faults) {
    std::lock_guard lock(mutex_);
    faults_.insert(faults_.end(), faults.begin(), faults.end());
  }
  // A paused camera produces no frames (dequeue times out).
  void set_paused(bool paused) {
    {
      std::lock_guard lock(mutex_);
      paused_ = paused;
    }
    wake_.notify_all();
  }
  // After a kDisconnect fault, this many open() attempts fail before the camera is back.
  void set_failed_opens_after_disconnect(int count) {
    std::lock_guard lock(mutex_);
    failed_opens_after_disconnect_ = count;
  }

  // --- observations ----------------------------------------------------------------------------
  int opens() const {
    std::lock_guard lock(mutex_);
    return opens_;
  }
  int failed_opens() const {
    std::lock_guard lock(mutex_);
    return failed_opens_;
  }
  int buffers_allocated() const {
    std::lock_guard lock(mutex_);
    return static_cast<int>(buffers_.size());
  }
  int buffers_queued() const {
    std::lock_guard lock(mutex_);
    return static_cast<int>(queue_.size());
  }
  int buffers_requested() const {
    std::lock_guard lock(mutex_);
    return buffers_requested_;
  }
  int mappings() const {
    std::lock_guard lock(mutex_);
    return mappings_;
  }
  bool streaming() const {
    std::lock_guard lock(mutex_);
    return streaming_;
  }
  std::uint32_t current_fourcc() const {
    std::lock_guard lock(mutex_);
    return current_.fourcc;
  }
  std::int32_t control_value(std::uint32_t id) const {
    std::lock_guard lock(mutex_);
    return controls_.at(id).value;
  }
  std::uint32_t frame_rate() const {
    std::lock_guard lock(mutex_);
    return frame_rate_;
  }
  // Every VIDIOC_S_CTRL that succeeded, in order.
  std::vector<std::pair<std::uint32_t, std::int32_t>> controls_set() const {
    std::lock_guard lock(mutex_);
    return controls_set_;
  }
  // CLOCK_MONOTONIC stamp of the last frame produced.
  TimeNs last_timestamp_ns() const {
    std::lock_guard lock(mutex_);
    return last_timestamp_ns_;
  }

 private:
  friend class FakeV4l2Device;

  struct Control {
    V4l2ControlRange range;
    std::int32_t value = 0;
  };

  enum class BufferState { kApplication, kQueued };
  struct Buffer {
    std::vector<std::uint8_t> memory;
    BufferState state = BufferState::kApplication;
  };

  static int bytes_per_pixel(std::uint32_t fourcc) {
    return fourcc == V4L2_PIX_FMT_GREY ? 1 : fourcc == V4L2_PIX_FMT_MJPEG ? 0 : 2;
  }

  static V4l2Status gone() { return {ENODEV, "fake: No such device"}; }

  void reset_controls() {
    controls_.clear();
    if (config_.has_exposure) {
      controls_[V4L2_CID_EXPOSURE_ABSOLUTE] = {{kExposureMin, kExposureMax, 1, kExposureDefault, 0},
                                               kExposureDefault};
    }
    if (config_.has_exposure_auto) {
      controls_[V4L2_CID_EXPOSURE_AUTO] = {{0, 3, 1, V4L2_EXPOSURE_APERTURE_PRIORITY, 0},
                                           V4L2_EXPOSURE_APERTURE_PRIORITY};
    }
    if (config_.has_gain) controls_[V4L2_CID_GAIN] = {{kGainMin, kGainMax, 1, kGainDefault, 0}, kGainDefault};
    frame_rate_ = config_.frame_rates.front();
  }

  V4l2Format describe(const FakeFormat& format) const {
    V4l2Format described;
    described.fourcc = format.fourcc;
    described.width = format.width;
    described.height = format.height;
    const int bpp = bytes_per_pixel(format.fourcc);
    described.bytesperline = bpp == 0 ? 0 : format.width * bpp + format.padding;
    described.sizeimage = static_cast<std::uint32_t>(bpp == 0 ? format.width * format.height * 2
                                                              : described.bytesperline * format.height);
    return described;
  }

  // Drivers pick a supported format instead of failing (section "Data Formats").
  FakeFormat adjust(const V4l2Format& wanted) const {
    for (const FakeFormat& format : config_.formats) {
      if (format.fourcc == wanted.fourcc) return format;
    }
    return config_.formats.front();
  }

  // Fills buffer `index` with the next frame; returns the dequeued description. Lock held.
  V4l2DequeuedBuffer produce(int index, FakeFault fault) {
    if (fault == FakeFault::kSkipThreeSequences) sequence_ += 3;
    Buffer& buffer = buffers_[static_cast<std::size_t>(index)];
    const V4l2Format format = describe(current_);
    std::fill(buffer.memory.begin(), buffer.memory.end(), 0xEE);  // padding shows up if read as pixels
    std::uint32_t bytesused = format.sizeimage;
    const auto value = [&](int x, int y, int bits) {
      return pixel(x, y, sequence_, bits, format.width, format.height);
    };
    switch (format.fourcc) {
      case V4L2_PIX_FMT_GREY:
        for (int y = 0; y < format.height; ++y) {
          for (int x = 0; x < format.width; ++x) {
            buffer.memory[y * format.bytesperline + x] = static_cast<std::uint8_t>(value(x, y, 8));
          }
        }
        break;
      case V4L2_PIX_FMT_Y16:
        for (int y = 0; y < format.height; ++y) {
          for (int x = 0; x < format.width; ++x) {
            const int v = value(x, y, 16);
            buffer.memory[y * format.bytesperline + 2 * x] = static_cast<std::uint8_t>(v & 0xff);
            buffer.memory[y * format.bytesperline + 2 * x + 1] = static_cast<std::uint8_t>(v >> 8);
          }
        }
        break;
      case V4L2_PIX_FMT_YUYV:
        for (int y = 0; y < format.height; ++y) {
          for (int x = 0; x < format.width; ++x) {
            buffer.memory[y * format.bytesperline + 2 * x] = static_cast<std::uint8_t>(value(x, y, 8));
            buffer.memory[y * format.bytesperline + 2 * x + 1] = (x % 2 == 0) ? 0x40 : 0xC0;  // U, V
          }
        }
        break;
      case V4L2_PIX_FMT_MJPEG: {
        Image grey(static_cast<int>(format.width), static_cast<int>(format.height), 8);
        for (int y = 0; y < grey.height; ++y) {
          for (int x = 0; x < grey.width; ++x) grey.row8(y)[x] = static_cast<std::uint8_t>(value(x, y, 8));
        }
        const std::vector<std::uint8_t> jpeg = encode_jpeg_grey(grey, 95);
        std::copy(jpeg.begin(), jpeg.end(), buffer.memory.begin());
        bytesused = static_cast<std::uint32_t>(jpeg.size());
        if (fault == FakeFault::kCorruptJpeg) {
          std::fill(buffer.memory.begin(), buffer.memory.begin() + 64, 0x5A);  // no SOI marker: undecodable
          bytesused = 64;
        }
        break;
      }
      default:
        break;
    }
    V4l2DequeuedBuffer dequeued;
    dequeued.index = index;
    dequeued.bytesused = fault == FakeFault::kShortBuffer ? bytesused / 2 : bytesused;
    dequeued.sequence = sequence_++;
    last_timestamp_ns_ = monotonic_now_ns();
    dequeued.timestamp.tv_sec = static_cast<time_t>(last_timestamp_ns_ / kNsPerSecond);
    dequeued.timestamp.tv_usec = static_cast<suseconds_t>(last_timestamp_ns_ % kNsPerSecond / 1000);
    last_timestamp_ns_ = static_cast<TimeNs>(dequeued.timestamp.tv_sec) * kNsPerSecond +
                         static_cast<TimeNs>(dequeued.timestamp.tv_usec) * 1000;
    dequeued.flags =
        config_.monotonic_timestamps ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN;
    dequeued.flags |=
        config_.start_of_exposure_timestamps ? V4L2_BUF_FLAG_TSTAMP_SRC_SOE : V4L2_BUF_FLAG_TSTAMP_SRC_EOF;
    if (fault == FakeFault::kErrorFlag) dequeued.flags |= V4L2_BUF_FLAG_ERROR;
    dequeued.flags |= V4L2_BUF_FLAG_DONE;
    return dequeued;
  }

  const Config config_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::uint64_t generation_ = 0;  // bumped when unplugged: older devices answer ENODEV
  bool unplugged_ = false;
  bool open_ = false;
  int failed_opens_after_disconnect_ = 0;
  int failed_opens_remaining_ = 0;
  int opens_ = 0;
  int failed_opens_ = 0;
  bool paused_ = false;
  std::deque<FakeFault> faults_;
  FakeFormat current_ = config_.formats.front();
  std::vector<Buffer> buffers_;
  std::deque<int> queue_;
  int buffers_requested_ = 0;
  int mappings_ = 0;
  bool streaming_ = false;
  std::uint32_t sequence_ = 0;
  std::map<std::uint32_t, Control> controls_;
  std::vector<std::pair<std::uint32_t, std::int32_t>> controls_set_;
  std::uint32_t frame_rate_ = 30;
  TimeNs last_timestamp_ns_ = 0;
};

class FakeV4l2Device final : public V4l2Device {
 public:
  FakeV4l2Device(std::shared_ptr<FakeV4l2Camera> camera, std::uint64_t generation)
      : camera_(std::move(camera)), generation_(generation) {}

  ~FakeV4l2Device() override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return;
    // close() stops streaming; buffers are freed only once nothing maps them any more (a mapping
    // holds its buffer, section "Streaming I/O (Memory Mapping)"), so leaked mappings show.
    camera_->streaming_ = false;
    camera_->queue_.clear();
    if (camera_->mappings_ == 0) camera_->buffers_.clear();
    camera_->open_ = false;
  }

  V4l2Status query_capabilities(V4l2Capabilities* capabilities) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    capabilities->driver = "fake";
    capabilities->card = "Fake V4L2 camera";
    capabilities->bus_info = "platform:fake-0";
    capabilities->capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
    return {};
  }

  V4l2Status enumerate_formats(std::vector<std::uint32_t>* fourccs) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    fourccs->clear();
    for (const FakeFormat& format : camera_->config_.formats) fourccs->push_back(format.fourcc);
    return {};
  }

  V4l2Status get_format(V4l2Format* format) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    *format = camera_->describe(camera_->current_);
    return {};
  }

  V4l2Status try_format(V4l2Format* format) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    *format = camera_->describe(camera_->adjust(*format));
    return {};
  }

  V4l2Status set_format(V4l2Format* format) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    if (!camera_->buffers_.empty()) return {EBUSY, "VIDIOC_S_FMT: Device or resource busy"};
    camera_->current_ = camera_->adjust(*format);
    *format = camera_->describe(camera_->current_);
    return {};
  }

  V4l2Status request_buffers(int* count) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    if (camera_->streaming_) return {EBUSY, "VIDIOC_REQBUFS: Device or resource busy"};
    // vb2 refuses to reallocate or free buffers that are still mapped.
    if (camera_->mappings_ > 0) return {EBUSY, "VIDIOC_REQBUFS: Device or resource busy (buffers mapped)"};
    camera_->buffers_requested_ = *count;
    *count = std::min(*count, camera_->config_.max_buffers);
    camera_->queue_.clear();
    camera_->buffers_.assign(static_cast<std::size_t>(*count), {});
    const std::uint32_t size = camera_->describe(camera_->current_).sizeimage;
    for (auto& buffer : camera_->buffers_) buffer.memory.assign(size, 0);
    return {};
  }

  V4l2Status query_buffer(int index, V4l2BufferInfo* info) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    if (index < 0 || index >= static_cast<int>(camera_->buffers_.size()))
      return {EINVAL, "VIDIOC_QUERYBUF: bad index"};
    info->length =
        static_cast<std::uint32_t>(camera_->buffers_[static_cast<std::size_t>(index)].memory.size());
    info->offset = static_cast<std::uint32_t>(index) << 16;
    return {};
  }

  V4l2Status map_buffer(const V4l2BufferInfo& info, const std::uint8_t** data) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    const std::size_t index = info.offset >> 16;
    if (index >= camera_->buffers_.size()) return {EINVAL, "mmap: Invalid argument"};
    ++camera_->mappings_;
    *data = camera_->buffers_[index].memory.data();
    return {};
  }

  // Like munmap, this works on a vanished device too.
  void unmap_buffer(const std::uint8_t* /*data*/, std::uint32_t /*length*/) override {
    std::lock_guard lock(camera_->mutex_);
    --camera_->mappings_;
  }

  V4l2Status queue_buffer(int index) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    if (index < 0 || index >= static_cast<int>(camera_->buffers_.size()))
      return {EINVAL, "VIDIOC_QBUF: bad index"};
    auto& buffer = camera_->buffers_[static_cast<std::size_t>(index)];
    if (buffer.state == FakeV4l2Camera::BufferState::kQueued) return {EINVAL, "VIDIOC_QBUF: already queued"};
    buffer.state = FakeV4l2Camera::BufferState::kQueued;
    camera_->queue_.push_back(index);
    camera_->wake_.notify_all();
    return {};
  }

  V4l2Status dequeue_buffer(int timeout_ms, V4l2DequeuedBuffer* result) override {
    std::unique_lock lock(camera_->mutex_);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      if (!alive()) return FakeV4l2Camera::gone();
      if (!camera_->streaming_) return {EINVAL, "VIDIOC_DQBUF: not streaming"};
      if (!camera_->paused_ && !camera_->queue_.empty()) break;
      if (camera_->wake_.wait_until(lock, deadline) == std::cv_status::timeout) {
        return {ETIMEDOUT, "fake: no frame within " + std::to_string(timeout_ms) + " ms"};
      }
    }
    FakeFault fault = FakeFault::kNone;
    if (!camera_->faults_.empty()) {
      fault = camera_->faults_.front();
      camera_->faults_.pop_front();
    }
    if (fault == FakeFault::kDisconnect) {
      camera_->unplugged_ = true;
      camera_->failed_opens_remaining_ = camera_->failed_opens_after_disconnect_;
      ++camera_->generation_;
      camera_->streaming_ = false;
      camera_->queue_.clear();
      camera_->buffers_.clear();
      camera_->open_ = false;
      camera_->reset_controls();  // a replugged camera starts from its defaults
      return {ENODEV, "VIDIOC_DQBUF: No such device"};
    }
    const int index = camera_->queue_.front();
    camera_->queue_.pop_front();
    camera_->buffers_[static_cast<std::size_t>(index)].state = FakeV4l2Camera::BufferState::kApplication;
    *result = camera_->produce(index, fault);
    return {};
  }

  V4l2Status stream_on() override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    if (camera_->buffers_.empty()) return {EINVAL, "VIDIOC_STREAMON: no buffers"};
    camera_->streaming_ = true;
    camera_->sequence_ = 0;
    return {};
  }

  V4l2Status stream_off() override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    camera_->streaming_ = false;
    for (auto& buffer : camera_->buffers_) buffer.state = FakeV4l2Camera::BufferState::kApplication;
    camera_->queue_.clear();
    camera_->wake_.notify_all();
    return {};
  }

  V4l2Status query_control(std::uint32_t id, V4l2ControlRange* range) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    const auto found = camera_->controls_.find(id);
    if (found == camera_->controls_.end()) return {EINVAL, "VIDIOC_QUERYCTRL: Invalid argument"};
    *range = found->second.range;
    return {};
  }

  V4l2Status get_control(std::uint32_t id, std::int32_t* value) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    const auto found = camera_->controls_.find(id);
    if (found == camera_->controls_.end()) return {EINVAL, "VIDIOC_G_CTRL: Invalid argument"};
    *value = found->second.value;
    return {};
  }

  V4l2Status set_control(std::uint32_t id, std::int32_t value) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    const auto found = camera_->controls_.find(id);
    if (found == camera_->controls_.end()) return {EINVAL, "VIDIOC_S_CTRL: Invalid argument"};
    if (value < found->second.range.minimum || value > found->second.range.maximum) {
      return {ERANGE, "VIDIOC_S_CTRL: Numerical result out of range"};
    }
    // uvcvideo refuses the absolute exposure while an automatic mode owns it.
    if (id == V4L2_CID_EXPOSURE_ABSOLUTE) {
      const auto mode = camera_->controls_.find(V4L2_CID_EXPOSURE_AUTO);
      if (mode != camera_->controls_.end() && mode->second.value != V4L2_EXPOSURE_MANUAL) {
        return {EACCES, "VIDIOC_S_CTRL: Permission denied"};
      }
    }
    found->second.value = value;
    camera_->controls_set_.emplace_back(id, value);
    return {};
  }

  V4l2Status get_frame_interval(V4l2FrameInterval* interval, bool* supported) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    *supported = camera_->config_.timeperframe;
    *interval = {1, camera_->frame_rate_};
    return {};
  }

  V4l2Status set_frame_interval(V4l2FrameInterval* interval) override {
    std::lock_guard lock(camera_->mutex_);
    if (!alive()) return FakeV4l2Camera::gone();
    if (!camera_->config_.timeperframe || interval->numerator == 0) {
      *interval = {1, camera_->frame_rate_};
      return {};
    }
    // Like the drivers: the nearest rate the sensor can do.
    const double wanted = static_cast<double>(interval->denominator) / interval->numerator;
    std::uint32_t best = camera_->config_.frame_rates.front();
    for (const std::uint32_t rate : camera_->config_.frame_rates) {
      if (std::abs(rate - wanted) < std::abs(best - wanted)) best = rate;
    }
    camera_->frame_rate_ = best;
    *interval = {1, best};
    return {};
  }

 private:
  bool alive() const { return camera_->generation_ == generation_; }

  std::shared_ptr<FakeV4l2Camera> camera_;
  std::uint64_t generation_;
};

inline std::unique_ptr<V4l2Device> FakeV4l2Camera::open(const std::string& /*path*/) {
  std::lock_guard lock(mutex_);
  if (unplugged_) {
    if (failed_opens_remaining_ > 0) {
      --failed_opens_remaining_;
      ++failed_opens_;
      throw V4l2OpenError(ENOENT, "cannot open: No such file or directory");
    }
    unplugged_ = false;
  }
  if (open_) throw V4l2OpenError(EBUSY, "cannot open: Device or resource busy (the fake allows one user)");
  open_ = true;
  ++opens_;
  return std::make_unique<FakeV4l2Device>(shared_from_this(), generation_);
}

}  // namespace panoptes::camera::testing
