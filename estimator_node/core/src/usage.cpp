// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/usage.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "panoptes/estimator/tracker.h"

namespace panoptes::estimator {

namespace {
constexpr double kMinMs = 1e-4;  // 0.1 µs
constexpr double kGrowth = 1.02;
}  // namespace

void DurationHistogram::add(double milliseconds) {
  if (!std::isfinite(milliseconds)) return;
  const double v = std::max(milliseconds, kMinMs);
  const int bin = std::min(kBins - 1, static_cast<int>(std::log(v / kMinMs) / std::log(kGrowth)));
  ++bins_[bin];
  ++count_;
}

double DurationHistogram::quantile_ms(double q) const {
  if (count_ == 0) return 0.0;
  const auto target = static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * count_));
  std::uint64_t seen = 0;
  for (int i = 0; i < kBins; ++i) {
    seen += bins_[i];
    if (seen >= std::max<std::uint64_t>(target, 1)) return kMinMs * std::pow(kGrowth, i + 0.5);  // bin centre
  }
  return kMinMs * std::pow(kGrowth, kBins);
}

UsageMonitor::PerCamera& UsageMonitor::camera(const std::string& camera_id) {
  // Garbage camera ids must not grow the map without bound.
  constexpr std::size_t kMaxCameras = 1024;
  const auto found = cameras_.find(camera_id);
  if (found != cameras_.end()) return found->second;
  return cameras_[cameras_.size() >= kMaxCameras ? std::string("<other>") : camera_id];
}

const char* to_string(CameraState state) {
  switch (state) {
    case CameraState::kLive:
      return "live";
    case CameraState::kLost:
      return "lost";
    case CameraState::kUnknown:
      break;
  }
  return "unknown";
}

void UsageMonitor::note_received(const std::string& camera_id, double latency_ms, TimeNs arrival_ns) {
  auto& camera = this->camera(camera_id);
  ++camera.received;
  camera.latency.add(latency_ms);
  camera.last_arrival_ns = std::max(camera.last_arrival_ns, arrival_ns);
}

void UsageMonitor::note_refused(const std::string& camera_id, bool new_writer) {
  auto& camera = this->camera(camera_id);
  ++camera.refused_frames;
  if (new_writer) ++camera.refused_writers;
  ++reasons_["camera_id_claimed_by_second_writer"];
}

std::size_t UsageMonitor::cameras_lost(TimeNs now_ns) const {
  std::size_t lost = 0;
  for (const auto& [id, camera] : cameras_) {
    if (camera.last_arrival_ns != 0 && now_ns - camera.last_arrival_ns > lost_after_ns_) ++lost;
  }
  return lost;
}

void UsageMonitor::judge_health(EstimatorUsage& usage, TimeNs now_ns) const {
  for (auto& u : usage.cameras) {
    const auto found = cameras_.find(u.camera_id);
    if (now_ns == 0 || found == cameras_.end() || found->second.last_arrival_ns == 0) continue;
    const TimeNs since_ns = std::max<TimeNs>(0, now_ns - found->second.last_arrival_ns);
    u.since_last_frame_s = static_cast<double>(since_ns) * 1e-9;
    u.state = since_ns > lost_after_ns_ ? CameraState::kLost : CameraState::kLive;
    ++(u.state == CameraState::kLive ? usage.cameras_live : usage.cameras_lost);
  }
  // Every camera whose health is known is lost: whatever the tracker holds is a prediction.
  if (usage.cameras_live == 0 && usage.cameras_lost > 0)
    usage.tracks_unobserved = usage.tracks_tentative + usage.tracks_confirmed + usage.tracks_coasting;
}

void UsageMonitor::note_dropped(const std::string& camera_id, const std::string& reason,
                                std::uint64_t frames) {
  camera(camera_id).dropped_before_tracker += frames;
  if (!reason.empty()) reasons_[reason] += frames;  // "": the caller counts the reason itself
}

void UsageMonitor::note_reason(const std::string& reason, std::uint64_t n) {
  if (n != 0) reasons_[reason] += n;
}

