// SPDX-License-Identifier: Apache-2.0
// SourceSettings from the `source:` section of a camera_node config, and control names.
#include <functional>
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

namespace {

// `ptp`, `trigger`, `trigger_activation`, `strobe`, `ptp_timeout_s`, `ptp_utc_offset_s`.
void read_timing(const YamlReader& reader, SourceSettings& settings) {
  // YAML 1.1 reads a bare on/off as a boolean; either spelling is accepted.
  const std::string ptp = reader.get_string("ptp", "off");
  if (ptp != "on" && ptp != "off" && ptp != "true" && ptp != "false")
    reader.fail("ptp", "expected on or off");
  settings.ptp = ptp == "on" || ptp == "true";
  settings.ptp_timeout_s = reader.get_double("ptp_timeout_s", settings.ptp_timeout_s);
  if (!(settings.ptp_timeout_s >= 0 && settings.ptp_timeout_s <= 600))
    reader.fail("ptp_timeout_s", "must be between 0 and 600");
  settings.ptp_utc_offset_s = reader.get_double("ptp_utc_offset_s", settings.ptp_utc_offset_s);
  if (!(settings.ptp_utc_offset_s >= 0 && settings.ptp_utc_offset_s <= 1000) ||
      settings.ptp_utc_offset_s != static_cast<int>(settings.ptp_utc_offset_s)) {
    reader.fail("ptp_utc_offset_s", "expected whole seconds between 0 and 1000 (TAI - UTC, 37 since 2017)");
  }
  const std::string trigger = reader.get_string("trigger", "off");
  settings.trigger = trigger == "off" || trigger == "false" ? "" : trigger;
  settings.trigger_activation = reader.get_string("trigger_activation", settings.trigger_activation);
  if (settings.trigger_activation != "RisingEdge" && settings.trigger_activation != "FallingEdge")
    reader.fail("trigger_activation", "expected RisingEdge or FallingEdge");
  const std::string strobe = reader.get_string("strobe", "off");
  settings.strobe = strobe == "off" || strobe == "false" ? "" : strobe;
  check_timing(settings,
               [&reader](const std::string& key, const std::string& why) { reader.fail(key, why); });
}

}  // namespace

void check_timing(const SourceSettings& settings,
                  const std::function<void(const std::string& key, const std::string& why)>& fail) {
  if (!settings.trigger.empty() && settings.frame_rate_hz > 0) {
    fail("frame_rate_hz",
         "a triggered camera runs at its trigger's rate; leave frame_rate_hz out with trigger");
  }
  if (settings.trigger.empty() && settings.trigger_activation != "RisingEdge")
    fail("trigger_activation", "needs a trigger source (trigger: Line0, ...)");
}

SourceSettings SourceSettings::from_yaml(const YamlReader& reader) {
  reader.expect_only({"exposure_us", "gain_db", "frame_rate_hz", "roi", "pixel_format", "buffers",
                      "timeout_ms", "reconnect_interval_ms", "ptp", "ptp_timeout_s", "ptp_utc_offset_s",
                      "trigger", "trigger_activation", "strobe"});
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
  read_timing(reader, settings);
  return settings;
}

}  // namespace panoptes::camera
