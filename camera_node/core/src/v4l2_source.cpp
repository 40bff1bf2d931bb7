// SPDX-License-Identifier: Apache-2.0
// V4L2 capture with mmap streaming I/O. Section names refer to the Linux Media Infrastructure
// userspace API, part I "Video for Linux API" (docs.kernel.org/userspace-api/media/v4l).
#include "v4l2_source.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/image_file.h"

#include "v4l2_device.h"

namespace panoptes::camera {
namespace {

// dequeue_buffer() waits at most this long at a time, so stop() and restart() take effect within
// it even though the device knows nothing about them.
constexpr int kDequeueSliceMs = 50;
// The wall clock may be stepped or slewed (time sync); re-reading its offset to the monotonic
// clock this often keeps mapped stamps on the current wall time.
constexpr TimeNs kClockOffsetRefreshNs = kNsPerSecond;
// A driver that rounds the frame interval further than this from the request is reported.
constexpr double kFrameRateTolerance = 0.01;

struct PixelFormat {
  std::uint32_t fourcc;
  const char* name;
  int bytes_per_pixel;  // 0: compressed
  int bits;             // of the delivered Image
};

// Preference order: native grey first (no conversion), then deeper grey, then the Y plane of
// packed YUV, then MJPG, which costs a decode per frame and loses precision to compression.
constexpr PixelFormat kPixelFormats[] = {
    {V4L2_PIX_FMT_GREY, "GREY", 1, 8},
    {V4L2_PIX_FMT_Y16, "Y16", 2, 16},
    {V4L2_PIX_FMT_YUYV, "YUYV", 2, 8},
    {V4L2_PIX_FMT_MJPEG, "MJPG", 0, 8},
};

// Accepts the V4L2 fourcc names and the GenICam names a config shared with Aravis cameras uses.
const PixelFormat* pixel_format_by_name(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::toupper(c); });
  if (name == "MONO8" || name == "Y8") name = "GREY";
  if (name == "MONO16") name = "Y16";
  if (name == "MJPEG") name = "MJPG";
  for (const PixelFormat& format : kPixelFormats) {
    if (name == format.name) return &format;
  }
  return nullptr;
}

std::string join_formats(const std::vector<std::uint32_t>& fourccs) {
  std::string text;
  for (const std::uint32_t fourcc : fourccs) text += (text.empty() ? "" : ", ") + fourcc_to_string(fourcc);
  return text.empty() ? "none" : text;
}

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.10g", value);
  return text;
}

TimeNs timeval_to_ns(const timeval& time) {
  return static_cast<TimeNs>(time.tv_sec) * kNsPerSecond + static_cast<TimeNs>(time.tv_usec) * 1000;
}

struct Mapping {
  const std::uint8_t* data = nullptr;
  std::uint32_t length = 0;
};

// One open stream on the device; replaced as a whole on reconnection.
struct Session {
  std::unique_ptr<V4l2Device> device;
  V4l2Format format;
  const PixelFormat* pixel_format = nullptr;
  std::vector<Mapping> buffers;
  std::optional<std::uint32_t> last_sequence;  // V4L2 sequence of the last buffer dequeued
  double nominal_rate_hz = 0;
};

// Tears a stream down in the order the spec requires: STREAMOFF (which also returns all queued
// buffers), munmap, then REQBUFS(0) to free them (section "Streaming I/O (Memory Mapping)").
// Errors are ignored: a vanished device fails every call, and closing must still release memory.
void close_session(Session& session) {
  if (!session.device) return;
  session.device->stream_off();
  for (const Mapping& mapping : session.buffers) session.device->unmap_buffer(mapping.data, mapping.length);
  session.buffers.clear();
  int none = 0;
  session.device->request_buffers(&none);
  session.device.reset();
}

class V4l2Source final : public FrameSource {
 public:
  V4l2Source(std::string path, V4l2DeviceFactory open_device, const SourceOptions& options)
      : path_(std::move(path)),
        open_device_(std::move(open_device)),
        max_frames_(options.max_frames),
        wanted_(options.settings) {
    session_ = open_session();
    const std::string node = std::filesystem::path(path_).filename().string();
    info_.camera_id = options.camera_id.empty() ? node : options.camera_id;
    info_.backend = "v4l2";
    info_.model = card_;
    info_.serial = bus_info_;
    info_.width = session_.format.width;
    info_.height = session_.format.height;
    info_.bits = session_.pixel_format->bits;
    info_.nominal_rate_hz = session_.nominal_rate_hz;
    waiting_since_ns_ = monotonic_now_ns();
  }

