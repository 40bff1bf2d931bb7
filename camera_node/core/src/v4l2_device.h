// SPDX-License-Identifier: Apache-2.0
// The Video4Linux2 operations the v4l2 frame source needs, one virtual call per ioctl (or
// mmap/poll), so the source can be tested against an in-memory device: these machines have no
// media support in the kernel (engineering.md). Section names refer to the Linux Media
// Infrastructure userspace API, part I "Video for Linux API" (docs.kernel.org/userspace-api/media/v4l).
// Private to panoptes_camera and its tests.
#pragma once

#include <linux/videodev2.h>
#include <sys/time.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace panoptes::camera {

// errno-style outcome of one device operation: error 0 = success; otherwise `message` says which
// operation failed and why ("VIDIOC_S_FMT: Invalid argument").
struct V4l2Status {
  int error = 0;
  std::string message;

  bool ok() const { return error == 0; }
  static V4l2Status success() { return {}; }
};

// Thrown by a device factory when the device cannot be opened; what() is e.g.
// "cannot open: No such file or directory".
class V4l2OpenError : public std::runtime_error {
 public:
  V4l2OpenError(int error, const std::string& message) : std::runtime_error(message), error_(error) {}
  int error() const { return error_; }

 private:
  int error_;
};

// VIDIOC_QUERYCAP (section "Querying Capabilities"); `capabilities` holds the device_caps of
// this node when the driver reports them, else the physical device's.
struct V4l2Capabilities {
  std::string driver;
  std::string card;
  std::string bus_info;
  std::uint32_t capabilities = 0;  // V4L2_CAP_*
};

// The single-planar pixel format of a capture stream (struct v4l2_pix_format, section "Image
// Formats"). bytesperline may exceed width * bytes per pixel: the rows are padded.
struct V4l2Format {
  std::uint32_t fourcc = 0;
  int width = 0;
  int height = 0;
  int bytesperline = 0;         // 0 for compressed formats
  std::uint32_t sizeimage = 0;  // bytes a buffer must hold
};

// One mmap buffer as VIDIOC_QUERYBUF describes it (section "Streaming I/O (Memory Mapping)").
struct V4l2BufferInfo {
  std::uint32_t length = 0;
  std::uint32_t offset = 0;  // the mmap offset of this buffer
};

// A buffer handed back by VIDIOC_DQBUF (section "Buffers", struct v4l2_buffer).
struct V4l2DequeuedBuffer {
  int index = 0;
  std::uint32_t bytesused = 0;
  std::uint32_t sequence = 0;
  timeval timestamp{};      // clock and sampling point given by the V4L2_BUF_FLAG_TIMESTAMP_* flags
  std::uint32_t flags = 0;  // V4L2_BUF_FLAG_*
};

// VIDIOC_QUERYCTRL (section "User Controls" / "Camera Control Reference").
struct V4l2ControlRange {
  std::int32_t minimum = 0;
  std::int32_t maximum = 0;
  std::int32_t step = 1;
  std::int32_t default_value = 0;
  std::uint32_t flags = 0;  // V4L2_CTRL_FLAG_*
};

// A time per frame as a fraction of seconds (struct v4l2_fract in v4l2_captureparm).
struct V4l2FrameInterval {
  std::uint32_t numerator = 0;
  std::uint32_t denominator = 0;
};

// An open capture device node. Control operations (query/get/set_control, frame interval) may be
// called from another thread while dequeue_buffer() waits: the kernel serialises ioctls on one
// file descriptor, and fakes must do the same. Everything else is called from one thread.
// Closing (the destructor) releases the mappings and the file descriptor.
class V4l2Device {
 public:
  virtual ~V4l2Device() = default;

  virtual V4l2Status query_capabilities(V4l2Capabilities* capabilities) = 0;
  // VIDIOC_ENUM_FMT over V4L2_BUF_TYPE_VIDEO_CAPTURE: the fourccs the device offers.
  virtual V4l2Status enumerate_formats(std::vector<std::uint32_t>* fourccs) = 0;
  // VIDIOC_G_FMT / VIDIOC_TRY_FMT / VIDIOC_S_FMT; try and set adjust `format` to what the driver
  // accepts (section "Data Formats": drivers adjust rather than fail).
  virtual V4l2Status get_format(V4l2Format* format) = 0;
  virtual V4l2Status try_format(V4l2Format* format) = 0;
  virtual V4l2Status set_format(V4l2Format* format) = 0;

  // VIDIOC_REQBUFS with V4L2_MEMORY_MMAP; `count` in: wanted, out: granted (0 frees all buffers).
  virtual V4l2Status request_buffers(int* count) = 0;
  virtual V4l2Status query_buffer(int index, V4l2BufferInfo* info) = 0;
  // mmap of a queried buffer (PROT_READ, MAP_SHARED); valid until unmap_buffer() or closing.
  virtual V4l2Status map_buffer(const V4l2BufferInfo& info, const std::uint8_t** data) = 0;
  virtual void unmap_buffer(const std::uint8_t* data, std::uint32_t length) = 0;

  virtual V4l2Status queue_buffer(int index) = 0;
  // Waits up to timeout_ms for a filled buffer (poll, then VIDIOC_DQBUF). ETIMEDOUT if none came;
  // ENODEV/EIO (or another errno) when the device failed or vanished.
  virtual V4l2Status dequeue_buffer(int timeout_ms, V4l2DequeuedBuffer* buffer) = 0;
  virtual V4l2Status stream_on() = 0;
  // VIDIOC_STREAMOFF also returns every queued buffer to the application (section
  // "ioctl VIDIOC_STREAMON, VIDIOC_STREAMOFF").
  virtual V4l2Status stream_off() = 0;

  // EINVAL from query_control: the device has no such control.
  virtual V4l2Status query_control(std::uint32_t id, V4l2ControlRange* range) = 0;
  virtual V4l2Status get_control(std::uint32_t id, std::int32_t* value) = 0;
  virtual V4l2Status set_control(std::uint32_t id, std::int32_t value) = 0;

  // VIDIOC_G_PARM / VIDIOC_S_PARM (section "ioctl VIDIOC_G_PARM, VIDIOC_S_PARM"). `supported` is
  // false when the driver lacks V4L2_CAP_TIMEPERFRAME; set adjusts `interval` to the one applied.
  virtual V4l2Status get_frame_interval(V4l2FrameInterval* interval, bool* supported) = 0;
  virtual V4l2Status set_frame_interval(V4l2FrameInterval* interval) = 0;
};

// Opens a device node (non-blocking, close-on-exec). Throws V4l2OpenError ("cannot open: <reason>").
std::unique_ptr<V4l2Device> open_real_v4l2_device(const std::string& path);

// "GREY", "Y16 ", "MJPG": the four characters of a fourcc, trailing spaces trimmed.
std::string fourcc_to_string(std::uint32_t fourcc);

}  // namespace panoptes::camera
