// SPDX-License-Identifier: Apache-2.0
// "aravis:<ip or device id>": a GenICam camera over GigE Vision or USB3 Vision through Aravis 0.8.
//
// Opening by IP address talks to that address only (GVCP unicast): no device-list update, hence
// no discovery broadcast. Any other target is an Aravis device id ("<vendor>-<serial>", a USB3
// Vision id, "Fake_1"), which Aravis resolves by enumerating every enabled interface; for GigE
// Vision that broadcasts a discovery packet on every network interface. "Fake_<n>" (Aravis's
// in-process fake camera) enables only the Fake interface, so it enumerates nothing real.
//
// Threads: next() runs on the capture thread and alone touches the stream; set_control(),
// control(), counters() and restart() may come from other threads. Aravis camera objects are not
// thread-safe, so every feature access holds camera_mutex_; the connection is only replaced on the
// capture thread, under that mutex.
#include "aravis_source.h"

#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "device_clock.h"
#include "genicam_timing.h"

namespace panoptes::camera {
namespace {

// Blocking waits are cut into slices this long so stop() ends them promptly.
constexpr guint64 kPopSliceUs = 20'000;
constexpr auto kReconnectWaitSlice = std::chrono::milliseconds(20);
// This many frame timeouts in a row and the camera is treated as gone: closed and reopened.
constexpr int kTimeoutsBeforeDisconnect = 5;
// How often a PTP-timed camera's lock is checked while streaming.
constexpr auto kPtpCheckInterval = std::chrono::seconds(1);

// Failures inside this file carry the reason only; open_aravis_source() and the reconnect loop
// prefix the spec.
class AravisError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string take_message(GError*& error) {
  std::string message = error != nullptr && error->message != nullptr ? error->message : "unknown error";
  g_clear_error(&error);
  return message;
}

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

struct MonoFormat {
  const char* name;
  ArvPixelFormat format;
  int bits;
};
// Unpacked monochrome formats: one pixel per byte, or per little-endian 16-bit word.
constexpr MonoFormat kMonoFormats[] = {
    {"Mono8", ARV_PIXEL_FORMAT_MONO_8, 8},    {"Mono10", ARV_PIXEL_FORMAT_MONO_10, 10},
    {"Mono12", ARV_PIXEL_FORMAT_MONO_12, 12}, {"Mono14", ARV_PIXEL_FORMAT_MONO_14, 14},
    {"Mono16", ARV_PIXEL_FORMAT_MONO_16, 16},
};

const MonoFormat* find_format(ArvPixelFormat format) {
  for (const MonoFormat& mono : kMonoFormats) {
    if (mono.format == format) return &mono;
  }
  return nullptr;
}

const MonoFormat* find_format(const std::string& name) {
  // The V4L2 names the config also accepts for the same layouts.
  const std::string genicam = name == "GREY" ? "Mono8" : name == "Y16" ? "Mono16" : name;
  for (const MonoFormat& mono : kMonoFormats) {
    if (genicam == mono.name) return &mono;
  }
  return nullptr;
}

std::string supported_format_names() {
  std::string names;
  for (const MonoFormat& mono : kMonoFormats) names += (names.empty() ? "" : ", ") + std::string(mono.name);
  return names;
}

bool is_ipv4_literal(const std::string& target) {
  in_addr address{};
  return inet_pton(AF_INET, target.c_str(), &address) == 1;
}

// The local address the kernel would use to reach `device_ip`: a connected UDP socket learns its
// source address from the routing table without sending anything.
std::string local_address_towards(const std::string& device_ip) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw AravisError(std::string("cannot create a UDP socket: ") + std::strerror(errno));
  sockaddr_in remote{};
  remote.sin_family = AF_INET;
  remote.sin_port = htons(3956);  // GVCP
  inet_pton(AF_INET, device_ip.c_str(), &remote.sin_addr);
  sockaddr_in local{};
  socklen_t length = sizeof(local);
  const bool ok = connect(fd, reinterpret_cast<const sockaddr*>(&remote), sizeof(remote)) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length) == 0;
  const int error = errno;
  close(fd);
  if (!ok) throw AravisError("no route to " + device_ip + " (" + std::strerror(error) + ")");
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &local.sin_addr, text, sizeof(text));
  return text;
}

void on_control_lost(ArvDevice* /*device*/, gpointer flag) {
  static_cast<std::atomic<bool>*>(flag)->store(true);
}

