// SPDX-License-Identifier: Apache-2.0
// Fixed-rate re-sampling of asynchronous track and pose updates (method: resample.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include <Eigen/Geometry>

#include "panoptes/formats/resample.h"

namespace panoptes {

namespace {

// For the sorted stamps of one object, the bracketing updates of each grid time, walked forward.
struct Bracket {
  std::size_t before = 0;  // index of the last update at or before t
  std::size_t after = 0;   // index of the first update at or after t
  double s = 0.0;          // interpolation weight of `after`
  bool valid = false;
};

class BracketWalker {
 public:
  BracketWalker(const std::vector<TimeNs>& stamps, TimeNs max_gap_ns)
      : stamps_(stamps), max_gap_ns_(max_gap_ns) {}

  // Grid times must be non-decreasing from call to call.
  Bracket at(TimeNs t) {
    while (next_ < stamps_.size() && stamps_[next_] <= t) ++next_;
    Bracket bracket;
    if (next_ == 0) return bracket;  // no update at or before t
    bracket.before = next_ - 1;
    if (stamps_[bracket.before] == t) {
      bracket.after = bracket.before;
      bracket.valid = true;
      return bracket;
    }
    if (next_ == stamps_.size()) return bracket;  // no update after t
    bracket.after = next_;
    const TimeNs gap = stamps_[bracket.after] - stamps_[bracket.before];
    if (gap > max_gap_ns_) return bracket;
    bracket.s = static_cast<double>(t - stamps_[bracket.before]) / static_cast<double>(gap);
    bracket.valid = true;
    return bracket;
  }

