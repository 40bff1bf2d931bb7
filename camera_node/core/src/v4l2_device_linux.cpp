// SPDX-License-Identifier: Apache-2.0
// V4l2Device on a real device node: ioctl, mmap and poll on a file descriptor.
#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>
#include <utility>

#include "v4l2_device.h"

namespace panoptes::camera {
namespace {

std::string errno_text(int error) {
  return std::system_category().message(error);
}

V4l2Status failure(const char* operation, int error) {
  return {error, std::string(operation) + ": " + errno_text(error)};
}

// The kernel fills fixed-size, NUL-padded byte arrays (struct v4l2_capability).
template <std::size_t N>
std::string from_fixed(const __u8 (&bytes)[N]) {
  std::size_t length = 0;
  while (length < N && bytes[length] != 0) ++length;
  return std::string(reinterpret_cast<const char*>(bytes), length);
}

class LinuxV4l2Device final : public V4l2Device {
 public:
  explicit LinuxV4l2Device(int fd) : fd_(fd) {}
  LinuxV4l2Device(const LinuxV4l2Device&) = delete;
  LinuxV4l2Device& operator=(const LinuxV4l2Device&) = delete;
  ~LinuxV4l2Device() override { ::close(fd_); }

  V4l2Status query_capabilities(V4l2Capabilities* capabilities) override {
    v4l2_capability cap{};
    if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) return failure("VIDIOC_QUERYCAP", errno);
    capabilities->driver = from_fixed(cap.driver);
    capabilities->card = from_fixed(cap.card);
    capabilities->bus_info = from_fixed(cap.bus_info);
    // device_caps describe this node; capabilities the whole physical device (section "ioctl
    // VIDIOC_QUERYCAP").
    capabilities->capabilities =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
    return V4l2Status::success();
  }

  V4l2Status enumerate_formats(std::vector<std::uint32_t>* fourccs) override {
    fourccs->clear();
    for (__u32 index = 0;; ++index) {
      v4l2_fmtdesc description{};
      description.index = index;
      description.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (xioctl(VIDIOC_ENUM_FMT, &description) < 0) {
        // EINVAL past the last index is how the enumeration ends.
        if (errno == EINVAL && index > 0) return V4l2Status::success();
        return failure("VIDIOC_ENUM_FMT", errno);
      }
      fourccs->push_back(description.pixelformat);
    }
  }