// One open camera with its stream and buffer pool; closing it is destroying it.
class Connection {
 public:
  Connection(const std::string& target, const SourceSettings& settings) {
    open_camera(target);
    ArvDevice* device = arv_camera_get_device(camera_);
    // Emitted from Aravis's heartbeat thread when the camera stops answering.
    control_lost_handler_ =
        g_signal_connect(device, "control-lost", G_CALLBACK(on_control_lost), &control_lost_);
    if (arv_camera_is_gv_device(camera_) && target.starts_with("127.")) {
      // The packet-socket receiver would also see loopback's outgoing copy of every packet.
      arv_camera_gv_set_stream_options(camera_, ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
    }
    apply_settings(settings);
    start_stream(settings.buffers);
  }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  ~Connection() {
    if (camera_ == nullptr) return;
    // A lost camera would make every command wait for its GVCP timeouts; skip the goodbye.
    if (stream_ != nullptr && !control_lost_.load()) {
      GError* error = nullptr;
      arv_camera_stop_acquisition(camera_, &error);
      g_clear_error(&error);
    }
    if (control_lost_handler_ != 0)
      g_signal_handler_disconnect(arv_camera_get_device(camera_), control_lost_handler_);
    if (stream_ != nullptr) g_object_unref(stream_);
    // The last reference to the device: its heartbeat thread is joined here, so no control-lost
    // emission can outlive control_lost_.
    g_object_unref(camera_);
  }

  ArvCamera* camera() const { return camera_; }
  ArvStream* stream() const { return stream_; }
  bool control_lost() const { return control_lost_.load(); }
  const MonoFormat& format() const { return *format_; }

  // Stream statistics by counter name: "stream_" + Aravis's info name without its "n_". Totals
  // that are not problems (completed buffers, transferred bytes) are left out.
  void read_stream_statistics(SourceCounters& out) const {
    const guint count = arv_stream_get_n_infos(stream_);
    for (guint id = 0; id < count; ++id) {
      if (arv_stream_get_info_type(stream_, id) != G_TYPE_UINT64) continue;
      std::string name = arv_stream_get_info_name(stream_, id);
      if (name == "n_completed_buffers" || name == "n_transferred_bytes") continue;
      if (name.starts_with("n_")) name.erase(0, 2);
      out["stream_" + name] = arv_stream_get_info_uint64(stream_, id);
    }
  }

  void fill_info(SourceInfo& info) const {
    GError* error = nullptr;
    const char* vendor = arv_camera_get_vendor_name(camera_, &error);
    g_clear_error(&error);
    const char* model = arv_camera_get_model_name(camera_, &error);
    g_clear_error(&error);
    const char* serial = arv_camera_get_device_serial_number(camera_, &error);
    g_clear_error(&error);
    info.backend = "aravis";
    info.model = std::string(vendor != nullptr ? vendor : "") +
                 (vendor != nullptr && model != nullptr ? " " : "") + (model != nullptr ? model : "");
    info.serial = serial != nullptr ? serial : "";
    gint x = 0, y = 0, width = 0, height = 0;
    arv_camera_get_region(camera_, &x, &y, &width, &height, &error);
    g_clear_error(&error);
    info.width = width;
    info.height = height;
    info.offset_x = x;
    info.offset_y = y;
    info.bits = format_->bits;
    info.ptp_timed = timing_.ptp_timed;
    info.timing_features = timing_.features;
    if (arv_camera_is_frame_rate_available(camera_, nullptr)) {
      const double rate = arv_camera_get_frame_rate(camera_, &error);
      if (error == nullptr && std::isfinite(rate)) info.nominal_rate_hz = rate;
      g_clear_error(&error);
    }
  }

 private:
  void open_camera(const std::string& target) {
    GError* error = nullptr;
    if (is_ipv4_literal(target)) {
      const std::string local = local_address_towards(target);
      GInetAddress* interface_address = g_inet_address_new_from_string(local.c_str());
      GInetAddress* device_address = g_inet_address_new_from_string(target.c_str());
      ArvDevice* device = arv_gv_device_new(interface_address, device_address, &error);
      g_object_unref(interface_address);
      g_object_unref(device_address);
      if (device == nullptr) {
        throw AravisError("no GigE Vision camera answered at " + target + " from " + local + " (" +
                          take_message(error) + ")");
      }
      camera_ = arv_camera_new_with_device(device, &error);
      g_object_unref(device);  // the camera holds its own reference
      if (camera_ == nullptr) {
        throw AravisError("the GigE Vision device at " + target + " is not a usable GenICam camera (" +
                          take_message(error) + ")");
      }
      return;
    }
    if (target.starts_with("Fake_")) {
      // Aravis's in-process fake camera (disabled by default in Aravis): reachable without
      // enumerating, hence without broadcasting on, any real interface.
      arv_disable_interface("GigEVision");
      arv_disable_interface("USB3Vision");
      arv_enable_interface("Fake");
    }
    // Enumerates the interfaces (GigE Vision discovery broadcasts): see the file comment.
    camera_ = arv_camera_new(target.c_str(), &error);
    if (camera_ == nullptr) {
      throw AravisError("no camera with device id '" + target + "' (" + take_message(error) +
                        "); a GigE Vision camera can also be given by its IPv4 address");
    }
  }

  // A GenICam feature write that Aravis did not refuse may still have been clamped or rounded by
  // the device: read it back.
  void check_read_back(const char* feature, double wanted, double actual, const char* unit) const {
    if (std::abs(actual - wanted) > std::max(1e-6, 0.01 * std::abs(wanted)) + 0.5) {
      throw AravisError(std::string(feature) + " " + format_number(wanted) + unit +
                        " was not accepted (the camera has " + format_number(actual) + unit + ")");
    }
  }

  static void check_bounds(const char* feature, double value, double minimum, double maximum,
                           const char* unit) {
    if (!(minimum <= maximum)) return;  // the device publishes no usable bounds
    if (value < minimum || value > maximum) {
      throw AravisError(std::string(feature) + " " + format_number(value) + unit + " is out of range [" +
                        format_number(minimum) + ", " + format_number(maximum) + "]" + unit);
    }
  }

  void apply_pixel_format(const std::string& wanted) {
    GError* error = nullptr;
    if (!wanted.empty()) {
      const MonoFormat* format = find_format(wanted);
      if (format == nullptr) {
        const bool packed = wanted.find("Packed") != std::string::npos || wanted.ends_with("p");
        throw AravisError("pixel format " + wanted + " is not supported" +
                          (packed ? " (packed formats are not unpacked here)" : "") + "; use one of " +
                          supported_format_names());
      }
      guint count = 0;
      const char** offered = arv_camera_dup_available_pixel_formats_as_strings(camera_, &count, &error);
      if (offered == nullptr)
        throw AravisError("cannot list the camera's pixel formats (" + take_message(error) + ")");
      std::string offered_names;
      bool found = false;
      for (guint i = 0; i < count; ++i) {
        found = found || std::string(offered[i]) == format->name;
        offered_names += (i == 0 ? "" : ", ") + std::string(offered[i]);
      }
      g_free(offered);
      if (!found) {
        throw AravisError("pixel format " + std::string(format->name) +
                          " is not offered by the camera (it offers " + offered_names + ")");
      }
      arv_camera_set_pixel_format(camera_, format->format, &error);
      if (error != nullptr) {
        throw AravisError("cannot set pixel format " + std::string(format->name) + " (" +
                          take_message(error) + ")");
      }
    }
    const ArvPixelFormat current = arv_camera_get_pixel_format(camera_, &error);
    if (error != nullptr) throw AravisError("cannot read the pixel format (" + take_message(error) + ")");
    format_ = find_format(current);
    if (format_ == nullptr) {
      const char* name = arv_camera_get_pixel_format_as_string(camera_, nullptr);
      throw AravisError("the camera's pixel format " + std::string(name != nullptr ? name : "?") +
                        " is not supported; set source.pixel_format to one of " + supported_format_names());
    }
  }

  void apply_region(const SourceSettings& settings) {
    GError* error = nullptr;
    gint sensor_width = 0, sensor_height = 0;
    arv_camera_get_sensor_size(camera_, &sensor_width, &sensor_height, &error);
    if (error != nullptr) {
      // No SensorWidth/Height: the largest image the camera allows stands in for the sensor.
      g_clear_error(&error);
      gint minimum = 0;
      arv_camera_get_width_bounds(camera_, &minimum, &sensor_width, &error);
      g_clear_error(&error);
      arv_camera_get_height_bounds(camera_, &minimum, &sensor_height, &error);
      g_clear_error(&error);
    }
    const int x = settings.roi_x, y = settings.roi_y;
    const int width = settings.roi_width > 0 ? settings.roi_width : sensor_width - x;
    const int height = settings.roi_height > 0 ? settings.roi_height : sensor_height - y;
    const std::string roi = "roi [" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                            std::to_string(width) + ", " + std::to_string(height) + "]";
    if (width <= 0 || height <= 0 || x + width > sensor_width || y + height > sensor_height) {
      throw AravisError(roi + " does not fit the " + std::to_string(sensor_width) + "x" +
                        std::to_string(sensor_height) + " sensor");
    }
    if ((x != 0 || y != 0) && !arv_camera_is_region_offset_available(camera_, nullptr)) {
      throw AravisError(roi + ": the camera has no region offset (OffsetX/OffsetY)");
    }
    const auto check_increment = [&roi](const char* what, int value, gint increment) {
      if (increment > 1 && value % increment != 0) {
        throw AravisError(roi + ": " + what + " must be a multiple of " + std::to_string(increment));
      }
    };
    check_increment("width", width, arv_camera_get_width_increment(camera_, nullptr));
    check_increment("height", height, arv_camera_get_height_increment(camera_, nullptr));
    if (x != 0) check_increment("x", x, arv_camera_get_x_offset_increment(camera_, nullptr));
    if (y != 0) check_increment("y", y, arv_camera_get_y_offset_increment(camera_, nullptr));
    arv_camera_set_region(camera_, x, y, width, height, &error);
    if (error != nullptr) throw AravisError(roi + " was refused (" + take_message(error) + ")");
    gint got_x = 0, got_y = 0, got_width = 0, got_height = 0;
    arv_camera_get_region(camera_, &got_x, &got_y, &got_width, &got_height, &error);
    if (error != nullptr) throw AravisError("cannot read the region back (" + take_message(error) + ")");
    if (got_x != x || got_y != y || got_width != width || got_height != height) {
      throw AravisError(roi + " was not accepted (the camera has [" + std::to_string(got_x) + ", " +
                        std::to_string(got_y) + ", " + std::to_string(got_width) + ", " +
                        std::to_string(got_height) + "])");
    }
  }

  void apply_settings(const SourceSettings& settings) {
    apply_pixel_format(settings.pixel_format);
    apply_region(settings);
    if (settings.exposure_us > 0) set_exposure(settings.exposure_us);
    if (settings.gain_db > 0) set_gain(settings.gain_db);
    if (settings.frame_rate_hz > 0) set_frame_rate(settings.frame_rate_hz);
    // After the frame rate: Aravis turns triggers off when it sets a frame rate.
    try {
      timing_ = apply_genicam_timing(camera_, settings);
    } catch (const GenicamTimingError& error) {
      throw AravisError(error.what());
    }
  }

  void start_stream(int buffers) {
    GError* error = nullptr;
    const guint payload = arv_camera_get_payload(camera_, &error);
    if (error != nullptr || payload == 0) {
      throw AravisError("cannot read the payload size (" +
                        (error ? take_message(error) : std::string("0 bytes")) + ")");
    }
    stream_ = arv_camera_create_stream(camera_, nullptr, nullptr, &error);
    if (stream_ == nullptr) throw AravisError("cannot open the image stream (" + take_message(error) + ")");
    if (ARV_IS_GV_STREAM(stream_)) {
      // Aravis sizes the UDP receive buffer to one frame; a receiving thread descheduled for a
      // moment then loses packets of the next. Room for the whole pool rides out such stalls
      // (the kernel caps it at net.core.rmem_max).
      const auto socket_buffer = static_cast<gint>(std::clamp<std::uint64_t>(
          std::uint64_t{payload} * static_cast<std::uint64_t>(buffers), 1u << 20, 1u << 28));
      g_object_set(stream_, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED, "socket-buffer-size",
                   socket_buffer, nullptr);
    }
    for (int i = 0; i < buffers; ++i) arv_stream_push_buffer(stream_, arv_buffer_new_allocate(payload));
    arv_camera_set_acquisition_mode(camera_, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
    if (error != nullptr)
      throw AravisError("cannot set continuous acquisition (" + take_message(error) + ")");
    arv_camera_start_acquisition(camera_, &error);
    if (error != nullptr) throw AravisError("cannot start acquisition (" + take_message(error) + ")");
  }

 public:
  // The three controls; each throws AravisError naming the feature and, when out of bounds, the
  // range. Callers hold the camera mutex.
  void set_exposure(double exposure_us) {
    GError* error = nullptr;
    if (!arv_camera_is_exposure_time_available(camera_, nullptr))
      throw AravisError("exposure is not available");
    double minimum = 0, maximum = 0;
    arv_camera_get_exposure_time_bounds(camera_, &minimum, &maximum, &error);
    if (error != nullptr) throw AravisError("cannot read the exposure bounds (" + take_message(error) + ")");
    check_bounds("exposure", exposure_us, minimum, maximum, " us");
    if (arv_camera_is_exposure_auto_available(camera_, nullptr)) {
      arv_camera_set_exposure_time_auto(camera_, ARV_AUTO_OFF, &error);
      if (error != nullptr)
        throw AravisError("cannot switch auto exposure off (" + take_message(error) + ")");
    }
    arv_camera_set_exposure_time(camera_, exposure_us, &error);
    if (error != nullptr) throw AravisError("cannot set exposure (" + take_message(error) + ")");
    check_read_back("exposure", exposure_us, exposure(), " us");
  }
  void set_gain(double gain) {
    GError* error = nullptr;
    if (!arv_camera_is_gain_available(camera_, nullptr)) throw AravisError("gain is not available");
    double minimum = 0, maximum = 0;
    arv_camera_get_gain_bounds(camera_, &minimum, &maximum, &error);
    if (error != nullptr) throw AravisError("cannot read the gain bounds (" + take_message(error) + ")");
    check_bounds("gain", gain, minimum, maximum, "");
    if (arv_camera_is_gain_auto_available(camera_, nullptr)) {
      arv_camera_set_gain_auto(camera_, ARV_AUTO_OFF, &error);
      if (error != nullptr) throw AravisError("cannot switch auto gain off (" + take_message(error) + ")");
    }
    arv_camera_set_gain(camera_, gain, &error);
    if (error != nullptr) throw AravisError("cannot set gain (" + take_message(error) + ")");
    check_read_back("gain", gain, this->gain(), "");
  }
  void set_frame_rate(double rate_hz) {
    GError* error = nullptr;
    if (!arv_camera_is_frame_rate_available(camera_, nullptr))
      throw AravisError("frame rate is not available");
    double minimum = 0, maximum = 0;
    arv_camera_get_frame_rate_bounds(camera_, &minimum, &maximum, &error);
    if (error != nullptr)
      throw AravisError("cannot read the frame rate bounds (" + take_message(error) + ")");
    check_bounds("frame rate", rate_hz, minimum, maximum, " Hz");
    arv_camera_set_frame_rate(camera_, rate_hz, &error);
    if (error != nullptr) throw AravisError("cannot set frame rate (" + take_message(error) + ")");
    check_read_back("frame rate", rate_hz, frame_rate(), " Hz");
  }
  std::string ptp_status() const {
    try {
      return read_ptp_status(camera_);
    } catch (const GenicamTimingError& error) {
      throw AravisError(error.what());
    }
  }
  double exposure() const { return read_double(arv_camera_get_exposure_time, "exposure"); }
  double gain() const { return read_double(arv_camera_get_gain, "gain"); }
  double frame_rate() const { return read_double(arv_camera_get_frame_rate, "frame rate"); }

 private:
  double read_double(double (*getter)(ArvCamera*, GError**), const char* feature) const {
    GError* error = nullptr;
    const double value = getter(camera_, &error);
    if (error != nullptr)
      throw AravisError(std::string("cannot read ") + feature + " (" + take_message(error) + ")");
    return value;
  }

  ArvCamera* camera_ = nullptr;
  ArvStream* stream_ = nullptr;
  gulong control_lost_handler_ = 0;
  std::atomic<bool> control_lost_{false};
  const MonoFormat* format_ = nullptr;
  TimingApplied timing_;
};

const char* status_counter(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return "";
    case ARV_BUFFER_STATUS_CLEARED:
      return "incomplete_cleared";
    case ARV_BUFFER_STATUS_TIMEOUT:
      return "incomplete_timeout";
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return "incomplete_missing_packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return "incomplete_wrong_packet_id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return "incomplete_size_mismatch";
    case ARV_BUFFER_STATUS_FILLING:
      return "incomplete_filling";
    case ARV_BUFFER_STATUS_ABORTED:
      return "incomplete_aborted";
    default:
      return "incomplete_unknown";
  }
}

class AravisSource final : public FrameSource {
 public:
  AravisSource(const std::string& target, const SourceOptions& options)
      : target_(target),
        spec_("aravis:" + target),
        settings_(options.settings),
        max_frames_(options.max_frames),
        ptp_utc_offset_ns_(static_cast<TimeNs>(std::llround(options.settings.ptp_utc_offset_s * 1e9))) {
    try {
      connection_ = std::make_unique<Connection>(target_, settings_);
      connection_->fill_info(info_);
      exposure_us_.store(connection_->exposure());
    } catch (const AravisError& error) {
      throw std::runtime_error(spec_ + ": " + error.what());
    }
    info_.camera_id = !options.camera_id.empty() ? options.camera_id
                      : !info_.serial.empty()    ? info_.serial
                                                 : target_;
  }

