// SPDX-License-Identifier: Apache-2.0
// Frame sources for camera_node, chosen by --source:
//   images:<dir or glob>, sim:<scene>#<camera>, aravis:<ip or device id>, v4l2:/dev/videoN,
//   features:<file.jsonl>.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/image.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes {
class YamlReader;
}

namespace panoptes::camera {

struct CapturedFrame {
  Image image;
  std::int64_t sequence = 0;
  TimeNs stamp_ns = 0;    // middle of the exposure on the common (wall) time base; 0 = unknown
  TimeNs arrival_ns = 0;  // when the frame reached the node (wall clock)
  double exposure_us = 0;
  // Sources that deliver features instead of pixels (recorded replay, feature-level simulation)
  // fill this; the node then skips detection and publishes these blobs as they are.
  std::optional<std::vector<Blob>> blobs;
};

struct SourceInfo {
  std::string camera_id;
  std::string backend;  // "images", "sim", "aravis", "v4l2", "features"
  std::string model;
  std::string serial;
  int width = 0;
  int height = 0;
  // Position of the frame's top-left pixel on the sensor (a region of interest): blob coordinates
  // are shifted by it so they stay in the full-sensor pixels the calibration uses.
  int offset_x = 0;
  int offset_y = 0;
  int bits = 8;  // significant bits per pixel of the frames it delivers
  double nominal_rate_hz = 0;
  std::optional<CameraCalibration> calibration;  // known intrinsics/pose (the simulator knows them)
  // The camera stamps frames with its PTP (IEEE 1588) clock, already on the common time base: the
  // node's software clock synchronisation is skipped for it (docs/camera_node.md, "PTP").
  bool ptp_timed = false;
  // GenICam timing features as read back from the camera after they were set (PTP, trigger,
  // strobe), in the order written: ("TriggerMode", "On"), ...
  std::vector<std::pair<std::string, std::string>> timing_features;
};

// Camera settings from the node's config (`source:` section); 0 / empty = leave the device's own.
struct SourceSettings {
  double exposure_us = 0;
  double gain_db = 0;
  double frame_rate_hz = 0;
  int roi_x = 0, roi_y = 0, roi_width = 0, roi_height = 0;  // width/height 0 = full sensor
  std::string pixel_format;                                 // e.g. Mono8, Mono12, Mono16, GREY, Y16
  int buffers = 8;                                          // driver/stream buffer pool size
  double timeout_ms = 1000;             // a frame not arriving within this counts as a timeout
  double reconnect_interval_ms = 1000;  // between attempts to reopen a vanished device

  // GenICam timing (aravis only; docs/camera_node.md, "PTP and hardware triggers").
  bool ptp = false;              // enable PtpEnable/GevIEEE1588; the camera's stamps become capture times
  double ptp_timeout_s = 30;     // wait this long for PtpStatus Slave or Master when opening
  double ptp_utc_offset_s = 37;  // TAI − UTC: PTP stamps are TAI, the common time base is UTC
  std::string trigger;           // "" = free-running; else the TriggerSource (Line0, Line1, Software, ...)
  std::string trigger_activation = "RisingEdge";  // RisingEdge | FallingEdge
  std::string strobe;  // "" = none; else the output line (LineSelector) driven by ExposureActive

  // Reads the `source:` section (keys above); unknown keys and out-of-range values throw
  // ConfigError naming the file and key.
  static SourceSettings from_yaml(const YamlReader& reader);
};

// Settings that exclude each other (trigger with frame_rate_hz, an activation without a trigger):
// calls `fail(key, why)` for the first found. Shared by the config file and the command line.
void check_timing(const SourceSettings& settings,
                  const std::function<void(const std::string& key, const std::string& why)>& fail);

enum class Control { kExposureUs, kGainDb, kFrameRateHz };
const char* control_name(Control control);

// Counters a source keeps about frames it could not deliver or problems it recovered from, by
// reason: "incomplete", "lost", "timeout", "decode_error", "disconnect", "reconnect", ...
using SourceCounters = std::map<std::string, std::uint64_t>;

// next() runs on the capture thread; every other member may be called from another thread
// concurrently with it (implementations synchronise).
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const SourceInfo& info() const = 0;
  // Blocks until the next frame (paced sources wait for its time); nullopt at the end of the
  // stream or after stop(). A live device that fails mid-stream is not the end of the stream:
  // the source counts the failure, retries, and keeps blocking until it delivers again.
  virtual std::optional<CapturedFrame> next() = 0;
  virtual void stop() {}

  // Sets a camera control; returns "" on success, otherwise why not ("not supported by ...",
  // "out of range [a, b]").
  virtual std::string set_control(Control control, double /*value*/) {
    return std::string(control_name(control)) + " is not supported by the " + info().backend + " source";
  }
  // Current value of a control, if the source has it.
  virtual std::optional<double> control(Control /*control*/) const { return std::nullopt; }
  // Closes and reopens the device (or rewinds a file); next() continues afterwards.
  virtual void restart() {}
  virtual SourceCounters counters() const { return {}; }
  // The most recent error the source recovered from ("" if none).
  virtual std::string last_error() const { return {}; }
};

struct SourceOptions {
  std::string camera_id;    // overrides the id the source would choose
  TimeNs sim_epoch_ns = 0;  // sim: wall time of scene time 0 (0 = now, rounded up to 1 s)
  // features: a file that will hold sim_epoch_ns (decimal); the replay waits for it to appear
  // (a start gate: nodes start, synchronise their clocks, then one file starts them all).
  std::string sim_epoch_file;
  bool paced = true;             // sim/features: real time; false = as fast as possible
  double rate_scale = 1.0;       // features: replay speed (2 = twice the recorded pace)
  std::int64_t max_frames = -1;  // stop after this many frames (-1 = the source's own end)
  SourceSettings settings;       // aravis/v4l2 camera settings
};

// Parses the --source spec and opens it. Throws std::runtime_error (ConfigError for scene files)
// with a message naming what is wrong.
std::unique_ptr<FrameSource> open_source(const std::string& spec, const SourceOptions& options);

}  // namespace panoptes::camera