 private:
  const std::vector<TimeNs>& stamps_;
  TimeNs max_gap_ns_;
  std::size_t next_ = 0;
};

// What the export needs of a track update, compact (records are large and interleaved by id).
struct TrackUpdate {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  float residual_m = 0.0F;
  std::uint8_t camera_mask = 0;
};
TimeNs stamp_of(const TrackUpdate& update) {
  return update.stamp_ns;
}
TimeNs stamp_of(const PoseRecord* pose) {
  return pose->stamp_ns;
}

// Orders one object's updates by stamp; of several updates with one stamp the last one read wins.
template <class Update>
void sort_by_stamp(std::vector<Update>& updates) {
  auto earlier = [](const Update& a, const Update& b) { return stamp_of(a) < stamp_of(b); };
  if (!std::is_sorted(updates.begin(), updates.end(), earlier)) {
    std::stable_sort(updates.begin(), updates.end(), earlier);
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < updates.size(); ++i) {
    if (kept > 0 && stamp_of(updates[kept - 1]) == stamp_of(updates[i])) {
      updates[kept - 1] = updates[i];
    } else {
      updates[kept++] = updates[i];
    }
  }
  updates.resize(kept);
}

template <class Update>
std::vector<TimeNs> stamps_of(const std::vector<Update>& updates) {
  std::vector<TimeNs> stamps;
  stamps.reserve(updates.size());
  for (const Update& update : updates) stamps.push_back(stamp_of(update));
  return stamps;
}

std::vector<TimeNs> grid_times_ns(const SampleGrid& grid) {
  std::vector<TimeNs> times(grid.count);
  for (std::size_t k = 0; k < grid.count; ++k) times[k] = grid.time_ns(k);
  return times;
}

std::vector<double> grid_times_s(const SampleGrid& grid) {
  std::vector<double> times(grid.count);
  for (std::size_t k = 0; k < grid.count; ++k) times[k] = ns_to_seconds(grid.time_ns(k) - grid.start_ns);
  return times;
}

float residual_of(const TrackRecord& track) {
  if (track.status == TrackStatus::kCoasting) return 0.0F;
  const auto& c = track.position_covariance;
  const double mean_variance = (c[0] + c[3] + c[5]) / 3.0;
  return mean_variance > 0.0 ? static_cast<float>(std::sqrt(mean_variance)) : 0.0F;
}

std::uint8_t camera_mask_of(const TrackRecord& track) {
  if (track.status == TrackStatus::kCoasting) return 0;
  const int cameras = std::clamp(track.cameras, 0, 7);
  return static_cast<std::uint8_t>((1 << cameras) - 1);
}

}  // namespace

TimeNs SampleGrid::time_ns(std::size_t k) const {
  if (!times.empty()) return times[k];
  return start_ns + static_cast<TimeNs>(std::llround(static_cast<double>(k) * 1e9 / rate_hz));
}

SampleGrid fixed_rate_grid(TimeNs first_ns, TimeNs last_ns, int rate_hz) {
  if (rate_hz < 1 || rate_hz > 10000)
    throw std::invalid_argument("fixed frame rate must be 1..10000 Hz, got " + std::to_string(rate_hz));
  SampleGrid grid;
  grid.rate_hz = rate_hz;
  const TimeNs rate = rate_hz;
  TimeNs second = first_ns / kNsPerSecond;
  // The first period k of `second` whose instant is at or after first_ns.
  TimeNs k = ((first_ns - second * kNsPerSecond) * rate + kNsPerSecond - 1) / kNsPerSecond;
  for (;;) {
    if (k == rate) {
      ++second;
      k = 0;
    }
    const TimeNs instant = second * kNsPerSecond + k * kNsPerSecond / rate;
    if (instant > last_ns) break;
    if (instant >= first_ns) grid.times.push_back(instant);
    ++k;
  }
  grid.count = grid.times.size();
  grid.start_ns = grid.times.empty() ? first_ns : grid.times.front();
  return grid;
}

SampleGrid make_grid(const std::vector<TrackRecord>& tracks, const std::vector<PoseRecord>& poses,
                     const ResampleOptions& options) {
  if (!(std::isfinite(options.rate_hz) && options.rate_hz > 0.0)) {
    throw std::invalid_argument("rate must be positive, got " + std::to_string(options.rate_hz));
  }
  TimeNs first = std::numeric_limits<TimeNs>::max();
  TimeNs last = std::numeric_limits<TimeNs>::min();
  for (const TrackRecord& track : tracks) {
    first = std::min(first, track.stamp_ns);
    last = std::max(last, track.stamp_ns);
  }
  for (const PoseRecord& pose : poses) {
    first = std::min(first, pose.stamp_ns);
    last = std::max(last, pose.stamp_ns);
  }
  if (options.start_ns) first = *options.start_ns;
  if (options.end_ns) last = *options.end_ns;
  if (first == std::numeric_limits<TimeNs>::max() || last < first) {
    throw std::invalid_argument("no records to export in the requested time range");
  }
  SampleGrid grid;
  grid.start_ns = first;
  grid.rate_hz = options.rate_hz;
  grid.count = static_cast<std::size_t>(std::floor(ns_to_seconds(last - first) * options.rate_hz + 1e-9)) + 1;
  return grid;
}

MarkerTrajectories resample_tracks(const std::vector<TrackRecord>& tracks, const SampleGrid& grid,
                                   const ResampleOptions& options) {
  std::map<std::int64_t, std::vector<TrackUpdate>> by_id;
  for (const TrackRecord& track : tracks) {
    if (track.status == TrackStatus::kTentative && !options.include_tentative) continue;
    by_id[track.id].push_back({track.stamp_ns, track.p, residual_of(track), camera_mask_of(track)});
  }
  MarkerTrajectories out;
  out.data_rate_hz = grid.rate_hz;
  out.units.assign(1, 'm');  // (a string literal here trips a GCC 12 -Wrestrict false positive)
  out.times_s = grid_times_s(grid);
  for (const auto& [id, unused] : by_id) {
    const auto named = options.marker_names.find(id);
    out.marker_names.push_back(named != options.marker_names.end()
                                   ? named->second
                                   : std::string("track_").append(std::to_string(id)));
  }
  const std::size_t markers = by_id.size();
  out.positions.assign(grid.count * markers, Eigen::Vector3d::Zero());
  out.valid.assign(grid.count * markers, 0);
  out.residuals_m.assign(grid.count * markers, -1.0F);
  out.camera_masks.assign(grid.count * markers, 0);
  const std::vector<TimeNs> times = grid_times_ns(grid);
  // Frame-major output: walk all markers at each sample time (one bracket walker per marker).
  std::vector<std::vector<TrackUpdate>*> updates_of;
  std::vector<std::vector<TimeNs>> stamps;
  for (auto& [id, updates] : by_id) {
    sort_by_stamp(updates);
    updates_of.push_back(&updates);
    stamps.push_back(stamps_of(updates));
  }
  std::vector<BracketWalker> walkers;
  walkers.reserve(markers);
  for (const std::vector<TimeNs>& marker_stamps : stamps)
    walkers.emplace_back(marker_stamps, options.max_gap_ns);
  for (std::size_t k = 0; k < grid.count; ++k) {
    for (std::size_t marker = 0; marker < markers; ++marker) {
      const Bracket b = walkers[marker].at(times[k]);
      if (!b.valid) continue;
      const TrackUpdate& before = (*updates_of[marker])[b.before];
      const TrackUpdate& after = (*updates_of[marker])[b.after];
      const std::size_t sample = k * markers + marker;
      out.positions[sample] = (1.0 - b.s) * before.p + b.s * after.p;
      out.valid[sample] = 1;
      const TrackUpdate& nearer = b.s < 0.5 ? before : after;
      out.residuals_m[sample] = nearer.residual_m;
      out.camera_masks[sample] = nearer.camera_mask;
    }
  }
  return out;
}

BodyTrajectories resample_poses(const std::vector<PoseRecord>& poses, const SampleGrid& grid,
                                const ResampleOptions& options) {
  std::map<std::string, std::vector<const PoseRecord*>> by_body;
  for (const PoseRecord& pose : poses) by_body[pose.body].push_back(&pose);
  BodyTrajectories out;
  out.data_rate_hz = grid.rate_hz;
  out.times_s = grid_times_s(grid);
  for (const auto& [name, unused] : by_body) out.body_names.push_back(name);
  const std::size_t bodies = by_body.size();
  out.positions.assign(grid.count * bodies, Eigen::Vector3d::Zero());
  out.quaternions.assign(grid.count * bodies, Eigen::Vector4d(0, 0, 0, 1));
  out.valid.assign(grid.count * bodies, 0);
  const std::vector<TimeNs> times = grid_times_ns(grid);
  std::size_t body = 0;
  for (auto& [name, records] : by_body) {
    sort_by_stamp(records);
    const std::vector<TimeNs> stamps = stamps_of(records);
    BracketWalker walker(stamps, options.max_gap_ns);
    for (std::size_t k = 0; k < grid.count; ++k) {
      const Bracket b = walker.at(times[k]);
      if (!b.valid) continue;
      const PoseRecord& before = *records[b.before];
      const PoseRecord& after = *records[b.after];
      const std::size_t sample = k * bodies + body;
      out.positions[sample] = (1.0 - b.s) * before.p + b.s * after.p;
      // Eigen's slerp takes the shorter arc (q and -q are one rotation).
      const Eigen::Quaterniond qa(before.q[3], before.q[0], before.q[1], before.q[2]);
      const Eigen::Quaterniond qb(after.q[3], after.q[0], after.q[1], after.q[2]);
      const Eigen::Quaterniond q = qa.normalized().slerp(b.s, qb.normalized()).normalized();
      out.quaternions[sample] = Eigen::Vector4d(q.x(), q.y(), q.z(), q.w());
      out.valid[sample] = 1;
    }
    ++body;
  }
  return out;
}

void append_body_origins(MarkerTrajectories& markers, const BodyTrajectories& bodies) {
  const std::size_t old_count = markers.marker_count();
  const std::size_t new_count = old_count + bodies.body_count();
  const std::size_t frames = bodies.frame_count();
  if (markers.frame_count() == 0) {
    markers.times_s = bodies.times_s;
    markers.data_rate_hz = bodies.data_rate_hz;
    if (markers.units.empty()) markers.units.assign(1, 'm');
  }
  MarkerTrajectories merged = markers;
  merged.marker_names.insert(merged.marker_names.end(), bodies.body_names.begin(), bodies.body_names.end());
  merged.positions.assign(frames * new_count, Eigen::Vector3d::Zero());
  merged.valid.assign(frames * new_count, 0);
  merged.residuals_m.assign(frames * new_count, -1.0F);
  merged.camera_masks.assign(frames * new_count, 0);
  for (std::size_t f = 0; f < frames; ++f) {
    for (std::size_t m = 0; m < new_count; ++m) {
      const std::size_t to = f * new_count + m;
      if (m < old_count) {
        const std::size_t from = f * old_count + m;
        merged.positions[to] = markers.positions[from];
        merged.valid[to] = markers.valid[from];
        if (!markers.residuals_m.empty()) merged.residuals_m[to] = markers.residuals_m[from];
        if (!markers.camera_masks.empty()) merged.camera_masks[to] = markers.camera_masks[from];
      } else {
        const std::size_t from = f * bodies.body_count() + (m - old_count);
        merged.positions[to] = bodies.positions[from];
        merged.valid[to] = bodies.valid[from];
        merged.residuals_m[to] = bodies.valid[from] != 0 ? 0.0F : -1.0F;  // computed, not measured
      }
    }
  }
  markers = std::move(merged);
}

}  // namespace panoptes