  ~AravisSource() override {
    stop();
    if (opener_.joinable()) opener_.join();
    close_connection();
  }

  const SourceInfo& info() const override { return info_; }

  std::optional<CapturedFrame> next() override {
    while (!stop_.load()) {
      if (max_frames_ >= 0 && delivered_ >= max_frames_) return std::nullopt;
      if (restart_requested_.exchange(false)) {
        count("restart");
        close_connection();
        next_attempt_ = std::chrono::steady_clock::now();
      }
      if (connection_ == nullptr) {
        reconnect_step();
        continue;
      }
      if (connection_->control_lost()) {
        lose_connection("the camera stopped answering (control lost)");
        continue;
      }
      ArvBuffer* buffer = arv_stream_timeout_pop_buffer(connection_->stream(), kPopSliceUs);
      if (buffer == nullptr) {
        handle_pop_timeout();
        continue;
      }
      waited_us_ = 0;
      timeouts_in_a_row_ = 0;
      auto frame = take_frame(buffer);
      arv_stream_push_buffer(connection_->stream(), buffer);
      update_stream_statistics();
      if (settings_.ptp) check_ptp_lock();
      if (frame) {
        ++delivered_;
        return frame;
      }
    }
    return std::nullopt;
  }

  void stop() override {
    {
      std::lock_guard lock(opener_mutex_);
      stop_.store(true);
    }
    opener_done_.notify_all();
  }

