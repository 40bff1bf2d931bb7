// SPDX-License-Identifier: Apache-2.0
#include "genicam_timing.h"

#include <chrono>
#include <sstream>
#include <string>
#include <thread>

namespace panoptes::camera {
namespace {

constexpr auto kPtpPollInterval = std::chrono::milliseconds(100);

std::string take_message(GError*& error) {
  std::string message = error != nullptr && error->message != nullptr ? error->message : "unknown error";
  g_clear_error(&error);
  return message;
}

// Writes features for one option (`purpose`, e.g. "trigger Line1"), checking each exists and is
// writable, reading it back, and recording what the camera kept.
class FeatureWriter {
 public:
  FeatureWriter(ArvCamera* camera, std::string purpose, TimingApplied& applied)
      : camera_(camera), purpose_(std::move(purpose)), applied_(applied) {}

  bool has(const char* feature) const {
    GError* error = nullptr;
    const bool available = arv_camera_is_feature_available(camera_, feature, &error);
    g_clear_error(&error);
    return available;
  }

  // Aravis writes read-only registers unless the camera's access-check policy says otherwise, so
  // the node's access mode is checked here.
  bool read_only(const char* feature) const {
    ArvGcNode* node = arv_device_get_feature(arv_camera_get_device(camera_), feature);
    return ARV_IS_GC_FEATURE_NODE(node) &&
           arv_gc_feature_node_get_actual_access_mode(ARV_GC_FEATURE_NODE(node)) == ARV_GC_ACCESS_MODE_RO;
  }

  void require_writable(const char* feature) const {
    if (!has(feature)) fail("the camera has no " + std::string(feature) + " feature");
    if (read_only(feature)) fail(std::string(feature) + " is read-only on this camera");
  }

  std::string read_string(const char* feature) const {
    GError* error = nullptr;
    const char* value = arv_camera_get_string(camera_, feature, &error);
    if (error != nullptr) fail("cannot read " + std::string(feature) + " (" + take_message(error) + ")");
    return value != nullptr ? value : "";
  }

  void write_enumeration(const char* feature, const std::string& value) {
    require_writable(feature);
    GError* error = nullptr;
    guint count = 0;
    const char** entries = arv_camera_dup_available_enumerations_as_strings(camera_, feature, &count, &error);
    if (entries == nullptr)
      fail("cannot list the entries of " + std::string(feature) + " (" + take_message(error) + ")");
    bool offered = false;
    std::string offered_names;
    for (guint i = 0; i < count; ++i) {
      offered = offered || value == entries[i];
      offered_names += (i == 0 ? "" : ", ") + std::string(entries[i]);
    }
    g_free(entries);
    if (!offered)
      fail(std::string(feature) + " has no entry " + value + " (the camera offers " + offered_names + ")");
    arv_camera_set_string(camera_, feature, value.c_str(), &error);
    if (error != nullptr)
      fail("cannot set " + std::string(feature) + " to " + value + " (" + take_message(error) + ")");
    keep(feature, value, read_string(feature));
  }

  void write_boolean(const char* feature, bool value) {
    require_writable(feature);
    GError* error = nullptr;
    arv_camera_set_boolean(camera_, feature, value ? TRUE : FALSE, &error);
    if (error != nullptr) fail("cannot set " + std::string(feature) + " (" + take_message(error) + ")");
    const bool actual = arv_camera_get_boolean(camera_, feature, &error) != FALSE;
    if (error != nullptr) fail("cannot read " + std::string(feature) + " back (" + take_message(error) + ")");
    keep(feature, value ? "true" : "false", actual ? "true" : "false");
  }

  void execute(const char* feature) const {
    GError* error = nullptr;
    arv_camera_execute_command(camera_, feature, &error);
    if (error != nullptr) fail("cannot execute " + std::string(feature) + " (" + take_message(error) + ")");
  }

  void record(const char* feature, const std::string& value) {
    applied_.features.emplace_back(feature, value);
  }

  [[noreturn]] void fail(const std::string& why) const { throw GenicamTimingError(purpose_ + ": " + why); }

