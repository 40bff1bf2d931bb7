// SPDX-License-Identifier: Apache-2.0
#include "panoptes/eval/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "panoptes/simulator.h"

namespace panoptes::estimator {

namespace {

// For every marker and camera, the mid-exposure times of the frames that showed the marker, so
// "how many cameras saw marker m in (t - window, t]" is one look per camera at the newest time at
// or before t. evaluate() asks in time order, so each (marker, camera) keeps a cursor that only
// moves forward (a binary search per question was 30 % of evaluate's time, in cache misses). Only
// frames the scene produces count: those with mid-exposure at or after its start.
class Visibility {
 public:
  Visibility(const Scene& scene, TimeNs from_ns, TimeNs to_ns) {
    from_ns = std::max<TimeNs>(from_ns, 0);
    const std::size_t cameras = scene.cameras().size();
    times_.assign(scene.marker_names().size(), std::vector<std::vector<TimeNs>>(cameras));
    for (std::size_t c = 0; c < cameras; ++c) {
      const CameraSimulator camera(scene, scene.cameras()[c].calibration.id);
      const SimCameraConfig& config = camera.config();
      // Start just before `from` and step to the first frame at or after it.
      auto k =
          static_cast<std::int64_t>(std::floor(ns_to_seconds(from_ns - config.phase_ns) * config.rate_hz)) -
          1;
      while (camera.frame_time_ns(k) < from_ns) ++k;
      while (camera.frame_time_ns(k - 1) >= from_ns) --k;
      for (; camera.frame_time_ns(k) <= to_ns; ++k) {
        const TimeNs t = camera.frame_time_ns(k);
        for (int m : camera.visible_markers(k)) times_[static_cast<std::size_t>(m)][c].push_back(t);
      }
    }
    after_.assign(times_.size(), std::vector<std::size_t>(cameras, 0));
  }

  int cameras_showing(std::size_t marker, TimeNs t, TimeNs window) {
    int count = 0;
    for (std::size_t c = 0; c < times_[marker].size(); ++c) {
      const std::vector<TimeNs>& times = times_[marker][c];
      std::size_t& after = after_[marker][c];   // the first time after the last question's t
      if (after > 0 && times[after - 1] > t) {  // asked out of order: search
        after = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin());
      }
      while (after < times.size() && times[after] <= t) ++after;
      if (after > 0 && times[after - 1] > t - window) ++count;
    }
    return count;
  }

 private:
  std::vector<std::vector<std::vector<TimeNs>>> times_;  // [marker][camera]
  std::vector<std::vector<std::size_t>> after_;          // [marker][camera]: see cameras_showing
};

double seconds_since_start(TimeNs stamp_ns, TimeNs epoch_ns) {
  return ns_to_seconds(stamp_ns - epoch_ns);
}

// Every marker's switches with the marker's name, in time order.
std::vector<std::pair<const IdSwitch*, const std::string*>> switches_in_time_order(
    const std::vector<MarkerEvaluation>& markers) {
  std::vector<std::pair<const IdSwitch*, const std::string*>> switches;
  for (const auto& marker : markers) {
    for (const auto& s : marker.id_switches) switches.emplace_back(&s, &marker.name);
  }
  std::stable_sort(switches.begin(), switches.end(),
                   [](const auto& a, const auto& b) { return a.first->stamp_ns < b.first->stamp_ns; });
  return switches;
}

// Records sorted by stamp (stable: a stamp's records keep their file order).
std::vector<const TrackRecord*> sorted_by_stamp(const std::vector<TrackRecord>& tracks) {
  std::vector<const TrackRecord*> sorted;
  sorted.reserve(tracks.size());
  for (const auto& t : tracks) sorted.push_back(&t);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const TrackRecord* a, const TrackRecord* b) { return a->stamp_ns < b->stamp_ns; });
  return sorted;
}

// [begin, end) of the records sharing a stamp.
using Records = std::pair<std::size_t, std::size_t>;
// A judged instant: its absolute stamp and its records (none: a camera frame at which no track
// was published).
using Instant = std::pair<TimeNs, Records>;