  std::string set_control(Control control, double value) override {
    std::lock_guard lock(camera_mutex_);
    if (connection_ == nullptr) return spec_ + ": the camera is not connected (reconnecting)";
    try {
      switch (control) {
        case Control::kExposureUs:
          connection_->set_exposure(value);
          exposure_us_.store(connection_->exposure());
          break;
        case Control::kGainDb:
          connection_->set_gain(value);
          break;
        case Control::kFrameRateHz:
          // Aravis would switch the trigger off to set a rate.
          if (!settings_.trigger.empty())
            return spec_ + ": frame rate is set by the hardware trigger (trigger " + settings_.trigger + ")";
          connection_->set_frame_rate(value);
          break;
      }
    } catch (const AravisError& error) {
      return spec_ + ": " + error.what();
    }
    return {};
  }

  std::optional<double> control(Control control) const override {
    std::lock_guard lock(camera_mutex_);
    if (connection_ == nullptr) return std::nullopt;
    try {
      switch (control) {
        case Control::kExposureUs:
          return connection_->exposure();
        case Control::kGainDb:
          return connection_->gain();
        case Control::kFrameRateHz:
          return connection_->frame_rate();
      }
    } catch (const AravisError&) {
    }
    return std::nullopt;
  }

  void restart() override { restart_requested_.store(true); }