 private:
  void keep(const char* feature, const std::string& wanted, const std::string& actual) {
    if (actual != wanted)
      fail(std::string(feature) + " " + wanted + " was not kept (the camera has " + actual + ")");
    record(feature, actual);
  }

  ArvCamera* camera_;
  std::string purpose_;
  TimingApplied& applied_;
};

// SFNC names first, then GigE Vision 2.0's (GevIEEE1588...), which older cameras carry.
struct PtpNames {
  const char* enable;
  const char* status;
  const char* latch;  // latches the data set (status, offset) so it reads consistently
};
constexpr PtpNames kPtpNames[] = {{"PtpEnable", "PtpStatus", "PtpDataSetLatch"},
                                  {"GevIEEE1588", "GevIEEE1588Status", "GevIEEE1588DataSetLatch"}};

std::string latched_status(FeatureWriter& writer, const PtpNames& names) {
  if (writer.has(names.latch)) writer.execute(names.latch);
  return writer.read_string(names.status);
}

void wait_for_ptp_lock(FeatureWriter& writer, const PtpNames& names, double timeout_s) {
  const auto start = std::chrono::steady_clock::now();
  const auto deadline = start + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const std::string status = latched_status(writer, names);
    if (ptp_locked(status)) {
      writer.record(names.status, status);
      return;
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      std::ostringstream why;
      why << names.status << " is still " << status << " after " << timeout_s
          << " s (ptp_timeout_s); wanted Slave or Master: is a PTP master reachable on the camera's network?";
      writer.fail(why.str());
    }
    std::this_thread::sleep_for(kPtpPollInterval);
  }
}

void enable_ptp(ArvCamera* camera, const SourceSettings& settings, TimingApplied& applied) {
  FeatureWriter writer(camera, "ptp", applied);
  const PtpNames* names = nullptr;
  for (const PtpNames& candidate : kPtpNames) {
    if (writer.has(candidate.enable)) {
      names = &candidate;
      break;
    }
  }
  if (names == nullptr)
    writer.fail("the camera has neither PtpEnable nor GevIEEE1588 (no IEEE 1588 support)");
  writer.write_boolean(names->enable, true);
  if (writer.has(names->status)) wait_for_ptp_lock(writer, *names, settings.ptp_timeout_s);
  applied.ptp_timed = true;
}

void configure_trigger(ArvCamera* camera, const SourceSettings& settings, TimingApplied& applied) {
  FeatureWriter writer(camera, "trigger " + settings.trigger, applied);
  // Without a selector the camera has one trigger, the frame trigger.
  if (writer.has("TriggerSelector")) writer.write_enumeration("TriggerSelector", "FrameStart");
  writer.write_enumeration("TriggerMode", "On");
  writer.write_enumeration("TriggerSource", settings.trigger);
  // A software trigger has no edge.
  if (settings.trigger != "Software")
    writer.write_enumeration("TriggerActivation", settings.trigger_activation);
}

void configure_strobe(ArvCamera* camera, const SourceSettings& settings, TimingApplied& applied) {
  FeatureWriter writer(camera, "strobe " + settings.strobe, applied);
  writer.write_enumeration("LineSelector", settings.strobe);
  // Output-only lines may have no LineMode, or a read-only one that already says Output.
  if (writer.has("LineMode")) {
    if (writer.read_only("LineMode") && writer.read_string("LineMode") == "Output") {
      writer.record("LineMode", "Output");
    } else {
      writer.write_enumeration("LineMode", "Output");
    }
  }
  writer.write_enumeration("LineSource", "ExposureActive");
}

}  // namespace

std::string read_ptp_status(ArvCamera* camera) {
  TimingApplied unused;
  FeatureWriter writer(camera, "ptp", unused);
  for (const PtpNames& names : kPtpNames) {
    if (writer.has(names.status)) return latched_status(writer, names);
  }
  return "";
}

TimingApplied apply_genicam_timing(ArvCamera* camera, const SourceSettings& settings) {
  TimingApplied applied;
  if (settings.ptp) enable_ptp(camera, settings, applied);
  if (!settings.trigger.empty()) configure_trigger(camera, settings, applied);
  if (!settings.strobe.empty()) configure_strobe(camera, settings, applied);
  return applied;
}

}  // namespace panoptes::camera