EstimatorUsage UsageMonitor::summarize(const Tracker& tracker, TimeNs stamp_ns, double latency_window_ms,
                                       const std::map<std::string, CameraCounters>& other_cameras,
                                       TimeNs now_ns) const {
  EstimatorUsage usage;
  usage.stamp_ns = stamp_ns;
  const auto counts = tracker.track_counts(tracker.last_stamp_ns());
  usage.tracks_tentative = counts[0];
  usage.tracks_confirmed = counts[1];
  usage.tracks_coasting = counts[2];
  const auto& stats = tracker.stats();
  usage.frames = stats.frames;
  usage.replays = stats.replays;
  usage.replayed_frames = stats.replayed_frames;
  usage.update_p50_ms = update_.quantile_ms(0.5);
  usage.update_p99_ms = update_.quantile_ms(0.99);
  usage.latency_window_ms = latency_window_ms;
  usage.counters = reasons_;
  if (stats.frames_unknown_camera) usage.counters["uncalibrated_camera"] += stats.frames_unknown_camera;
  if (stats.frames_too_late) usage.counters["too_late"] += stats.frames_too_late;
  if (stats.blobs_non_finite) usage.counters["non_finite_blob_in_tracker"] += stats.blobs_non_finite;
  if (stats.blobs_not_initiated) usage.counters["blobs_not_initiated"] += stats.blobs_not_initiated;

  const auto& tracked = tracker.camera_counters();
  std::map<std::string, CameraUsage> merged;
  for (const auto& [id, camera] : cameras_) {
    auto& u = merged[id];
    u.camera_id = id;
    u.frames = camera.received;
    u.dropped = camera.dropped_before_tracker;
    u.latency_p50_ms = camera.latency.quantile_ms(0.5);
    u.latency_p99_ms = camera.latency.quantile_ms(0.99);
    u.refused_frames = camera.refused_frames;
    u.refused_writers = camera.refused_writers;
  }
  const auto merge = [&merged](const std::string& id, const CameraCounters& counters) {
    auto& u = merged[id];
    u.camera_id = id;
    // Frames that never passed through the monitor (direct use of the tracker) still count.
    u.frames = std::max(u.frames, counters.frames + u.dropped);
    u.used = counters.used;
    u.late = counters.late;
    u.too_late = counters.too_late;
    u.dropped += counters.frames - counters.used;
    u.blobs = counters.blobs;
    u.associated = counters.associated;
    u.last_stamp_ns = counters.last_stamp_ns;
  };
  for (const auto& [id, counters] : tracked) merge(id, counters);
  for (const auto& [id, counters] : other_cameras) merge(id, counters);
  for (auto& [id, u] : merged) {
    u.utilisation = u.frames == 0 ? 0.0 : static_cast<double>(u.used) / static_cast<double>(u.frames);
    usage.cameras.push_back(u);
  }
  judge_health(usage, now_ns);
  usage.calibration = tracker.calibration_health();
  for (const auto& health : usage.calibration) {
    if (health.quarantines > 0) usage.counters["calibration_quarantines"] += health.quarantines;
    if (health.blobs_withheld > 0) usage.counters["blobs_of_quarantined_camera"] += health.blobs_withheld;
  }
  return usage;
}

std::vector<std::string> EstimatorUsage::lines() const {
  std::vector<std::string> out;
  char buffer[512];
  for (const auto& c : cameras) {
    std::snprintf(
        buffer, sizeof buffer,
        "camera %s: frames %llu used %llu late %llu dropped %llu utilisation %.4f latency p50 %.3f ms "
        "p99 %.3f ms",
        c.camera_id.c_str(), static_cast<unsigned long long>(c.frames),
        static_cast<unsigned long long>(c.used), static_cast<unsigned long long>(c.late),
        static_cast<unsigned long long>(c.dropped), c.utilisation, c.latency_p50_ms, c.latency_p99_ms);
    out.emplace_back(buffer);
    if (c.refused_frames > 0) {
      out.back() += " refused " + std::to_string(c.refused_frames) + " from " +
                    std::to_string(c.refused_writers) + " second writer(s)";
    }
  }
  for (const auto& h : calibration) {
    if (h.state == CalibrationState::kOk) continue;
    out.push_back("calibration " + h.camera_id + ": " + to_string(h.state) +
                  (h.reason.empty() || h.state == CalibrationState::kQuarantined ? "" : ", ") +
                  (h.state == CalibrationState::kQuarantined
                       ? h.reason.substr(std::string("quarantined").size())
                       : h.reason));
  }
  std::snprintf(buffer, sizeof buffer, "replays %llu (%llu frames replayed)",
                static_cast<unsigned long long>(replays), static_cast<unsigned long long>(replayed_frames));
  out.emplace_back(buffer);
  if (cpu_percent > 0) {  // rates over the last status period: live only
    std::snprintf(buffer, sizeof buffer, ", %.1f/s (%.0f frames/s), cpu %.1f%%", replays_per_s,
                  replayed_frames_per_s, cpu_percent);
    out.back() += buffer;
  }
  std::string reasons = "dropped by reason:";
  if (counters.empty()) reasons += " none";
  for (const auto& [reason, n] : counters) reasons += " " + reason + "=" + std::to_string(n);
  out.push_back(reasons);
  return out;
}

}  // namespace panoptes::estimator