  SourceCounters counters() const override {
    std::lock_guard lock(counters_mutex_);
    SourceCounters all = events_;
    for (const auto& [name, value] : closed_streams_) all[name] += value;
    for (const auto& [name, value] : current_stream_) all[name] += value;
    return all;
  }

  std::string last_error() const override {
    std::lock_guard lock(counters_mutex_);
    return last_error_;
  }

 private:
  void count(const std::string& name, std::uint64_t amount = 1) {
    std::lock_guard lock(counters_mutex_);
    events_[name] += amount;
  }

  void note_error(const std::string& message) {
    std::lock_guard lock(counters_mutex_);
    last_error_ = message;
  }

  void update_stream_statistics() {
    SourceCounters statistics;
    connection_->read_stream_statistics(statistics);
    std::lock_guard lock(counters_mutex_);
    current_stream_ = std::move(statistics);
  }

  // Once a second: a camera that lost its PTP lock stamps frames off the common time base. They are
  // still delivered (the lock usually returns), counted, and the status named in last_error.
  void check_ptp_lock() {
    const auto now = std::chrono::steady_clock::now();
    if (now < next_ptp_check_) return;
    next_ptp_check_ = now + kPtpCheckInterval;
    std::string problem;
    try {
      std::lock_guard lock(camera_mutex_);
      const std::string status = connection_->ptp_status();
      if (status.empty() || ptp_locked(status)) return;
      problem = "PTP status " + status + ", not Slave or Master: stamps may be off the common time base";
    } catch (const AravisError& error) {
      problem = error.what();
    }
    count("ptp_not_locked");
    note_error(spec_ + ": " + problem);
  }

