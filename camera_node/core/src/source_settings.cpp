// SPDX-License-Identifier: Apache-2.0
// SourceSettings from the `source:` section of a camera_node config, and control names.
#include <string>

#include "panoptes/camera/sources.h"
#include "panoptes/config.h"

namespace panoptes::camera {

const char* control_name(Control control) {
  switch (control) {
    case Control::kExposureUs:
      return "exposure";
    case Control::kGainDb:
      return "gain";
    case Control::kFrameRateHz:
      return "frame rate";
  }
  return "control";
}

SourceSettings SourceSettings::from_yaml(const YamlReader& reader) {
  reader.expect_only({"exposure_us", "gain_db", "frame_rate_hz", "roi", "pixel_format", "buffers",
                      "timeout_ms", "reconnect_interval_ms"});
  SourceSettings settings;
  const auto non_negative = [&reader](const std::string& key, double fallback, double maximum) {
    const double value = reader.get_double(key, fallback);
    if (!(value >= 0 && value <= maximum)) {
      reader.fail(key, "must be between 0 and " + std::to_string(maximum));
    }
    return value;
  };
  settings.exposure_us = non_negative("exposure_us", settings.exposure_us, 10e6);
  settings.gain_db = non_negative("gain_db", settings.gain_db, 100);
  settings.frame_rate_hz = non_negative("frame_rate_hz", settings.frame_rate_hz, 100000);
  settings.timeout_ms = non_negative("timeout_ms", settings.timeout_ms, 600000);
  settings.reconnect_interval_ms =
      non_negative("reconnect_interval_ms", settings.reconnect_interval_ms, 600000);
  const long long buffers = reader.get_int("buffers", settings.buffers);
  if (buffers < 2 || buffers > 256) reader.fail("buffers", "must be between 2 and 256");
  settings.buffers = static_cast<int>(buffers);
  settings.pixel_format = reader.get_string("pixel_format", settings.pixel_format);
  if (reader.has("roi")) {
    const auto roi = reader.get_doubles("roi", 4);
    for (double value : roi) {
      if (!(value >= 0 && value <= 65535) || value != static_cast<int>(value)) {
        reader.fail("roi", "expected [x, y, width, height] in whole pixels");
      }
    }
    settings.roi_x = static_cast<int>(roi[0]);
    settings.roi_y = static_cast<int>(roi[1]);
    settings.roi_width = static_cast<int>(roi[2]);
    settings.roi_height = static_cast<int>(roi[3]);
  }
  return settings;
}

}  // namespace panoptes::camera