  V4l2Source(const V4l2Source&) = delete;
  V4l2Source& operator=(const V4l2Source&) = delete;
  ~V4l2Source() override { close_session(session_); }

  const SourceInfo& info() const override { return info_; }

  std::optional<CapturedFrame> next() override {
    while (true) {
      if (stopped()) return std::nullopt;
      if (max_frames_ >= 0 && delivered_ >= max_frames_) return std::nullopt;
      if (take_restart_request()) {
        drop_session();
        reconnect_due_ns_ = monotonic_now_ns();
      }
      if (!session_.device) {
        reopen();
        continue;
      }
      V4l2DequeuedBuffer buffer;
      const V4l2Status status = session_.device->dequeue_buffer(kDequeueSliceMs, &buffer);
      if (status.error == ETIMEDOUT) {
        note_waiting();
        continue;
      }
      if (!status.ok()) {
        fail_stream(status);
        continue;
      }
      if (buffer.index < 0 || buffer.index >= static_cast<int>(session_.buffers.size())) {
        fail_stream({EINVAL, "VIDIOC_DQBUF returned buffer index " + std::to_string(buffer.index)});
        continue;
      }
      waiting_since_ns_ = monotonic_now_ns();
      std::optional<CapturedFrame> frame = convert(buffer);
      // The buffer goes back to the driver before the frame leaves: a consumer that holds frames
      // must not starve the driver of buffers (the image was copied out).
      if (const V4l2Status queued = session_.device->queue_buffer(buffer.index); !queued.ok()) {
        fail_stream(queued);
        continue;
      }
      if (frame) {
        ++delivered_;
        return frame;
      }
    }
  }