  void handle_pop_timeout() {
    waited_us_ += kPopSliceUs;
    if (static_cast<double>(waited_us_) < settings_.timeout_ms * 1000.0) return;
    waited_us_ = 0;
    count("timeout");
    update_stream_statistics();
    if (++timeouts_in_a_row_ >= kTimeoutsBeforeDisconnect) {
      lose_connection("no frame for " + std::to_string(kTimeoutsBeforeDisconnect) + " timeouts of " +
                      format_number(settings_.timeout_ms) + " ms");
    }
  }

  void lose_connection(const std::string& why) {
    count("disconnect");
    note_error(spec_ + ": " + why);
    close_connection();
    next_attempt_ =
        std::chrono::steady_clock::now() +
        std::chrono::microseconds(static_cast<std::int64_t>(settings_.reconnect_interval_ms * 1000));
  }

  void close_connection() {
    std::unique_ptr<Connection> closing;
    {
      std::lock_guard lock(camera_mutex_);
      closing = std::move(connection_);
    }
    if (closing == nullptr) return;
    {
      // This stream's statistics stay in the totals.
      std::lock_guard lock(counters_mutex_);
      for (const auto& [name, value] : current_stream_) closed_streams_[name] += value;
      current_stream_.clear();
    }
    closing.reset();
    waited_us_ = 0;
    timeouts_in_a_row_ = 0;
    have_frame_id_ = false;
    clock_.reset();
  }