  V4l2Status get_format(V4l2Format* format) override {
    v4l2_format raw{};
    raw.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_G_FMT, &raw) < 0) return failure("VIDIOC_G_FMT", errno);
    from_raw(raw, format);
    return V4l2Status::success();
  }

  V4l2Status try_format(V4l2Format* format) override {
    return apply_format(VIDIOC_TRY_FMT, "VIDIOC_TRY_FMT", format);
  }
  V4l2Status set_format(V4l2Format* format) override {
    return apply_format(VIDIOC_S_FMT, "VIDIOC_S_FMT", format);
  }

  V4l2Status request_buffers(int* count) override {
    v4l2_requestbuffers request{};
    request.count = static_cast<__u32>(*count);
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_REQBUFS, &request) < 0) return failure("VIDIOC_REQBUFS", errno);
    *count = static_cast<int>(request.count);
    return V4l2Status::success();
  }

  V4l2Status query_buffer(int index, V4l2BufferInfo* info) override {
    v4l2_buffer buffer{};
    buffer.index = static_cast<__u32>(index);
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_QUERYBUF, &buffer) < 0) return failure("VIDIOC_QUERYBUF", errno);
    info->length = buffer.length;
    info->offset = buffer.m.offset;
    return V4l2Status::success();
  }

  V4l2Status map_buffer(const V4l2BufferInfo& info, const std::uint8_t** data) override {
    // Read-only: capture buffers are only read, and a stray write into a buffer the driver owns
    // would corrupt a later frame silently.
    void* address = ::mmap(nullptr, info.length, PROT_READ, MAP_SHARED, fd_, static_cast<off_t>(info.offset));
    if (address == MAP_FAILED) return failure("mmap", errno);
    *data = static_cast<const std::uint8_t*>(address);
    return V4l2Status::success();
  }

  void unmap_buffer(const std::uint8_t* data, std::uint32_t length) override {
    ::munmap(const_cast<std::uint8_t*>(data), length);
  }

  V4l2Status queue_buffer(int index) override {
    v4l2_buffer buffer{};
    buffer.index = static_cast<__u32>(index);
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_QBUF, &buffer) < 0) return failure("VIDIOC_QBUF", errno);
    return V4l2Status::success();
  }

  V4l2Status dequeue_buffer(int timeout_ms, V4l2DequeuedBuffer* result) override {
    pollfd descriptor{fd_, POLLIN, 0};
    const int ready = ::poll(&descriptor, 1, timeout_ms);
    if (ready < 0) {
      if (errno == EINTR) return {ETIMEDOUT, "poll: interrupted"};
      return failure("poll", errno);
    }
    if (ready == 0) return {ETIMEDOUT, "no frame within " + std::to_string(timeout_ms) + " ms"};
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    // After POLLERR the DQBUF errno tells why (ENODEV once the device is unplugged); a buffer that
    // is still ready is taken normally.
    if (xioctl(VIDIOC_DQBUF, &buffer) < 0) {
      const int error = errno;
      if (error == EAGAIN) {
        if ((descriptor.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) return {EIO, "poll: device error"};
        return {ETIMEDOUT, "VIDIOC_DQBUF: no buffer ready"};
      }
      return failure("VIDIOC_DQBUF", error);
    }
    result->index = static_cast<int>(buffer.index);
    result->bytesused = buffer.bytesused;
    result->sequence = buffer.sequence;
    result->timestamp = buffer.timestamp;
    result->flags = buffer.flags;
    return V4l2Status::success();
  }

  V4l2Status stream_on() override {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_STREAMON, &type) < 0) return failure("VIDIOC_STREAMON", errno);
    return V4l2Status::success();
  }

  V4l2Status stream_off() override {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_STREAMOFF, &type) < 0) return failure("VIDIOC_STREAMOFF", errno);
    return V4l2Status::success();
  }

  V4l2Status query_control(std::uint32_t id, V4l2ControlRange* range) override {
    v4l2_queryctrl query{};
    query.id = id;
    if (xioctl(VIDIOC_QUERYCTRL, &query) < 0) return failure("VIDIOC_QUERYCTRL", errno);
    // A disabled control is as good as absent (section "ioctls VIDIOC_QUERYCTRL ...").
    if ((query.flags & V4L2_CTRL_FLAG_DISABLED) != 0) return {EINVAL, "VIDIOC_QUERYCTRL: control disabled"};
    range->minimum = query.minimum;
    range->maximum = query.maximum;
    range->step = query.step;
    range->default_value = query.default_value;
    range->flags = query.flags;
    return V4l2Status::success();
  }

  V4l2Status get_control(std::uint32_t id, std::int32_t* value) override {
    v4l2_control control{};
    control.id = id;
    if (xioctl(VIDIOC_G_CTRL, &control) < 0) return failure("VIDIOC_G_CTRL", errno);
    *value = control.value;
    return V4l2Status::success();
  }

  V4l2Status set_control(std::uint32_t id, std::int32_t value) override {
    v4l2_control control{};
    control.id = id;
    control.value = value;
    if (xioctl(VIDIOC_S_CTRL, &control) < 0) return failure("VIDIOC_S_CTRL", errno);
    return V4l2Status::success();
  }

  V4l2Status get_frame_interval(V4l2FrameInterval* interval, bool* supported) override {
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_G_PARM, &parm) < 0) {
      *supported = false;
      return failure("VIDIOC_G_PARM", errno);
    }
    *supported = (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) != 0;
    interval->numerator = parm.parm.capture.timeperframe.numerator;
    interval->denominator = parm.parm.capture.timeperframe.denominator;
    return V4l2Status::success();
  }

  V4l2Status set_frame_interval(V4l2FrameInterval* interval) override {
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = interval->numerator;
    parm.parm.capture.timeperframe.denominator = interval->denominator;
    if (xioctl(VIDIOC_S_PARM, &parm) < 0) return failure("VIDIOC_S_PARM", errno);
    interval->numerator = parm.parm.capture.timeperframe.numerator;
    interval->denominator = parm.parm.capture.timeperframe.denominator;
    return V4l2Status::success();
  }

 private:
  int xioctl(unsigned long request, void* argument) {
    int result;
    do {
      result = ::ioctl(fd_, request, argument);
    } while (result < 0 && errno == EINTR);
    return result;
  }

  static void from_raw(const v4l2_format& raw, V4l2Format* format) {
    format->fourcc = raw.fmt.pix.pixelformat;
    format->width = static_cast<int>(raw.fmt.pix.width);
    format->height = static_cast<int>(raw.fmt.pix.height);
    format->bytesperline = static_cast<int>(raw.fmt.pix.bytesperline);
    format->sizeimage = raw.fmt.pix.sizeimage;
  }

  V4l2Status apply_format(unsigned long request, const char* name, V4l2Format* format) {
    v4l2_format raw{};
    raw.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    raw.fmt.pix.pixelformat = format->fourcc;
    raw.fmt.pix.width = static_cast<__u32>(format->width);
    raw.fmt.pix.height = static_cast<__u32>(format->height);
    raw.fmt.pix.field = V4L2_FIELD_NONE;
    // bytesperline 0 asks the driver for its natural (minimum) stride.
    raw.fmt.pix.bytesperline = 0;
    if (xioctl(request, &raw) < 0) return failure(name, errno);
    from_raw(raw, format);
    return V4l2Status::success();
  }

  int fd_;
};

}  // namespace

std::unique_ptr<V4l2Device> open_real_v4l2_device(const std::string& path) {
  // Non-blocking: waiting is done in poll() with a timeout, so a stop request is never stuck
  // behind a DQBUF that sleeps until the next frame (section "Streaming I/O (Memory Mapping)").
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    throw V4l2OpenError(error, "cannot open: " + errno_text(error));
  }
  return std::make_unique<LinuxV4l2Device>(fd);
}

std::string fourcc_to_string(std::uint32_t fourcc) {
  std::string text;
  for (int shift = 0; shift < 32; shift += 8) {
    const char c = static_cast<char>((fourcc >> shift) & 0xff);
    text += (c >= 0x20 && c < 0x7f) ? c : '?';
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace panoptes::camera
