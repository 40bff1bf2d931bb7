// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/calibration_health.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/LU>

#include "panoptes/errors.h"

namespace panoptes::estimator {

const char* to_string(CalibrationMode mode) {
  return mode == CalibrationMode::kOff ? "off" : mode == CalibrationMode::kDetect ? "detect" : "correct";
}

CalibrationMode parse_calibration_mode(const std::string& text, const std::string& key) {
  if (text == "off") return CalibrationMode::kOff;
  if (text == "detect") return CalibrationMode::kDetect;
  if (text == "correct") return CalibrationMode::kCorrect;
  throw ConfigError("continuous calibration", key, "expected off, detect or correct, got '" + text + "'");
}

const char* to_string(CalibrationState state) {
  switch (state) {
    case CalibrationState::kUnknown:
      return "unknown";
    case CalibrationState::kOk:
      return "ok";
    case CalibrationState::kSmallBias:
      return "small bias";
    case CalibrationState::kQuarantined:
      return "quarantined";
  }
  return "?";
}

ResidualStats residual_stats(std::size_t n, const Eigen::Vector2d& sum, const Eigen::Matrix2d& sum_outer,
                             double floor_px) {
  ResidualStats stats;
  stats.samples = n;
  if (n == 0) return stats;
  const double count = static_cast<double>(n);
  stats.bias = sum / count;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  if (n >= 2) covariance = (sum_outer - count * stats.bias * stats.bias.transpose()) / (count - 1.0);
  stats.spread_px = std::sqrt(std::max(0.0, covariance.trace()));
  if (n < 3) return stats;
  covariance += floor_px * floor_px * Eigen::Matrix2d::Identity();
  stats.t2 = count * stats.bias.dot(covariance.inverse() * stats.bias);
  // (n−2)/(2(n−1)) T² ~ F(2, n−2); its survival function in closed form.
  stats.p_value = std::pow(1.0 + stats.t2 / (count - 1.0), -(count - 2.0) / 2.0);
  return stats;
}

void CalibrationMonitor::Sums::add(const Eigen::Vector2d& r) {
  ++n;
  sum += r;
  outer += r * r.transpose();
}

void CalibrationMonitor::Sums::remove(const Sums& part) {
  n -= std::min(n, part.n);
  sum -= part.sum;
  outer -= part.outer;
  if (n == 0) {  // no drift of the running sums
    sum.setZero();
    outer.setZero();
  }
}

CalibrationMonitor::CalibrationMonitor(CalibrationHealthOptions options, double centroid_sigma_px)
    : options_(std::move(options)), floor_px_(centroid_sigma_px) {}

void CalibrationMonitor::set_cameras(const std::vector<std::string>& camera_ids,
                                     const std::vector<Eigen::Vector2d>& image_sizes) {
  std::vector<PerCamera> cameras(camera_ids.size());
  for (std::size_t i = 0; i < camera_ids.size(); ++i) {
    // A camera already known keeps its statistics (and quarantine) when another one is added.
    const auto known = std::find_if(cameras_.begin(), cameras_.end(),
                                    [&](const PerCamera& c) { return c.health.camera_id == camera_ids[i]; });
    if (known != cameras_.end()) cameras[i] = std::move(*known);
    cameras[i].health.camera_id = camera_ids[i];
    cameras[i].image_size = image_sizes[i].cwiseMax(Eigen::Vector2d(1, 1));
  }
  cameras_ = std::move(cameras);
}

bool CalibrationMonitor::due(int camera_index, TimeNs stamp_ns) {
  PerCamera& camera = cameras_.at(camera_index);
  if (camera.last_monitored_ns != 0 && stamp_ns >= camera.last_monitored_ns &&
      stamp_ns - camera.last_monitored_ns < options_.sample_interval_ns)
    return false;
  camera.last_monitored_ns = stamp_ns;
  return true;
}

std::size_t CalibrationMonitor::find_sample(const PerCamera& camera, std::int64_t track_id) {
  const auto& last = camera.last_sample;
  // The track asked about last (wants(), then add_prediction() and add() of the same track).
  if (camera.hint < last.size() && last[camera.hint].first == track_id) return camera.hint;
  const auto found = std::lower_bound(last.begin(), last.end(), track_id,
                                      [](const auto& entry, std::int64_t id) { return entry.first < id; });
  camera.hint = static_cast<std::size_t>(found - last.begin());
  return camera.hint;
}

bool CalibrationMonitor::wants(int camera_index, std::int64_t track_id, TimeNs stamp_ns) const {
  const PerCamera& camera = cameras_.at(camera_index);
  const std::size_t at = find_sample(camera, track_id);
  if (at == camera.last_sample.size() || camera.last_sample[at].first != track_id) return true;
  const TimeNs last = camera.last_sample[at].second;
  return stamp_ns - last >= options_.sample_interval_ns || stamp_ns < last;
}

void CalibrationMonitor::note_sample(PerCamera& camera, std::int64_t track_id, TimeNs stamp_ns) {
  auto& last = camera.last_sample;
  const std::size_t at = find_sample(camera, track_id);
  if (at < last.size() && last[at].first == track_id) {
    last[at].second = stamp_ns;
  } else {  // track ids grow: a new one almost always goes at the end
    last.emplace(last.begin() + static_cast<std::ptrdiff_t>(at), track_id, stamp_ns);
  }
}

CalibrationMonitor::Frame& CalibrationMonitor::frame_at(PerCamera& camera, TimeNs stamp_ns) {
  if (camera.window.empty() || camera.window.back().stamp_ns != stamp_ns) camera.window.push_back({stamp_ns});
  return camera.window.back();
}

void CalibrationMonitor::add_prediction(int camera_index, std::int64_t track_id, TimeNs stamp_ns, bool seen) {
  PerCamera& camera = cameras_.at(camera_index);
  note_sample(camera, track_id, stamp_ns);
  Frame& frame = frame_at(camera, stamp_ns);
  ++frame.predicted;
  ++camera.predicted;
  if (seen) {
    ++frame.seen;
    ++camera.seen;
  }
}

void CalibrationMonitor::add_blobs(int camera_index, TimeNs stamp_ns, std::size_t blobs,
                                   std::size_t explained) {
  PerCamera& camera = cameras_.at(camera_index);
  Frame& frame = frame_at(camera, stamp_ns);
  frame.blobs += blobs;
  frame.explained += explained;
  camera.blobs += blobs;
  camera.explained += explained;
}

void CalibrationMonitor::add(int camera_index, std::int64_t track_id, TimeNs stamp_ns,
                             const Eigen::Vector2d& at, const Eigen::Vector2d& residual) {
  PerCamera& camera = cameras_.at(camera_index);
  note_sample(camera, track_id, stamp_ns);
  const int column = std::clamp(static_cast<int>(kCalibrationRegionsX * at.x() / camera.image_size.x()), 0,
                                kCalibrationRegionsX - 1);
  const int row = std::clamp(static_cast<int>(kCalibrationRegionsY * at.y() / camera.image_size.y()), 0,
                             kCalibrationRegionsY - 1);
  const int region = row * kCalibrationRegionsX + column;
  frame_at(camera, stamp_ns).regions[region].add(residual);
  camera.whole.add(residual);
  camera.regions[region].add(residual);
  ++camera.health.residuals;
}

void CalibrationMonitor::expire(PerCamera& camera, TimeNs stamp_ns) {
  while (!camera.window.empty() && stamp_ns - camera.window.front().stamp_ns > options_.window_ns) {
    const Frame& old = camera.window.front();
    for (int r = 0; r < kCalibrationRegions; ++r) {
      camera.whole.remove(old.regions[r]);
      camera.regions[r].remove(old.regions[r]);
    }
    camera.predicted -= old.predicted;
    camera.seen -= old.seen;
    camera.blobs -= old.blobs;
    camera.explained -= old.explained;
    camera.window.pop_front();
  }
  // Tracks not sampled for a window are forgotten (ids are never reused).
  std::erase_if(camera.last_sample,
                [&](const auto& entry) { return stamp_ns - entry.second > 4 * options_.window_ns; });
}

void CalibrationMonitor::update_stats(PerCamera& camera) const {
  auto& health = camera.health;
  health.predicted = camera.predicted;
  health.seen = camera.seen;
  health.blobs = camera.blobs;
  health.explained = camera.explained;
  health.whole = residual_stats(camera.whole.n, camera.whole.sum, camera.whole.outer, floor_px_);
  for (int r = 0; r < kCalibrationRegions; ++r) {
    const Sums& sums = camera.regions[r];
    health.regions[r] = residual_stats(sums.n, sums.sum, sums.outer, floor_px_);
  }
}

namespace {

constexpr std::array<const char*, kCalibrationRegions> kRegionNames = {
    "top left", "top", "top right", "left", "centre", "right", "bottom left", "bottom", "bottom right"};

std::string describe(const ResidualStats& s, const char* where) {
  char buffer[200];
  std::snprintf(buffer, sizeof buffer,
                "%s: bias (%+.2f, %+.2f) px = %.2f px over %zu residuals, spread %.2f px, p %.1e", where,
                s.bias.x(), s.bias.y(), s.bias.norm(), s.samples, s.spread_px, s.p_value);
  return buffer;
}

}  // namespace

void CalibrationMonitor::note_correction(int camera_index, const std::string& why) {
  CameraCalibrationHealth& health = cameras_.at(camera_index).health;
  if (health.state != CalibrationState::kQuarantined) return;
  static const std::string kNotCorrected = "; not corrected: ";
  const auto at = health.reason.find(kNotCorrected);
  if (at != std::string::npos) health.reason.erase(at);
  health.reason += kNotCorrected + why;
}

void CalibrationMonitor::restart(int camera_index) {
  PerCamera& camera = cameras_.at(camera_index);
  PerCamera fresh;
  fresh.image_size = camera.image_size;
  fresh.last_monitored_ns = camera.last_monitored_ns;
  fresh.health = std::move(camera.health);
  camera = std::move(fresh);
}

void CalibrationMonitor::note_transition(const CameraCalibrationHealth& health, bool quarantined,
                                         TimeNs stamp_ns) {
  if (transitions_.size() < kMaxTransitions)
    transitions_.push_back({health.camera_id, quarantined, stamp_ns, quarantined ? health.reason : ""});
}

std::vector<CalibrationTransition> CalibrationMonitor::take_transitions() {
  std::vector<CalibrationTransition> out = std::move(transitions_);
  transitions_.clear();
  return out;
}

bool CalibrationMonitor::judge(int camera_index, TimeNs stamp_ns) {
  PerCamera& camera = cameras_.at(camera_index);
  expire(camera, stamp_ns);
  update_stats(camera);
  auto& health = camera.health;
  const CalibrationState before = health.state;
  // The whole image and each region are tested; α is shared among them (Bonferroni).
  const double alpha = options_.false_alarm / static_cast<double>(kCalibrationRegions + 1);
  const auto judged = [&](const ResidualStats& s) { return s.samples >= options_.min_samples; };
  const auto significant = [&](const ResidualStats& s) { return judged(s) && s.p_value < alpha; };
  const auto biased = [&](const ResidualStats& s) {
    return significant(s) && s.bias.norm() >= options_.min_bias_px;
  };
  const auto calm = [&](const ResidualStats& s) {
    return !judged(s) || s.bias.norm() < options_.release_fraction * options_.min_bias_px ||
           s.p_value > options_.release_p;
  };
  // The most significant biased part of the image, or of those only significant.
  const ResidualStats* worst = nullptr;
  const char* where = "whole image";
  bool any_biased = false;
  const auto consider = [&](const ResidualStats& s, const char* name) {
    if (!significant(s)) return;
    const bool is_biased = biased(s);
    if (worst == nullptr || (is_biased && !any_biased) || (is_biased == any_biased && s.t2 > worst->t2)) {
      worst = &s;
      where = name;
    }
    any_biased = any_biased || is_biased;
  };
  consider(health.whole, "whole image");
  for (int r = 0; r < kCalibrationRegions; ++r) consider(health.regions[r], kRegionNames[r]);
  // Blobs that miss the tracks altogether (a bump beyond search_px) leave no residuals to test.
  const bool judged_seen = health.predicted >= options_.min_blind_predictions;
  const double seen_share =
      judged_seen ? static_cast<double>(health.seen) / static_cast<double>(health.predicted) : 1.0;
  const bool unexplained =
      health.blobs > 0 && static_cast<double>(health.explained) <
                              options_.max_explained_blob_fraction * static_cast<double>(health.blobs);
  const bool blind = judged_seen && seen_share < options_.min_seen_fraction && unexplained;
  std::string blind_reason;
  if (blind) {
    blind_reason = "its blobs miss the tracks: " + std::to_string(health.seen) + " of " +
                   std::to_string(health.predicted) + " predictions in its image had a blob in their gate, " +
                   std::to_string(health.explained) + " of its " + std::to_string(health.blobs) +
                   " blobs lay near a track";
  }

  if (health.state == CalibrationState::kQuarantined) {
    bool all_calm = judged(health.whole) && calm(health.whole) &&
                    (!judged_seen || seen_share >= options_.release_seen_fraction);
    for (const auto& region : health.regions) all_calm = all_calm && calm(region);
    if (!all_calm) {
      camera.calm_since_ns = 0;
    } else if (camera.calm_since_ns == 0) {
      camera.calm_since_ns = stamp_ns;
    }
    if (camera.calm_since_ns == 0 || stamp_ns - camera.calm_since_ns < options_.window_ns) return false;
    camera.calm_since_ns = 0;
    ++health.releases;
    note_transition(health, false, stamp_ns);
  } else if ((any_biased || blind) && last_quarantine_ns_ != 0 &&
             stamp_ns - last_quarantine_ns_ < options_.window_ns && stamp_ns >= last_quarantine_ns_) {
    // Held: one camera at a time, the most biased first.
    health.state = CalibrationState::kSmallBias;
    health.reason = "held while " + last_quarantined_ +
                    " was just quarantined: " + (any_biased ? describe(*worst, where) : blind_reason);
    health.quarantined_since_ns = 0;
    return health.state != before;
  } else if (any_biased || blind) {
    last_quarantine_ns_ = stamp_ns;
    last_quarantined_ = health.camera_id;
    health.state = CalibrationState::kQuarantined;
    health.reason = "quarantined: " + (any_biased ? describe(*worst, where) : blind_reason);
    health.quarantined_since_ns = stamp_ns;
    ++health.quarantines;
    note_transition(health, true, stamp_ns);
    return true;
  }
  health.quarantined_since_ns = 0;
  if (!judged(health.whole)) {
    health.state = CalibrationState::kUnknown;
    health.reason = "too few residuals (" + std::to_string(health.whole.samples) + ")";
  } else if (worst != nullptr) {
    health.state = CalibrationState::kSmallBias;
    health.reason = "small bias " + describe(*worst, where);
  } else {
    health.state = CalibrationState::kOk;
    health.reason.clear();
  }
  return health.state != before;
}

bool CalibrationMonitor::quarantined(int camera) const {
  return cameras_.at(camera).health.state == CalibrationState::kQuarantined;
}

void CalibrationMonitor::note_withheld(int camera, std::size_t blobs) {
  cameras_.at(camera).health.blobs_withheld += blobs;
}

std::vector<CameraCalibrationHealth> CalibrationMonitor::health() const {
  std::vector<CameraCalibrationHealth> all;
  all.reserve(cameras_.size());
  for (const auto& camera : cameras_) all.push_back(camera.health);
  return all;
}

}  // namespace panoptes::estimator