  // Opening blocks for seconds when nobody answers (GVCP retries), so it runs on its own thread
  // and next() keeps waking up to notice stop().
  void reconnect_step() {
    std::unique_lock lock(opener_mutex_);
    if (opener_finished_) {
      opener_finished_ = false;
      lock.unlock();
      opener_.join();
      lock.lock();
      if (opened_ != nullptr) {
        std::unique_ptr<Connection> opened = std::move(opened_);
        lock.unlock();
        {
          std::lock_guard camera_lock(camera_mutex_);
          connection_ = std::move(opened);
          exposure_us_.store(connection_->exposure());
        }
        count("reconnect");
        return;
      }
      count("reconnect_failed");
      note_error(spec_ + ": " + open_error_);
      next_attempt_ =
          std::chrono::steady_clock::now() +
          std::chrono::microseconds(static_cast<std::int64_t>(settings_.reconnect_interval_ms * 1000));
    }
    if (!opener_.joinable() && std::chrono::steady_clock::now() >= next_attempt_) {
      opener_ = std::thread([this] {
        std::unique_ptr<Connection> opened;
        std::string error;
        try {
          opened = std::make_unique<Connection>(target_, settings_);
        } catch (const std::exception& failure) {
          error = failure.what();
        }
        {
          std::lock_guard done_lock(opener_mutex_);
          opened_ = std::move(opened);
          open_error_ = error;
          opener_finished_ = true;
        }
        opener_done_.notify_all();
      });
    }
    opener_done_.wait_for(lock, kReconnectWaitSlice, [this] { return opener_finished_ || stop_.load(); });
  }

  // Frame ids: 16-bit on GigE Vision 1.x (1..65535, 0 never used), 64-bit on GEV 2 and USB3
  // Vision. The sequence keeps counting across wraps and reconnections, and a frame's sequence
  // always says which frame it is: a gap is frames skipped ("lost" when a newer one arrives first),
  // a duplicate or a frame completed late (an incomplete one timing out after its successor) keeps
  // its own, older number. A large step back means the camera restarted its counter.
  std::int64_t sequence_of(guint64 frame_id) {
    constexpr std::int64_t kReorderWindow = 1024;
    if (!have_frame_id_) {
      have_frame_id_ = true;
      last_frame_id_ = frame_id;
      sequence_ = sequence_ < 0 ? static_cast<std::int64_t>(frame_id) : sequence_ + 1;
      return sequence_;
    }
    auto delta = static_cast<std::int64_t>(frame_id - last_frame_id_);
    if (last_frame_id_ <= 0xFFFF && frame_id <= 0xFFFF) {
      if (delta < -32768) delta += 0xFFFF;
      if (delta > 32768) delta -= 0xFFFF;
    }
    if (delta > 0) {
      if (delta > 1) count("lost", static_cast<std::uint64_t>(delta - 1));
      last_frame_id_ = frame_id;
      sequence_ += delta;
      return sequence_;
    }
    if (delta >= -kReorderWindow) {
      count(delta == 0 ? "duplicate" : "out_of_order");
      return sequence_ + delta;
    }
    last_frame_id_ = frame_id;
    return ++sequence_;
  }