  void stop() override {
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
    }
    wake_.notify_all();
  }

  void restart() override {
    {
      std::lock_guard lock(mutex_);
      restart_requested_ = true;
    }
    wake_.notify_all();
  }

  std::string set_control(Control control, double value) override {
    std::shared_lock device_lock(device_mutex_);
    if (!session_.device) return std::string(control_name(control)) + ": the device is disconnected";
    std::string error = apply_control(*session_.device, control, value);
    if (error.empty()) {
      // A reconnected device starts from its defaults: remember what to apply again.
      std::lock_guard lock(mutex_);
      switch (control) {
        case Control::kExposureUs:
          wanted_.exposure_us = value;
          break;
        case Control::kGainDb:
          wanted_.gain_db = value;
          break;
        case Control::kFrameRateHz:
          wanted_.frame_rate_hz = value;
          break;
      }
    }
    return error;
  }

  std::optional<double> control(Control control) const override {
    std::shared_lock device_lock(device_mutex_);
    if (!session_.device) return std::nullopt;
    V4l2Device& device = *session_.device;
    std::int32_t value = 0;
    switch (control) {
      case Control::kExposureUs:
        if (!device.get_control(V4L2_CID_EXPOSURE_ABSOLUTE, &value).ok()) return std::nullopt;
        return value * kExposureUnitUs;
      case Control::kGainDb:
        if (!device.get_control(V4L2_CID_GAIN, &value).ok()) return std::nullopt;
        return value;
      case Control::kFrameRateHz: {
        V4l2FrameInterval interval;
        bool supported = false;
        if (!device.get_frame_interval(&interval, &supported).ok() || interval.numerator == 0)
          return std::nullopt;
        return static_cast<double>(interval.denominator) / interval.numerator;
      }
    }
    return std::nullopt;
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
  // V4L2_CID_EXPOSURE_ABSOLUTE counts 100 µs units (section "Camera Control Reference").
  static constexpr double kExposureUnitUs = 100.0;

  // Opens and configures the device and starts streaming. Throws std::runtime_error with the
  // reason (without the "v4l2:<path>: " prefix, which the caller adds).
  Session open_session() {
    Session session;
    session.device = open_device_(path_);
    V4l2Device& device = *session.device;
    try {
      check_capabilities(device);
      negotiate_format(session);
      SourceSettings wanted;
      {
        std::lock_guard lock(mutex_);
        wanted = wanted_;
      }
      apply_settings(device, wanted);
      read_exposure(device);
      V4l2FrameInterval interval;
      bool supported = false;
      if (device.get_frame_interval(&interval, &supported).ok() && interval.numerator != 0) {
        session.nominal_rate_hz = static_cast<double>(interval.denominator) / interval.numerator;
      }
      start_streaming(session, wanted.buffers);
    } catch (...) {
      close_session(session);
      throw;
    }
    return session;
  }

  void check_capabilities(V4l2Device& device) {
    V4l2Capabilities capabilities;
    if (const V4l2Status status = device.query_capabilities(&capabilities); !status.ok()) {
      if (status.error == ENOTTY) throw std::runtime_error("not a V4L2 device (" + status.message + ")");
      throw std::runtime_error(status.message);
    }
    const std::uint32_t caps = capabilities.capabilities;
    if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) {
      if ((caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) != 0) {
        throw std::runtime_error("multi-planar capture devices are not supported (" + capabilities.card +
                                 ")");
      }
      throw std::runtime_error("not a video capture device (" + capabilities.card + ")");
    }
    if ((caps & V4L2_CAP_STREAMING) == 0) {
      throw std::runtime_error("device does not support streaming I/O (" + capabilities.card + ")");
    }
    card_ = capabilities.card;
    bus_info_ = capabilities.bus_info;
  }

  void negotiate_format(Session& session) {
    V4l2Device& device = *session.device;
    std::vector<std::uint32_t> offered;
    if (const V4l2Status status = device.enumerate_formats(&offered); !status.ok()) {
      throw std::runtime_error(status.message);
    }
    const PixelFormat* chosen = nullptr;
    if (!wanted_.pixel_format.empty()) {
      chosen = pixel_format_by_name(wanted_.pixel_format);
      if (chosen == nullptr) {
        throw std::runtime_error("pixel format '" + wanted_.pixel_format +
                                 "' is not supported by the v4l2 backend (it reads GREY, Y16, YUYV, MJPG)");
      }
      if (std::find(offered.begin(), offered.end(), chosen->fourcc) == offered.end()) {
        throw std::runtime_error("pixel format " + std::string(chosen->name) +
                                 " is not offered by the device (it offers: " + join_formats(offered) + ")");
      }
    } else {
      for (const PixelFormat& format : kPixelFormats) {
        if (std::find(offered.begin(), offered.end(), format.fourcc) != offered.end()) {
          chosen = &format;
          break;
        }
      }
      if (chosen == nullptr) {
        throw std::runtime_error("the device offers no format the v4l2 backend reads (it offers: " +
                                 join_formats(offered) + "; the backend reads GREY, Y16, YUYV, MJPG)");
      }
    }

    if (wanted_.roi_x != 0 || wanted_.roi_y != 0) {
      throw std::runtime_error(
          "roi offsets are not supported by the v4l2 backend (roi width/height select the "
          "frame size)");
    }
    V4l2Format format;
    if (const V4l2Status status = device.get_format(&format); !status.ok())
      throw std::runtime_error(status.message);
    format.fourcc = chosen->fourcc;
    if (wanted_.roi_width > 0 && wanted_.roi_height > 0) {
      format.width = wanted_.roi_width;
      format.height = wanted_.roi_height;
    }
    // TRY_FMT first so a frame size the device cannot deliver is an error, not a silent change
    // (drivers adjust sizes instead of failing: section "Data Formats", "ioctl VIDIOC_G_FMT ...").
    V4l2Format trial = format;
    if (const V4l2Status status = device.try_format(&trial); !status.ok() && status.error != ENOTTY) {
      throw std::runtime_error(status.message);
    } else if (status.ok() && wanted_.roi_width > 0 &&
               (trial.width != format.width || trial.height != format.height)) {
      throw std::runtime_error("frame size " + std::to_string(format.width) + "x" +
                               std::to_string(format.height) + " is not offered by the device for " +
                               chosen->name + " (nearest: " + std::to_string(trial.width) + "x" +
                               std::to_string(trial.height) + ")");
    }
    if (const V4l2Status status = device.set_format(&format); !status.ok())
      throw std::runtime_error(status.message);
    if (format.fourcc != chosen->fourcc) {
      throw std::runtime_error("the driver replaced pixel format " + std::string(chosen->name) + " with " +
                               fourcc_to_string(format.fourcc));
    }
    if (format.width <= 0 || format.height <= 0) {
      throw std::runtime_error("the driver set an empty frame size " + std::to_string(format.width) + "x" +
                               std::to_string(format.height));
    }
    // bytesperline 0 means unpadded for uncompressed formats (section "Single-planar format
    // structure": "... or 0 if the driver ... does not know"); it never goes below one row.
    const int row_bytes = format.width * chosen->bytes_per_pixel;
    if (format.bytesperline < row_bytes) format.bytesperline = row_bytes;
    session.format = format;
    session.pixel_format = chosen;
  }

  void apply_settings(V4l2Device& device, const SourceSettings& wanted) {
    const auto apply = [&](Control control, double value) {
      if (value <= 0) return;  // 0 = leave the device's own
      if (std::string error = apply_control(device, control, value); !error.empty()) {
        throw std::runtime_error(error);
      }
    };
    apply(Control::kFrameRateHz, wanted.frame_rate_hz);
    apply(Control::kExposureUs, wanted.exposure_us);
    apply(Control::kGainDb, wanted.gain_db);
  }

  void read_exposure(V4l2Device& device) {
    std::int32_t units = 0;
    V4l2ControlRange range;
    if (device.query_control(V4L2_CID_EXPOSURE_ABSOLUTE, &range).ok() &&
        device.get_control(V4L2_CID_EXPOSURE_ABSOLUTE, &units).ok()) {
      exposure_us_ = units * kExposureUnitUs;
    } else {
      exposure_us_ = 0;
    }
  }

  static void start_streaming(Session& session, int wanted_buffers) {
    V4l2Device& device = *session.device;
    int count = wanted_buffers;
    if (const V4l2Status status = device.request_buffers(&count); !status.ok()) {
      throw std::runtime_error(status.message);
    }
    // Fewer than two buffers cannot stream: the driver would have none to fill while one is read.
    if (count < 2) throw std::runtime_error("the driver granted only " + std::to_string(count) + " buffers");
    for (int index = 0; index < count; ++index) {
      V4l2BufferInfo buffer_info;
      if (const V4l2Status status = device.query_buffer(index, &buffer_info); !status.ok()) {
        throw std::runtime_error(status.message);
      }
      Mapping mapping;
      if (const V4l2Status status = device.map_buffer(buffer_info, &mapping.data); !status.ok()) {
        throw std::runtime_error(status.message);
      }
      mapping.length = buffer_info.length;
      session.buffers.push_back(mapping);
    }
    for (int index = 0; index < count; ++index) {
      if (const V4l2Status status = device.queue_buffer(index); !status.ok())
        throw std::runtime_error(status.message);
    }
    if (const V4l2Status status = device.stream_on(); !status.ok()) throw std::runtime_error(status.message);
  }

  // Returns "" or why the control was not set. `device` is held by the caller.
  std::string apply_control(V4l2Device& device, Control control, double value) {
    const std::string name = control_name(control);
    if (!std::isfinite(value) || value <= 0)
      return name + " must be positive (got " + format_number(value) + ")";
    switch (control) {
      case Control::kExposureUs:
        return apply_exposure(device, value);
      case Control::kGainDb:
        return apply_gain(device, value);
      case Control::kFrameRateHz:
        return apply_frame_rate(device, value);
    }
    return name + " is not supported by the v4l2 source";
  }

  std::string apply_exposure(V4l2Device& device, double exposure_us) {
    V4l2ControlRange range;
    if (!device.query_control(V4L2_CID_EXPOSURE_ABSOLUTE, &range).ok()) {
      return "exposure is not supported by this V4L2 device (no V4L2_CID_EXPOSURE_ABSOLUTE)";
    }
    const double units = std::round(exposure_us / kExposureUnitUs);
    if (units < range.minimum || units > range.maximum) {
      return "exposure " + format_number(exposure_us) + " us is out of range [" +
             format_number(range.minimum * kExposureUnitUs) + ", " +
             format_number(range.maximum * kExposureUnitUs) + "] us";
    }
    // An absolute exposure only holds in manual mode; in an auto mode the driver ignores it or
    // refuses it (section "Camera Control Reference", V4L2_CID_EXPOSURE_AUTO).
    V4l2ControlRange auto_range;
    std::int32_t mode = V4L2_EXPOSURE_MANUAL;
    if (device.query_control(V4L2_CID_EXPOSURE_AUTO, &auto_range).ok() &&
        device.get_control(V4L2_CID_EXPOSURE_AUTO, &mode).ok() && mode != V4L2_EXPOSURE_MANUAL) {
      if (const V4l2Status status = device.set_control(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL);
          !status.ok()) {
        return "exposure: cannot switch to manual exposure (" + status.message + ")";
      }
    }
    if (const V4l2Status status =
            device.set_control(V4L2_CID_EXPOSURE_ABSOLUTE, static_cast<std::int32_t>(units));
        !status.ok()) {
      return "exposure: " + status.message;
    }
    exposure_us_ = units * kExposureUnitUs;
    return {};
  }

  // V4L2 defines no unit for V4L2_CID_GAIN (section "User Controls"), so the value is passed in
  // the driver's own units; the range in the message is in those units too.
  static std::string apply_gain(V4l2Device& device, double gain) {
    V4l2ControlRange range;
    if (!device.query_control(V4L2_CID_GAIN, &range).ok()) {
      return "gain is not supported by this V4L2 device (no V4L2_CID_GAIN)";
    }
    const double value = std::round(gain);
    if (value < range.minimum || value > range.maximum) {
      return "gain " + format_number(gain) + " is out of range [" + std::to_string(range.minimum) + ", " +
             std::to_string(range.maximum) + "] (device units: V4L2 defines no unit for gain)";
    }
    if (const V4l2Status status = device.set_control(V4L2_CID_GAIN, static_cast<std::int32_t>(value));
        !status.ok()) {
      return "gain: " + status.message;
    }
    return {};
  }

  static std::string apply_frame_rate(V4l2Device& device, double rate_hz) {
    V4l2FrameInterval current;
    bool supported = false;
    if (!device.get_frame_interval(&current, &supported).ok() || !supported) {
      return "frame rate is not settable on this V4L2 device (no V4L2_CAP_TIMEPERFRAME)";
    }
    // A time per frame in milliseconds over 1000 keeps rates like 29.97 Hz exact enough.
    const double denominator = std::round(rate_hz * 1000.0);
    if (denominator < 1 || denominator > 4e9)
      return "frame rate " + format_number(rate_hz) + " Hz is out of range";
    V4l2FrameInterval interval{1000, static_cast<std::uint32_t>(denominator)};
    if (const V4l2Status status = device.set_frame_interval(&interval); !status.ok()) {
      return "frame rate: " + status.message;
    }
    if (interval.numerator == 0) return "frame rate: the driver returned an empty frame interval";
    const double applied_hz = static_cast<double>(interval.denominator) / interval.numerator;
    if (std::abs(applied_hz - rate_hz) > kFrameRateTolerance * rate_hz) {
      return "frame rate " + format_number(rate_hz) + " Hz is not available; the device now runs at " +
             format_number(applied_hz) + " Hz";
    }
    return {};
  }

  // The image of a dequeued buffer, or nullopt (counted) when it cannot be used.
  std::optional<CapturedFrame> convert(const V4l2DequeuedBuffer& buffer) {
    const TimeNs arrival_ns = wall_now_ns();
    if (session_.last_sequence) {
      // Unsigned arithmetic follows the 32-bit sequence through wrap-around.
      const std::uint32_t missing = buffer.sequence - *session_.last_sequence - 1;
      if (missing > 0 && missing < (1u << 31)) count("lost", missing);
    } else {
      sequence_base_ = next_sequence_ - buffer.sequence;
    }
    session_.last_sequence = buffer.sequence;
    const std::int64_t sequence = sequence_base_ + buffer.sequence;
    next_sequence_ = sequence + 1;

    // V4L2_BUF_FLAG_ERROR: "the buffer ... data might be corrupted" (section "Buffers").
    if ((buffer.flags & V4L2_BUF_FLAG_ERROR) != 0) {
      count("corrupt");
      return std::nullopt;
    }
    const V4l2Format& format = session_.format;
    const PixelFormat& pixel_format = *session_.pixel_format;
    const Mapping& mapping = session_.buffers[static_cast<std::size_t>(buffer.index)];
    const std::size_t used = std::min<std::size_t>(buffer.bytesused, mapping.length);
    const std::size_t needed =
        pixel_format.bytes_per_pixel == 0
            ? 1
            : static_cast<std::size_t>(format.bytesperline) * (format.height - 1) +
                  static_cast<std::size_t>(format.width) * pixel_format.bytes_per_pixel;
    if (used < needed) {
      count("short");
      return std::nullopt;
    }

    CapturedFrame frame;
    frame.sequence = sequence;
    frame.arrival_ns = arrival_ns;
    if (!fill_image(mapping.data, used, &frame.image)) {
      count("decode_error");
      return std::nullopt;
    }
    const double exposure_us = exposure_us_;
    frame.exposure_us = exposure_us;
    frame.stamp_ns = mid_exposure_stamp(buffer, arrival_ns, exposure_us);
    return frame;
  }

  bool fill_image(const std::uint8_t* data, std::size_t used, Image* image) const {
    const V4l2Format& format = session_.format;
    const std::size_t stride = static_cast<std::size_t>(format.bytesperline);
    const std::size_t width = static_cast<std::size_t>(format.width);
    switch (session_.pixel_format->fourcc) {
      case V4L2_PIX_FMT_GREY: {
        *image = Image(format.width, format.height, 8);
        for (int y = 0; y < format.height; ++y) {
          std::memcpy(image->row8(y), data + y * stride, width);
        }
        return true;
      }
      case V4L2_PIX_FMT_Y16: {
        // Little-endian whatever the host (section "V4L2_PIX_FMT_Y16"); drivers with fewer bits
        // keep them in the low part (e.g. 0..1023 for 10 bits), so the values pass through.
        *image = Image(format.width, format.height, 16);
        for (int y = 0; y < format.height; ++y) {
          const std::uint8_t* row = data + y * stride;
          std::uint16_t* out = image->row16(y);
          for (std::size_t x = 0; x < width; ++x) {
            out[x] = static_cast<std::uint16_t>(row[2 * x] | (row[2 * x + 1] << 8));
          }
        }
        return true;
      }
      case V4L2_PIX_FMT_YUYV: {
        // Y0 U0 Y1 V0: luma is every even byte (section "Packed YUV formats").
        *image = Image(format.width, format.height, 8);
        for (int y = 0; y < format.height; ++y) {
          const std::uint8_t* row = data + y * stride;
          std::uint8_t* out = image->row8(y);
          for (std::size_t x = 0; x < width; ++x) out[x] = row[2 * x];
        }
        return true;
      }
      case V4L2_PIX_FMT_MJPEG: {
        return decode_jpeg_grey(data, used, *image) && image->width == format.width &&
               image->height == format.height;
      }
    }
    return false;
  }

  // V4L2 stamps buffers on CLOCK_MONOTONIC when V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC is set, at the
  // start of exposure (V4L2_BUF_FLAG_TSTAMP_SRC_SOE, e.g. uvcvideo) or when the last byte of the
  // frame arrived (V4L2_BUF_FLAG_TSTAMP_SRC_EOF, the common case) (section "Buffers", "Buffer
  // Flags"). The common time base is the wall clock, so the stamp moves by the current offset
  // between the two clocks, then to mid-exposure. For EOF this assumes the exposure ended when
  // the frame was complete: the sensor readout and transfer time is unknown to V4L2 and is not
  // subtracted, so EOF stamps are late by that time (a constant per mode, left to the clock
  // offset calibration). Without a monotonic stamp (UNKNOWN, COPY) the arrival time stands in
  // for the end of the frame.
  TimeNs mid_exposure_stamp(const V4l2DequeuedBuffer& buffer, TimeNs arrival_ns, double exposure_us) {
    const TimeNs half_exposure_ns = static_cast<TimeNs>(std::llround(exposure_us * 500.0));
    if ((buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) != V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
      return arrival_ns - half_exposure_ns;
    }
    const TimeNs wall_ns = timeval_to_ns(buffer.timestamp) + monotonic_to_wall_ns();
    if ((buffer.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE) {
      return wall_ns + half_exposure_ns;
    }
    return wall_ns - half_exposure_ns;
  }

  TimeNs monotonic_to_wall_ns() {
    const TimeNs before = monotonic_now_ns();
    if (offset_sampled_ns_ != 0 && before - offset_sampled_ns_ < kClockOffsetRefreshNs)
      return wall_offset_ns_;
    // The wall reading is bracketed by two monotonic ones; their midpoint is its monotonic time.
    const TimeNs wall = wall_now_ns();
    const TimeNs after = monotonic_now_ns();
    wall_offset_ns_ = wall - (before + (after - before) / 2);
    offset_sampled_ns_ = after;
    return wall_offset_ns_;
  }

  void note_waiting() {
    if (wanted_timeout_ms() <= 0) return;
    const TimeNs now = monotonic_now_ns();
    const double waited_ms = static_cast<double>(now - waiting_since_ns_) / kNsPerMillisecond;
    if (waited_ms < wanted_timeout_ms()) return;
    waiting_since_ns_ = now;
    // The error before the count: a reader that sees the timeout counted sees its error too (a
    // test read the error between the two and found it empty, once in a fresh check).
    set_last_error("no frame within " + format_number(wanted_timeout_ms()) + " ms");
    count("timeout");
  }

  double wanted_timeout_ms() const { return wanted_.timeout_ms; }

  // A failed dequeue or requeue ends this stream; next() reopens the device after the interval.
  void fail_stream(const V4l2Status& status) {
    const bool vanished = status.error == ENODEV || status.error == EIO;
    count(vanished ? "disconnect" : "stream_error");
    set_last_error(status.message);
    drop_session();
    reconnect_due_ns_ = monotonic_now_ns() + reconnect_interval_ns();
  }

  TimeNs reconnect_interval_ns() const {
    return static_cast<TimeNs>(wanted_.reconnect_interval_ms * static_cast<double>(kNsPerMillisecond));
  }

  void drop_session() {
    Session old;
    {
      std::unique_lock device_lock(device_mutex_);
      old = std::move(session_);
      session_ = Session{};
    }
    close_session(old);
  }

  // Waits for the reconnection time (or a stop/restart), then tries once.
  void reopen() {
    {
      std::unique_lock lock(mutex_);
      while (!stopped_ && !restart_requested_) {
        const TimeNs remaining = reconnect_due_ns_ - monotonic_now_ns();
        if (remaining <= 0) break;
        wake_.wait_for(lock, std::chrono::nanoseconds(remaining));
      }
      if (stopped_ || restart_requested_) return;
    }
    try {
      Session session = open_session();
      {
        std::unique_lock device_lock(device_mutex_);
        session_ = std::move(session);
      }
      waiting_since_ns_ = monotonic_now_ns();
      count("reconnect");
    } catch (const std::exception& error) {
      set_last_error("reopening " + path_ + ": " + error.what());
      reconnect_due_ns_ = monotonic_now_ns() + reconnect_interval_ns();
    }
  }

  bool take_restart_request() {
    std::lock_guard lock(mutex_);
    if (!restart_requested_) return false;
    restart_requested_ = false;
    ++counters_["restart"];
    return true;
  }

  bool stopped() const {
    std::lock_guard lock(mutex_);
    return stopped_;
  }

  void count(const std::string& reason, std::uint64_t amount = 1) {
    std::lock_guard lock(mutex_);
    counters_[reason] += amount;
  }

  void set_last_error(std::string message) {
    std::lock_guard lock(mutex_);
    last_error_ = std::move(message);
  }

  const std::string path_;
  const V4l2DeviceFactory open_device_;
  SourceInfo info_;
  const std::int64_t max_frames_;

  // Guards which device session_ holds: the capture thread replaces it under a unique lock;
  // set_control()/control() from other threads use it under a shared lock.
  mutable std::shared_mutex device_mutex_;
  Session session_;

  // Capture-thread state.
  std::int64_t delivered_ = 0;
  std::int64_t sequence_base_ = 0;
  std::int64_t next_sequence_ = 0;
  TimeNs waiting_since_ns_ = 0;
  TimeNs reconnect_due_ns_ = 0;
  TimeNs wall_offset_ns_ = 0;
  TimeNs offset_sampled_ns_ = 0;
  std::string card_;
  std::string bus_info_;
  std::atomic<double> exposure_us_{0};  // 0 = unknown; written by set_control() on any thread

  mutable std::mutex mutex_;  // guards the members below and wanted_'s control fields
  std::condition_variable wake_;
  SourceSettings wanted_;  // the settings, updated by set_control() so a reconnection restores them
  bool stopped_ = false;
  bool restart_requested_ = false;
  SourceCounters counters_;
  std::string last_error_;
};

}  // namespace

std::unique_ptr<FrameSource> make_v4l2_source(std::string path, V4l2DeviceFactory open_device,
                                              const SourceOptions& options) {
  const std::string spec = "v4l2:" + path;
  try {
    return std::make_unique<V4l2Source>(std::move(path), std::move(open_device), options);
  } catch (const std::exception& error) {
    throw std::runtime_error(spec + ": " + error.what());
  }
}

std::unique_ptr<FrameSource> open_v4l2_source(const std::string& target, const SourceOptions& options) {
  return make_v4l2_source(target, open_real_v4l2_device, options);
}

}  // namespace panoptes::camera
