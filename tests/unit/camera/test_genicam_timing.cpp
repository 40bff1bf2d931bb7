// SPDX-License-Identifier: Apache-2.0
// PTP, hardware trigger and strobe configuration of the aravis source against Aravis's in-process
// fake camera ("Fake_1") given our own GenICam description with those features
// (tests/unit/camera/data/timing_camera.xml). The fake keeps every register it is written, so the
// features read back are what the camera holds; its buffers carry its clock's stamp (the host's
// UTC wall clock, to the microsecond), which stands in for PTP time. No network: only the Fake
// interface is enabled, and a test checks that no socket is opened.
#include <arv.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/camera/sources.h"
#include "panoptes/config.h"
#include "panoptes/time.h"

namespace panoptes::camera {
namespace {

namespace fs = std::filesystem;
using Features = std::vector<std::pair<std::string, std::string>>;

const std::string kTimingXml = std::string(PANOPTES_SOURCE_DIR) + "/tests/unit/camera/data/timing_camera.xml";

// Aravis reads the description when the camera is opened; "" (nullptr to Aravis) is its own fake's.
class GenicamFile {
 public:
  explicit GenicamFile(const std::string& path) {
    arv_set_fake_camera_genicam_filename(path.empty() ? nullptr : path.c_str());
  }
  ~GenicamFile() { arv_set_fake_camera_genicam_filename(nullptr); }
  GenicamFile(const GenicamFile&) = delete;
  GenicamFile& operator=(const GenicamFile&) = delete;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A variant of the timing camera: every `from` replaced by `to`, written to a temporary file.
std::string variant(const std::string& name, const std::vector<std::pair<std::string, std::string>>& edits) {
  std::string text = read_text(kTimingXml);
  for (const auto& [from, to] : edits) {
    std::size_t at = 0;
    std::size_t replaced = 0;
    while ((at = text.find(from, at)) != std::string::npos) {
      text.replace(at, from.size(), to);
      at += to.size();
      ++replaced;
    }
    EXPECT_GT(replaced, 0u) << "the description no longer contains " << from;
  }
  const fs::path path =
      fs::temp_directory_path() / ("panoptes_" + name + "_" + std::to_string(getpid()) + ".xml");
  std::ofstream(path) << text;
  return path.string();
}

SourceOptions small_options() {
  SourceOptions options;
  options.settings.roi_width = 32;
  options.settings.roi_height = 24;
  options.settings.buffers = 4;
  return options;
}

std::unique_ptr<FrameSource> open_with(const std::string& genicam, const SourceOptions& options) {
  const GenicamFile file(genicam);
  return open_source("aravis:Fake_1", options);
}

std::string open_error(const std::string& genicam, const SourceOptions& options) {
  try {
    open_with(genicam, options);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

int open_sockets() {
  int sockets = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    const fs::path target = fs::read_symlink(entry.path(), error);
    if (!error && target.string().starts_with("socket:")) ++sockets;
  }
  return sockets;
}

TEST(GenicamTiming, TriggerAndStrobeAreWrittenAndReadBack) {
  SourceOptions options = small_options();
  options.settings.trigger = "Line1";
  options.settings.trigger_activation = "FallingEdge";
  options.settings.strobe = "Line2";
  const auto source = open_with(kTimingXml, options);
  const Features expected = {{"TriggerSelector", "FrameStart"}, {"TriggerMode", "On"},
                             {"TriggerSource", "Line1"},        {"TriggerActivation", "FallingEdge"},
                             {"LineSelector", "Line2"},         {"LineMode", "Output"},
                             {"LineSource", "ExposureActive"}};
  EXPECT_EQ(source->info().timing_features, expected);
  EXPECT_FALSE(source->info().ptp_timed);
  // TriggerMode FrameStart is the fake's own trigger register: triggered, it still delivers
  // (at its trigger frequency, as an external trigger would).
  ASSERT_TRUE(source->next().has_value());
  // Setting a frame rate would switch the trigger off (Aravis clears triggers to set a rate).
  const std::string refused = source->set_control(Control::kFrameRateHz, 30);
  EXPECT_TRUE(contains(refused, "set by the hardware trigger (trigger Line1)")) << refused;
}

TEST(GenicamTiming, PtpStampsBecomeCaptureTimes) {
  SourceOptions options = small_options();
  options.settings.ptp = true;
  options.settings.ptp_timeout_s = 2;
  options.settings.ptp_utc_offset_s = 37;
  const auto source = open_with(kTimingXml, options);
  const Features expected = {{"PtpEnable", "true"}, {"PtpStatus", "Slave"}};
  EXPECT_EQ(source->info().timing_features, expected);
  EXPECT_TRUE(source->info().ptp_timed);
  EXPECT_EQ(source->counters().count("ptp_not_locked"), 0u);
  for (int i = 0; i < 3; ++i) {
    const auto frame = source->next();
    ASSERT_TRUE(frame.has_value());
    // The fake stamps a buffer's device time and its arrival with one reading of its clock, so
    // the capture time is exactly the device stamp − (TAI − UTC) + half the 10 ms exposure. The
    // software mapping of the device clock would put it 5 ms after the arrival instead.
    EXPECT_EQ(frame->stamp_ns, frame->arrival_ns - 37 * kNsPerSecond + 5 * kNsPerMillisecond);
  }
}

TEST(GenicamTiming, WithoutPtpTheDeviceClockIsMappedToTheHost) {
  const auto source = open_with(kTimingXml, small_options());
  EXPECT_FALSE(source->info().ptp_timed);
  EXPECT_TRUE(source->info().timing_features.empty());
  const auto frame = source->next();
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->stamp_ns, frame->arrival_ns + 5 * kNsPerMillisecond);
}

TEST(GenicamTiming, OlderGevIEEE1588NamesAreUsedWhenThatIsWhatTheCameraHas) {
  const std::string legacy = variant("gev1588", {{"PtpEnable", "GevIEEE1588"},
                                                 {"PtpStatus", "GevIEEE1588Status"},
                                                 {"PtpDataSetLatch", "GevIEEE1588DataSetLatch"}});
  SourceOptions options = small_options();
  options.settings.ptp = true;
  options.settings.ptp_timeout_s = 2;
  const auto source = open_with(legacy, options);
  fs::remove(legacy);
  const Features expected = {{"GevIEEE1588", "true"}, {"GevIEEE1588Status", "Slave"}};
  EXPECT_EQ(source->info().timing_features, expected);
  EXPECT_TRUE(source->info().ptp_timed);
}

TEST(GenicamTiming, APtpStatusThatNeverLocksIsAnErrorAfterTheTimeout) {
  // Enabled, the status goes to Listening (2) instead of Slave (4): no master answers.
  const std::string listening = variant("listening", {{"ENABLED ? 4 : 1", "ENABLED ? 2 : 1"}});
  SourceOptions options = small_options();
  options.settings.ptp = true;
  options.settings.ptp_timeout_s = 0.3;
  const std::string error = open_error(listening, options);
  fs::remove(listening);
  EXPECT_TRUE(contains(error, "aravis:Fake_1: ptp: PtpStatus is still Listening after 0.3 s")) << error;
}

TEST(GenicamTiming, ALockLostWhileStreamingIsCountedAndNamed) {
  // Slave until acquisition starts, Listening from then on.
  const std::string losing = variant("losing", {{"<Formula>ENABLED ? 4 : 1</Formula>",
                                                 "<pVariable Name=\"RUNNING\">AcquisitionRunning</pVariable>"
                                                 "<Formula>ENABLED ? (RUNNING ? 2 : 4) : 1</Formula>"}});
  SourceOptions options = small_options();
  options.settings.ptp = true;
  options.settings.ptp_timeout_s = 2;
  const auto source = open_with(losing, options);
  fs::remove(losing);
  ASSERT_TRUE(source->next().has_value()) << "frames still come";
  const SourceCounters counters = source->counters();
  ASSERT_EQ(counters.count("ptp_not_locked"), 1u);
  EXPECT_EQ(counters.at("ptp_not_locked"), 1u) << "checked once a second, the first at the first frame";
  EXPECT_TRUE(contains(source->last_error(), "aravis:Fake_1: PTP status Listening, not Slave or Master"))
      << source->last_error();
}

TEST(GenicamTiming, FeaturesTheCameraLacksAreNamed) {
  // Aravis's own fake camera description has triggers (rising edge only) but no PTP and no lines.
  SourceOptions options = small_options();
  options.settings.ptp = true;
  std::string error = open_error("", options);
  EXPECT_TRUE(contains(error, "aravis:Fake_1: ptp: the camera has neither PtpEnable nor GevIEEE1588"))
      << error;

  options = small_options();
  options.settings.strobe = "Line1";
  error = open_error("", options);
  EXPECT_TRUE(contains(error, "aravis:Fake_1: strobe Line1: the camera has no LineSelector feature"))
      << error;

  options = small_options();
  options.settings.trigger = "Line0";
  options.settings.trigger_activation = "FallingEdge";
  error = open_error("", options);
  EXPECT_TRUE(contains(
      error, "trigger Line0: TriggerActivation has no entry FallingEdge (the camera offers RisingEdge)"))
      << error;

  options = small_options();
  options.settings.trigger = "Line7";
  error = open_error(kTimingXml, options);
  EXPECT_TRUE(
      contains(error, "TriggerSource has no entry Line7 (the camera offers Line0, Software, Line1, Line2)"))
      << error;
}

TEST(GenicamTiming, AReadOnlyFeatureIsRefused) {
  const std::string fixed_lines =
      variant("read_only_line_mode",
              {{"<AccessMode>RW</AccessMode><!-- LineModeAccess -->", "<AccessMode>RO</AccessMode>"}});
  SourceOptions options = small_options();
  options.settings.strobe = "Line3";
  const std::string error = open_error(fixed_lines, options);
  fs::remove(fixed_lines);
  EXPECT_TRUE(contains(error, "aravis:Fake_1: strobe Line3: LineMode is read-only on this camera")) << error;
}

TEST(GenicamTiming, TheFakeCameraOpensNoSocket) {
  const int before = open_sockets();
  SourceOptions options = small_options();
  options.settings.ptp = true;
  options.settings.trigger = "Line0";
  options.settings.strobe = "Line1";
  const auto source = open_with(kTimingXml, options);
  ASSERT_TRUE(source->next().has_value());
  EXPECT_EQ(open_sockets(), before);
}

SourceSettings settings_of(const std::string& yaml) {
  return SourceSettings::from_yaml(YamlReader("camera.yaml", YAML::Load(yaml)));
}

std::string settings_error(const std::string& yaml) {
  try {
    settings_of(yaml);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "no error";
}

TEST(GenicamTimingSettings, DefaultsAndKeys) {
  const SourceSettings defaults = settings_of("{}");
  EXPECT_FALSE(defaults.ptp);
  EXPECT_DOUBLE_EQ(defaults.ptp_timeout_s, 30);
  EXPECT_DOUBLE_EQ(defaults.ptp_utc_offset_s, 37);
  EXPECT_EQ(defaults.trigger, "");
  EXPECT_EQ(defaults.trigger_activation, "RisingEdge");
  EXPECT_EQ(defaults.strobe, "");
  const SourceSettings set = settings_of(
      "ptp: on\nptp_timeout_s: 5\nptp_utc_offset_s: 0\ntrigger: Line1\ntrigger_activation: FallingEdge\n"
      "strobe: Line2");
  EXPECT_TRUE(set.ptp);
  EXPECT_DOUBLE_EQ(set.ptp_timeout_s, 5);
  EXPECT_DOUBLE_EQ(set.ptp_utc_offset_s, 0);
  EXPECT_EQ(set.trigger, "Line1");
  EXPECT_EQ(set.trigger_activation, "FallingEdge");
  EXPECT_EQ(set.strobe, "Line2");
  EXPECT_EQ(settings_of("trigger: off\nstrobe: off\nptp: off").trigger, "");
}

TEST(GenicamTimingSettings, BadValuesNameTheKey) {
  EXPECT_TRUE(contains(settings_error("ptp: sometimes"), "camera.yaml: ptp: expected on or off"));
  EXPECT_TRUE(contains(settings_error("ptp_utc_offset_s: 36.5"), "ptp_utc_offset_s: expected whole seconds"));
  EXPECT_TRUE(contains(settings_error("ptp_timeout_s: -1"), "ptp_timeout_s: must be between 0 and 600"));
  EXPECT_TRUE(contains(settings_error("trigger: Line0\ntrigger_activation: Both"),
                       "trigger_activation: expected RisingEdge or FallingEdge"));
  EXPECT_TRUE(
      contains(settings_error("trigger_activation: FallingEdge"), "trigger_activation: needs a trigger"));
  EXPECT_TRUE(contains(settings_error("trigger: Line0\nframe_rate_hz: 100"),
                       "frame_rate_hz: a triggered camera runs at its trigger's rate"));
}

TEST(GenicamTimingSettings, OnlyAravisSourcesTakeThem) {
  SourceOptions options;
  options.settings.ptp = true;
  try {
    open_source("images:/nonexistent", options);
    ADD_FAILURE() << "opened";
  } catch (const std::runtime_error& error) {
    EXPECT_TRUE(contains(error.what(), "only aravis: sources have them")) << error.what();
  }
}

}  // namespace
}  // namespace panoptes::camera