  std::optional<CapturedFrame> take_frame(ArvBuffer* buffer) {
    const TimeNs received_ns = wall_now_ns();
    const std::int64_t sequence = sequence_of(arv_buffer_get_frame_id(buffer));
    const ArvBufferStatus status = arv_buffer_get_status(buffer);
    if (status != ARV_BUFFER_STATUS_SUCCESS) {
      count("incomplete");
      count(status_counter(status));
      return std::nullopt;
    }
    const ArvPixelFormat pixel_format = arv_buffer_get_image_pixel_format(buffer);
    const MonoFormat* format = find_format(pixel_format);
    const int width = arv_buffer_get_image_width(buffer);
    const int height = arv_buffer_get_image_height(buffer);
    gint x_padding = 0, y_padding = 0;
    arv_buffer_get_image_padding(buffer, &x_padding, &y_padding);
    std::size_t size = 0;
    const auto* data = static_cast<const std::uint8_t*>(arv_buffer_get_image_data(buffer, &size));
    if (format == nullptr || width <= 0 || height <= 0 || data == nullptr) {
      count("decode_error");
      note_error(spec_ + ": a frame came with pixel format 0x" + format_hex(pixel_format) + " and size " +
                 std::to_string(width) + "x" + std::to_string(height));
      return std::nullopt;
    }
    const std::size_t bytes_per_pixel = format->bits > 8 ? 2 : 1;
    const std::size_t row_bytes = static_cast<std::size_t>(width) * bytes_per_pixel;
    const std::size_t stride = row_bytes + static_cast<std::size_t>(std::max(0, x_padding));
    if (size < stride * static_cast<std::size_t>(height - 1) + row_bytes) {
      count("decode_error");
      note_error(spec_ + ": a " + std::to_string(width) + "x" + std::to_string(height) + " " + format->name +
                 " frame had only " + std::to_string(size) + " bytes");
      return std::nullopt;
    }

    CapturedFrame frame;
    frame.image = Image(width, height, format->bits);
    for (int y = 0; y < height; ++y) {
      const std::uint8_t* row = data + static_cast<std::size_t>(y) * stride;
      if (bytes_per_pixel == 1) {
        std::memcpy(frame.image.row8(y), row, row_bytes);
      } else {
        // GenICam multi-byte pixels are little-endian whatever the host is.
        std::uint16_t* out = frame.image.row16(y);
        for (int x = 0; x < width; ++x) {
          const std::size_t low_byte = 2 * static_cast<std::size_t>(x);
          out[x] = static_cast<std::uint16_t>(row[low_byte] | (row[low_byte + 1] << 8));
        }
      }
    }
    frame.sequence = sequence;
    frame.exposure_us = exposure_us_.load();
    // The stream thread's wall-clock time of the frame's arrival, if it recorded one: the moment
    // we pop it may be later by however long it waited in the queue.
    const guint64 system_ns = arv_buffer_get_system_timestamp(buffer);
    frame.arrival_ns = system_ns != 0 ? static_cast<TimeNs>(system_ns) : received_ns;
    const auto half_exposure_ns = static_cast<TimeNs>(std::llround(frame.exposure_us * 500.0));
    frame.stamp_ns = capture_stamp(arv_buffer_get_timestamp(buffer), frame.arrival_ns, half_exposure_ns);
    return frame;
  }

  // Mid-exposure capture time from the buffer's device stamp (0 = none).
  TimeNs capture_stamp(guint64 device_ns, TimeNs arrival_ns, TimeNs half_exposure_ns) {
    if (device_ns == 0) {
      if (settings_.ptp) count("ptp_missing_stamp");
      // No device clock: the frame was read out by its arrival; its exposure ended before that.
      return arrival_ns - half_exposure_ns;
    }
    // SFNC: the timestamp is latched at frame (exposure) start on most cameras, so the middle of
    // the exposure is half an exposure later.
    if (settings_.ptp) {
      // PTP time is TAI, already common to every PTP-timed camera and host; the common time base
      // is UTC (docs/camera_node.md, "PTP and hardware triggers").
      return static_cast<TimeNs>(device_ns) - ptp_utc_offset_ns_ + half_exposure_ns;
    }
    const std::size_t resets = clock_.resets();
    const TimeNs stamp_ns = clock_.add(static_cast<TimeNs>(device_ns), arrival_ns) + half_exposure_ns;
    if (clock_.resets() != resets) count("clock_reset");
    return stamp_ns;
  }

  static std::string format_hex(std::uint32_t value) {
    char text[16];
    std::snprintf(text, sizeof(text), "%08x", value);
    return text;
  }

  const std::string target_;
  const std::string spec_;
  const SourceSettings settings_;
  const std::int64_t max_frames_;
  const TimeNs ptp_utc_offset_ns_ = 0;
  SourceInfo info_;

  mutable std::mutex camera_mutex_;  // guards connection_ against feature access from other threads
  std::unique_ptr<Connection> connection_;
  std::atomic<double> exposure_us_{0};

  mutable std::mutex counters_mutex_;
  SourceCounters events_;
  SourceCounters closed_streams_;
  SourceCounters current_stream_;
  std::string last_error_;

  std::atomic<bool> stop_{false};
  std::atomic<bool> restart_requested_{false};

  // Reconnection (capture thread, with the opener thread reporting through opener_mutex_).
  std::mutex opener_mutex_;
  std::condition_variable opener_done_;
  std::thread opener_;
  bool opener_finished_ = false;
  std::unique_ptr<Connection> opened_;
  std::string open_error_;
  std::chrono::steady_clock::time_point next_attempt_{};

  // Capture-thread state.
  std::int64_t delivered_ = 0;
  guint64 waited_us_ = 0;
  int timeouts_in_a_row_ = 0;
  bool have_frame_id_ = false;
  guint64 last_frame_id_ = 0;
  std::int64_t sequence_ = -1;
  DeviceClockMapper clock_;
  std::chrono::steady_clock::time_point next_ptp_check_{};
};

}  // namespace

std::unique_ptr<FrameSource> open_aravis_source(const std::string& target, const SourceOptions& options) {
  return std::make_unique<AravisSource>(target, options);
}

}  // namespace panoptes::camera