// Scene times (mid-exposure) of the frames every camera of the scene makes in [from, to]: the
// simulator's own range (CameraSimulator::frames_in), which ends before the scene's duration.
std::vector<TimeNs> frame_times(const Scene& scene, TimeNs from_ns, TimeNs to_ns) {
  const TimeNs end_ns = to_ns < scene.duration_ns() ? to_ns + 1 : scene.duration_ns();
  std::vector<TimeNs> times;
  for (const auto& camera_config : scene.cameras()) {
    const CameraSimulator camera(scene, camera_config.calibration.id);
    const CameraSimulator::FrameRange range = camera.frames_in(from_ns, end_ns);
    for (std::int64_t k = range.first; k < range.end; ++k) times.push_back(camera.frame_time_ns(k));
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

// The judged instants: those after the warm-up and within the scene, in time order.
std::vector<Instant> judged_instants(const std::vector<const TrackRecord*>& sorted, const Scene& scene,
                                     const EvaluationOptions& options) {
  const TimeNs to_ns = std::min(scene.duration_ns(), options.until_ns);
  std::vector<Instant> instants;
  for (std::size_t begin = 0; begin < sorted.size();) {
    std::size_t end = begin;
    while (end < sorted.size() && sorted[end]->stamp_ns == sorted[begin]->stamp_ns) ++end;
    const TimeNs scene_time = sorted[begin]->stamp_ns - options.epoch_ns;
    if (scene_time >= options.warmup_ns && scene_time <= to_ns)
      instants.emplace_back(sorted[begin]->stamp_ns, Records{begin, end});
    begin = end;
  }
  if (!options.judge_every_frame || sorted.empty()) return instants;
  const std::size_t with_records = instants.size();
  for (const TimeNs t : frame_times(scene, std::max<TimeNs>(options.warmup_ns, 0), to_ns)) {
    const TimeNs stamp = options.epoch_ns + t;
    const auto at =
        std::lower_bound(instants.begin(), instants.begin() + static_cast<std::ptrdiff_t>(with_records),
                         stamp, [](const Instant& i, TimeNs s) { return i.first < s; });
    if (at != instants.begin() + static_cast<std::ptrdiff_t>(with_records) && at->first == stamp) continue;
    instants.emplace_back(stamp, Records{0, 0});
  }
  std::stable_sort(instants.begin(), instants.end(),
                   [](const Instant& a, const Instant& b) { return a.first < b.first; });
  return instants;
}

// An evaluation with every scene marker named and nothing counted yet.
Evaluation empty_evaluation(const Scene& scene, const EvaluationOptions& options, std::size_t instant_count) {
  const auto& names = scene.marker_names();
  Evaluation result;
  result.options = options;
  result.markers.resize(names.size());
  for (std::size_t m = 0; m < names.size(); ++m) result.markers[m].name = names[m];
  if (options.keep_series) {
    result.series.scene_time_ns.reserve(instant_count);
    result.series.error_m.assign(names.size(), std::vector<float>(instant_count, NAN));
    result.series.flags.assign(names.size(), std::vector<std::uint8_t>(instant_count, 0));
  }
  return result;
}

// What evaluate() adds up over the instants besides the counts an Evaluation holds.
struct Totals {
  explicit Totals(std::size_t markers) : sum2(markers, 0.0), last_id(markers, 0) {}
  std::vector<double> sum2;                                   // per marker: matched errors squared
  std::vector<std::int64_t> last_id;                          // per marker: track last matched (0: none)
  std::map<std::int64_t, std::size_t> last_marker;            // track id -> marker it last matched
  std::map<std::int64_t, std::pair<int, int>> track_matches;  // id -> (samples, matched)
  double total_sum2 = 0;
  std::size_t total_matched = 0;
};

// One instant's matching, indexed by marker and by record (k - begin).
struct InstantMatch {
  std::vector<bool> marker_taken;
  std::vector<bool> track_taken;
  std::vector<bool> near_a_marker;
};

// Greedy nearest pairs within the match distance, each marker and track used once; every pair's
// error and id switch is counted.
InstantMatch match_instant(const std::vector<const TrackRecord*>& sorted, Records records,
                           const std::vector<MarkerTruth>& truth, std::size_t instant,
                           const EvaluationOptions& options, Evaluation& result, Totals& totals) {
  const auto [begin, end] = records;
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  const double max_d2 = options.match_distance_m * options.match_distance_m;
  for (std::size_t m = 0; m < truth.size(); ++m) {
    if (!truth[m].valid) continue;
    for (std::size_t k = begin; k < end; ++k) {
      const double d2 = (sorted[k]->p - truth[m].p).squaredNorm();
      if (d2 < max_d2) pairs.emplace_back(std::sqrt(d2), m, k);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  InstantMatch match{std::vector<bool>(truth.size(), false), std::vector<bool>(end - begin, false),
                     std::vector<bool>(end - begin, false)};
  for (const auto& [d, m, k] : pairs) {
    match.near_a_marker[k - begin] = true;
    if (match.marker_taken[m] || match.track_taken[k - begin]) continue;
    match.marker_taken[m] = true;
    match.track_taken[k - begin] = true;
    auto& marker = result.markers[m];
    ++marker.tracked;
    totals.sum2[m] += d * d;
    totals.total_sum2 += d * d;
    ++totals.total_matched;
    marker.max_error_m = std::max(marker.max_error_m, d);
    const std::int64_t id = sorted[k]->id;
    if (totals.last_id[m] != 0 && totals.last_id[m] != id) {
      const auto before = totals.last_marker.find(id);
      marker.id_switches.push_back({sorted[k]->stamp_ns, totals.last_id[m], id,
                                    seconds_since_start(sorted[k]->stamp_ns, options.epoch_ns),
                                    before != totals.last_marker.end() && before->second != m});
    }
    totals.last_id[m] = id;
    totals.last_marker[id] = m;
    if (options.keep_series) result.series.error_m[m][instant] = static_cast<float>(d);
  }
  return match;
}

// Every marker with truth at this instant: a step, trackable or not, tracked or not.
void count_markers(const std::vector<MarkerTruth>& truth, const InstantMatch& match, Visibility& visibility,
                   TimeNs scene_time, std::size_t instant, const EvaluationOptions& options,
                   Evaluation& result) {
  for (std::size_t m = 0; m < truth.size(); ++m) {
    if (!truth[m].valid) continue;
    auto& marker = result.markers[m];
    ++marker.steps;
    const int cameras = visibility.cameras_showing(m, scene_time, options.trackable_window_ns);
    const bool trackable = cameras >= options.trackable_min_cameras;
    if (trackable) {
      ++marker.trackable;
      if (match.marker_taken[m]) ++marker.tracked_trackable;
    }
    if (cameras == options.trackable_min_cameras) {
      ++result.edge_trackable;
      if (match.marker_taken[m]) ++result.edge_tracked;
    }
    if (options.keep_series) {
      result.series.flags[m][instant] = static_cast<std::uint8_t>(
          EvaluationSeries::kHasTruth | (trackable ? EvaluationSeries::kTrackable : 0) |
          (match.marker_taken[m] ? EvaluationSeries::kTracked : 0));
    }
  }
}

// Every record at this instant: matched, false, or a duplicate near a marker.
void count_records(const std::vector<const TrackRecord*>& sorted, Records records, const InstantMatch& match,
                   Evaluation& result, Totals& totals) {
  const auto [begin, end] = records;
  for (std::size_t k = begin; k < end; ++k) {
    auto& counts = totals.track_matches[sorted[k]->id];
    ++counts.first;
    ++result.records;
    if (match.track_taken[k - begin]) {
      ++counts.second;
    } else {
      ++result.false_records;
      if (match.near_a_marker[k - begin]) ++result.duplicate_records;
    }
  }
}

// The figures over all instants: RMSEs, worst cases, switches and false tracks.
void summarise(const Totals& totals, const EvaluationOptions& options, Evaluation& result) {
  result.min_tracked_fraction = result.markers.empty() ? 0.0 : 1.0;
  for (std::size_t m = 0; m < result.markers.size(); ++m) {
    auto& marker = result.markers[m];
    marker.rmse_m =
        marker.tracked == 0 ? 0.0 : std::sqrt(totals.sum2[m] / static_cast<double>(marker.tracked));
    result.worst_marker_rmse_m = std::max(result.worst_marker_rmse_m, marker.rmse_m);
    result.max_error_m = std::max(result.max_error_m, marker.max_error_m);
    result.min_tracked_fraction = std::min(result.min_tracked_fraction, marker.tracked_fraction());
    result.id_switch_count += marker.id_switches.size();
    result.id_swap_count += static_cast<std::size_t>(std::count_if(
        marker.id_switches.begin(), marker.id_switches.end(), [](const IdSwitch& s) { return s.swap; }));
    result.trackable += marker.trackable;
    result.tracked_trackable += marker.tracked_trackable;
    if (marker.trackable > 0) result.min_coverage = std::min(result.min_coverage, marker.coverage());
  }
  result.rmse_m = totals.total_matched == 0
                      ? 0.0
                      : std::sqrt(totals.total_sum2 / static_cast<double>(totals.total_matched));
  result.track_ids = totals.track_matches.size();
  for (const auto& [id, counts] : totals.track_matches) {
    const auto [samples, matched] = counts;
    if (samples >= options.false_track_min_samples && 2 * matched < samples)
      result.false_tracks.push_back(id);
    if (matched < samples) {
      result.false_record_ids.push_back(
          {id, static_cast<std::size_t>(samples), static_cast<std::size_t>(samples - matched)});
    }
  }
}

}  // namespace

Evaluation evaluate(const Scene& scene, const std::vector<TrackRecord>& tracks,
                    const EvaluationOptions& options) {
  const std::vector<const TrackRecord*> sorted = sorted_by_stamp(tracks);
  const std::vector<Instant> instants = judged_instants(sorted, scene, options);
  Evaluation result = empty_evaluation(scene, options, instants.size());
  if (instants.empty()) {
    result.min_tracked_fraction = result.markers.empty() ? 0.0 : 1.0;
    for (const auto& marker : result.markers) {
      result.min_tracked_fraction = std::min(result.min_tracked_fraction, marker.tracked_fraction());
    }
    return result;
  }

  const TimeNs first_time = instants.front().first - options.epoch_ns;
  const TimeNs last_time = instants.back().first - options.epoch_ns;
  Visibility visibility(scene, first_time - options.trackable_window_ns, last_time);
  Totals totals(result.markers.size());
  TimeNs previous_time = first_time;
  for (std::size_t instant = 0; instant < instants.size(); ++instant) {
    const TimeNs scene_time = instants[instant].first - options.epoch_ns;
    result.max_instant_gap_ns = std::max(result.max_instant_gap_ns, scene_time - previous_time);
    previous_time = scene_time;
    ++result.instants;
    if (options.keep_series) result.series.scene_time_ns.push_back(scene_time);
    const auto truth = scene.markers_at(scene_time);
    const InstantMatch match =
        match_instant(sorted, instants[instant].second, truth, instant, options, result, totals);
    count_markers(truth, match, visibility, scene_time, instant, options, result);
    count_records(sorted, instants[instant].second, match, result, totals);
  }
  summarise(totals, options, result);
  return result;
}

std::string Evaluation::to_json() const {
  using Json = nlohmann::ordered_json;
  const auto coverage_or_null = [](std::size_t trackable, double coverage) {
    return trackable == 0 ? Json(nullptr) : Json(coverage);
  };
  Json j;
  j["instants"] = instants;
  j["track_ids"] = track_ids;
  j["rmse_mm"] = rmse_m * 1e3;
  j["max_error_mm"] = max_error_m * 1e3;
  j["worst_marker_rmse_mm"] = worst_marker_rmse_m * 1e3;
  j["min_tracked_fraction"] = min_tracked_fraction;
  j["trackable"] = trackable;
  j["tracked_trackable"] = tracked_trackable;
  j["coverage"] = coverage_or_null(trackable, coverage());
  j["min_coverage"] = coverage_or_null(trackable, min_coverage);
  j["edge_trackable"] = edge_trackable;
  j["edge_tracked"] = edge_tracked;
  j["edge_coverage"] = coverage_or_null(edge_trackable, edge_coverage());
  j["id_switches"] = id_switch_count;
  j["id_swaps"] = id_swap_count;
  j["records"] = records;
  j["false_records"] = false_records;
  j["false_record_fraction"] = false_record_fraction();
  j["duplicate_records"] = duplicate_records;
  j["false_tracks"] = false_tracks;
  j["false_record_ids"] = Json::array();
  for (const FalseRecords& ids : false_record_ids) {
    j["false_record_ids"].push_back(
        {{"id", ids.id}, {"records", ids.records}, {"false_records", ids.false_records}});
  }
  j["max_instant_gap_ms"] = static_cast<double>(max_instant_gap_ns) * 1e-6;

  j["id_switch_events"] = Json::array();
  for (const auto& [s, name] : switches_in_time_order(markers)) {
    j["id_switch_events"].push_back({{"marker", *name},
                                     {"stamp_ns", s->stamp_ns},
                                     {"t_s", s->t_s},
                                     {"from", s->from_id},
                                     {"to", s->to_id},
                                     {"swap", s->swap}});
  }

  j["options"] = {{"epoch_ns", options.epoch_ns},
                  {"warmup_s", ns_to_seconds(options.warmup_ns)},
                  {"until_s", options.until_ns == std::numeric_limits<TimeNs>::max()
                                  ? Json(nullptr)
                                  : Json(ns_to_seconds(options.until_ns))},
                  {"match_distance_mm", options.match_distance_m * 1e3},
                  {"trackable_window_ms", static_cast<double>(options.trackable_window_ns) * 1e-6},
                  {"trackable_min_cameras", options.trackable_min_cameras}};

  j["markers"] = Json::array();
  for (const auto& marker : markers) {
    Json m;
    m["name"] = marker.name;
    m["rmse_mm"] = marker.rmse_m * 1e3;
    m["max_error_mm"] = marker.max_error_m * 1e3;
    m["tracked_fraction"] = marker.tracked_fraction();
    m["steps"] = marker.steps;
    m["tracked"] = marker.tracked;
    m["trackable"] = marker.trackable;
    m["tracked_trackable"] = marker.tracked_trackable;
    m["coverage"] = coverage_or_null(marker.trackable, marker.coverage());
    m["id_switches"] = Json::array();
    for (const auto& s : marker.id_switches) {
      m["id_switches"].push_back(
          {{"stamp_ns", s.stamp_ns}, {"t_s", s.t_s}, {"from", s.from_id}, {"to", s.to_id}, {"swap", s.swap}});
    }
    j["markers"].push_back(m);
  }
  return j.dump(2);
}

std::string Evaluation::summary() const {
  std::ostringstream out;
  char line[320];
  std::snprintf(line, sizeof line, "%-24s %10s %10s %9s %9s %10s\n", "marker", "RMSE mm", "max mm", "tracked",
                "coverage", "ID switch");
  out << line;
  for (const auto& marker : markers) {
    char coverage[16] = "      -";
    if (marker.trackable > 0) std::snprintf(coverage, sizeof coverage, "%7.1f%%", 100.0 * marker.coverage());
    std::snprintf(line, sizeof line, "%-24s %10.3f %10.3f %8.1f%% %9s %10zu\n", marker.name.c_str(),
                  marker.rmse_m * 1e3, marker.max_error_m * 1e3, 100.0 * marker.tracked_fraction(), coverage,
                  marker.id_switches.size());
    out << line;
  }
  // The first switches in time order; indented, so that only the table's rows start with a marker
  // name.
  constexpr std::size_t kListedSwitches = 20;
  const auto switches = switches_in_time_order(markers);
  for (std::size_t i = 0; i < switches.size() && i < kListedSwitches; ++i) {
    const auto& [s, name] = switches[i];
    std::snprintf(line, sizeof line, "  ID switch at %.3f s: %s %lld -> %lld%s\n", s->t_s, name->c_str(),
                  static_cast<long long>(s->from_id), static_cast<long long>(s->to_id),
                  s->swap ? " (another marker's track)" : "");
    out << line;
  }
  if (switches.size() > kListedSwitches)
    out << "  ... and " << switches.size() - kListedSwitches << " more ID switches\n";
  std::snprintf(line, sizeof line,
                "  records %zu, false %zu (%.2f%%; %zu duplicates of tracked markers) from %zu track ids; "
                "trackable marker-instants %zu, tracked %zu (shown by exactly %d cameras %zu, tracked %zu); "
                "longest silence %.1f ms\n",
                records, false_records, 100.0 * false_record_fraction(), duplicate_records,
                false_record_ids.size(), trackable, tracked_trackable, options.trackable_min_cameras,
                edge_trackable, edge_tracked, static_cast<double>(max_instant_gap_ns) * 1e-6);
  out << line;
  char coverage_text[48] = "-";
  if (trackable > 0) {
    std::snprintf(coverage_text, sizeof coverage_text, "%.2f%% (min %.1f%%)", 100.0 * coverage(),
                  100.0 * min_coverage);
  }
  std::snprintf(line, sizeof line,
                "all: RMSE %.3f mm, max %.3f mm, worst marker %.3f mm, min tracked %.1f%%, coverage %s, "
                "ID switches %zu (swaps %zu), false records %.2f%%, false tracks %zu, instants %zu\n",
                rmse_m * 1e3, max_error_m * 1e3, worst_marker_rmse_m * 1e3, 100.0 * min_tracked_fraction,
                coverage_text, id_switch_count, id_swap_count, 100.0 * false_record_fraction(),
                false_tracks.size(), instants);
  out << line;
  return out.str();
}

PoseEvaluation evaluate_poses(const Scene& scene, const std::vector<PoseRecord>& poses,
                              const EvaluationOptions& options) {
  constexpr TimeNs kBin = 10'000'000;
  // Bodies, then the rigs of moving cameras (inside-out poses are judged like bodies').
  std::vector<std::string> names;
  for (const auto& definition : scene.body_definitions()) names.push_back(definition.name);
  for (const auto& rig : scene.rig_names()) names.push_back(rig);
  const TimeNs first = options.warmup_ns, last = std::min(scene.duration_ns(), options.until_ns);
  const std::size_t bins = last > first ? static_cast<std::size_t>((last - first) / kBin) + 1 : 0;
  struct Sums {
    double p2 = 0, a2 = 0;
    std::size_t correct = 0;
    std::vector<char> bins;
  };
  std::map<std::string, std::size_t> index;
  PoseEvaluation evaluation;
  std::vector<Sums> sums(names.size());
  for (std::size_t b = 0; b < names.size(); ++b) {
    index[names[b]] = b;
    evaluation.bodies.push_back({names[b]});
    sums[b].bins.assign(bins, 0);
  }
  for (const PoseRecord& pose : poses) {
    const auto found = index.find(pose.body);
    if (found == index.end()) continue;
    const TimeNs t = pose.stamp_ns - options.epoch_ns;
    if (t < first || t > last) continue;
    const std::size_t b = found->second;
    BodyEvaluation& e = evaluation.bodies[b];
    ++e.records;
    RigidTransform truth;
    for (const BodyTruth& body : scene.bodies_at(t + pose.horizon_ns))
      if (body.name == pose.body) truth = body.T_world_body;
    const Eigen::Quaterniond q(pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z());
    const double dp = (pose.p - truth.t).norm();
    const double da = q.normalized().angularDistance(truth.q) * 180.0 / M_PI;
    if (!(dp <= 0.02 && da <= 5.0)) {
      ++e.wrong;
      continue;
    }
    Sums& s = sums[b];
    s.p2 += dp * dp;
    s.a2 += da * da;
    ++s.correct;
    e.max_m = std::max(e.max_m, dp);
    e.max_deg = std::max(e.max_deg, da);
    s.bins[static_cast<std::size_t>((t - first) / kBin)] = 1;
  }
  for (std::size_t b = 0; b < names.size(); ++b) {
    BodyEvaluation& e = evaluation.bodies[b];
    const Sums& s = sums[b];
    if (s.correct > 0) {
      e.rmse_m = std::sqrt(s.p2 / static_cast<double>(s.correct));
      e.rmse_deg = std::sqrt(s.a2 / static_cast<double>(s.correct));
    }
    if (bins > 0)
      e.tracked_fraction =
          static_cast<double>(std::count(s.bins.begin(), s.bins.end(), 1)) / static_cast<double>(bins);
  }
  return evaluation;
}

std::string PoseEvaluation::summary() const {
  std::ostringstream out;
  char line[192];
  std::snprintf(line, sizeof line, "%-20s %10s %10s %10s %10s %9s %8s\n", "body", "RMSE mm", "max mm",
                "RMSE deg", "max deg", "tracked", "wrong");
  out << line;
  for (const auto& e : bodies) {
    std::snprintf(line, sizeof line, "%-20s %10.3f %10.3f %10.4f %10.4f %8.2f%% %8zu\n", e.body.c_str(),
                  e.rmse_m * 1e3, e.max_m * 1e3, e.rmse_deg, e.max_deg, 100.0 * e.tracked_fraction, e.wrong);
    out << line;
  }
  return out.str();
}

std::string PoseEvaluation::to_json() const {
  nlohmann::json json = nlohmann::json::array();
  for (const auto& e : bodies) {
    json.push_back({{"body", e.body},
                    {"records", e.records},
                    {"wrong", e.wrong},
                    {"rmse_mm", e.rmse_m * 1e3},
                    {"max_mm", e.max_m * 1e3},
                    {"rmse_deg", e.rmse_deg},
                    {"max_deg", e.max_deg},
                    {"tracked", e.tracked_fraction}});
  }
  return nlohmann::json{{"bodies", json}}.dump(2);
}

}  // namespace panoptes::estimator
