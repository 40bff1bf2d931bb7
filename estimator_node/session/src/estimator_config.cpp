// SPDX-License-Identifier: Apache-2.0
// EstimatorConfig <-> YAML. One description of the fields (visit_config) drives both the reader
// and the writer, so every key that is printed can be read back and none is forgotten.
#include "panoptes/session/estimator_config.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "panoptes/config.h"
#include "panoptes/labelling/segment_kinematics.h"

namespace panoptes::session {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Shortest text that reads back as exactly `value`.
std::string format_double(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// Allowed values of a number: [low, high], or (low, high] with `low_open`.
struct Limits {
  double low = -kInfinity;
  double high = kInfinity;
  bool low_open = false;

  bool admits(double value) const {
    return std::isfinite(value) && (low_open ? value > low : value >= low) && value <= high;
  }
  std::string describe() const {
    if (high == kInfinity)
      return std::string("must be a finite number ") + (low_open ? "> " : ">= ") + format_double(low);
    return std::string("must be a number in ") + (low_open ? "(" : "[") + format_double(low) + ", " +
           format_double(high) + "]";
  }
};
constexpr Limits kPositive{0.0, kInfinity, true};
constexpr Limits kNonNegative{0.0, kInfinity, false};
constexpr Limits between(double low, double high) {
  return {low, high, false};
}

constexpr long long kHourNs = 3600LL * 1'000'000'000LL;

// Reads fields from a YAML map; keys left out keep their values.
class FieldReader {
 public:
  explicit FieldReader(const YamlReader& reader) : reader_(reader) {
    if (!reader_.node().IsMap() && !reader_.node().IsNull()) reader_.fail("", "expected a map");
  }

  void number(const char* key, double& value, Limits limits, const char* /*doc*/) {
    keys_.emplace_back(key);
    if (!reader_.has(key)) return;
    const double read = reader_.get_double(key);
    if (!limits.admits(read)) reader_.fail(key, limits.describe());
    value = read;
  }

  template <class Integer>
  void integer(const char* key, Integer& value, long long low, long long high, const char* /*doc*/) {
    keys_.emplace_back(key);
    if (!reader_.has(key)) return;
    const long long read = reader_.get_int(key);
    if (read < low || read > high)
      reader_.fail(key, "must be an integer in [" + std::to_string(low) + ", " + std::to_string(high) + "]");
    value = static_cast<Integer>(read);
  }

  void flag(const char* key, bool& value, const char* /*doc*/) {
    keys_.emplace_back(key);
    value = reader_.get_bool(key, value);
  }

  // `check` returns "" for an admissible value, else why not.
  void text(const char* key, std::string& value, std::string (*check)(const std::string&),
            const char* /*doc*/) {
    keys_.emplace_back(key);
    if (!reader_.has(key)) return;
    std::string read = reader_.get_string(key);
    if (const std::string reason = check(read); !reason.empty()) reader_.fail(key, reason);
    value = std::move(read);
  }

  // A list of non-empty strings (a single string is a list of one).
  void names(const char* key, std::vector<std::string>& value, const char* /*doc*/) {
    keys_.emplace_back(key);
    if (!reader_.has(key)) return;
    if (reader_.node()[key].IsScalar()) {
      value = {reader_.get_string(key)};
      if (value.front().empty()) reader_.fail(key, "must not be empty");
      return;
    }
    std::vector<std::string> read;
    for (const YamlReader& item : reader_.sequence(key)) {
      if (!item.node().IsScalar() || item.node().Scalar().empty())
        item.fail("", "must be a non-empty string");
      read.push_back(item.node().Scalar());
    }
    value = std::move(read);
  }

  template <class Visit>
  void section(const char* key, const char* /*doc*/, Visit&& visit) {
    keys_.emplace_back(key);
    if (!reader_.has(key)) return;
    FieldReader child(reader_.child(key));
    visit(child);
    child.finish();
  }

  // A key read elsewhere (`surface`: estimator_node's surface mode, docs/surface.md).
  void elsewhere(const char* key) { keys_.emplace_back(key); }

  // Unknown keys are errors: a misspelt key must not silently leave a default in place.
  void finish() const { reader_.expect_only(keys_); }

 private:
  YamlReader reader_;
  std::vector<std::string> keys_;
};

// Writes fields as YAML, one `key: value  # doc` line each.
class FieldWriter {
 public:
  void number(const char* key, double& value, Limits, const char* doc) {
    line(key, format_double(value), doc);
  }

  template <class Integer>
  void integer(const char* key, Integer& value, long long, long long, const char* doc) {
    line(key, std::to_string(value), doc);
  }

  void flag(const char* key, bool& value, const char* doc) { line(key, value ? "true" : "false", doc); }

  void text(const char* key, std::string& value, std::string (*)(const std::string&), const char* doc) {
    line(key, quote(value), doc);
  }

  void names(const char* key, std::vector<std::string>& value, const char* doc) {
    std::string list = "[";
    for (const auto& name : value) list += (list.size() > 1 ? ", " : "") + quote(name);
    line(key, list + "]", doc);
  }

  template <class Visit>
  void section(const char* key, const char* doc, Visit&& visit) {
    line(key, "", doc);
    indent_ += "  ";
    visit(*this);
    indent_.resize(indent_.size() - 2);
  }

  const std::string& text() const { return text_; }

 private:
  static std::string quote(const std::string& value) {
    YAML::Emitter quoted;  // always quoted: "" and values such as "true" or "1" stay strings
    quoted << YAML::DoubleQuoted << value;
    return quoted.c_str();
  }

  void line(const char* key, const std::string& value, const char* doc) {
    text_ += indent_ + key + ":" + (value.empty() ? "" : " " + value);
    if (doc && *doc) text_ += std::string("  # ") + doc;
    text_ += "\n";
  }

  std::string indent_;
  std::string text_;
};

}  // namespace

std::string check_frames_mode(const std::string& mode) {
  return mode == "auto" || mode == "per-camera" || mode == "fixed"
             ? ""
             : "'" + mode + "': must be auto, per-camera or fixed";
}

std::string check_axis_name(const std::string& axis) {
  return labelling::axis_from_name(axis) ? "" : "'" + axis + "': must be an axis (+x, -x, +y, -y, +z or -z)";
}

std::string check_continuous_calibration(const std::string& mode) {
  if (mode == "off" || mode == "detect" || mode == "correct") return "";
  return "'" + mode + "': must be off, detect or correct";
}

namespace {

template <class Fields>
void visit_node(Fields& f, NodeSettings& o) {
  f.integer("inbox_capacity", o.inbox_capacity, 1, 1 << 24, "frames waiting to be ordered by stamp");
  f.number("latency_window_ms", o.latency_window_ms, between(0, 10000),
           "how long frames wait to be ordered by stamp (live, --replay-arrival)");
  f.flag("predictions", o.predictions, "live: publish predicted windows");
  f.number("prediction_margin_px", o.prediction_margin_px, between(0, 1000),
           "live: pixels added around each predicted gate");
  f.number("prediction_horizon_ms", o.prediction_horizon_ms, between(0, 1000),
           "body poses are published this far ahead of the newest frame (seed 000 Ch. 5)");
  f.number("status_period_s", o.status_period_s, kPositive, "live: seconds between status messages");
  f.number("bodies_poll_s", o.bodies_poll_s, kPositive,
           "live: how often the bodies and calibration files are checked for changes");
  f.text("frames", o.frames, check_frames_mode,
         "per-camera: a frame per camera frame; fixed: frame_rate_hz; auto: fixed live, per-camera records "
         "offline (docs/frames.md)");
  f.integer("frame_rate_hz", o.frame_rate_hz, 1, 10000, "rate of fixed-rate frames");
  f.number("camera_lost_after_s", o.camera_lost_after_s, between(0.01, 3600),
           "live: a camera without a frame for this long (wall time) is lost");
  f.integer("realtime_priority", o.realtime_priority, 0, 99,
            "live: SCHED_FIFO priority of the estimator thread (0: normal; needs CAP_SYS_NICE)");
}

template <class Fields>
void visit_screen(Fields& f, estimator::FrameScreenOptions& o) {
  f.integer("max_blobs", o.max_blobs, 1, 1 << 24, "frames with more blobs are rejected");
  f.integer("max_stamp_skew_ns", o.max_stamp_skew_ns, 1, kHourNs,
            "|stamp - reference| beyond this rejects a frame");
  f.integer("max_future_ns", o.max_future_ns, 0, kHourNs,
            "live: how far a stamp may lie ahead of the wall clock");
  f.number("max_abs_coordinate_px", o.max_abs_coordinate_px, kPositive, "blobs farther outside are garbage");
  f.integer("max_camera_id_length", o.max_camera_id_length, 1, 65536, "longer camera ids are rejected");
}

template <class Fields>
void visit_initiator(Fields& f, estimator::InitiatorOptions& o) {
  f.integer("window_ns", o.window_ns, 0, kHourNs, "other cameras' tracklets this recent may pair");
  f.number("link_radius_px", o.link_radius_px, kPositive,
           "a blob continues its camera's tracklet within this");
  f.number("epipolar_px", o.epipolar_px, kPositive, "distance to the epipolar line, beyond time alignment");
  f.number("reprojection_px", o.reprojection_px, kPositive, "every supporting view must reproject this well");
  f.number("max_image_speed_px_s", o.max_image_speed_px_s, kNonNegative,
           "allowance for a partner without a pixel velocity yet");
  f.integer("unaligned_max_dt_ns", o.unaligned_max_dt_ns, 0, kHourNs,
            "... which pairs only this close in time");
  f.number("min_depth_m", o.min_depth_m, kNonNegative, "points closer to a camera are rejected");
  f.flag("partial_velocity", o.partial_velocity,
         "near a fast track, a birth seen a frame before by one view only takes that view's velocity across "
         "its line of sight");
}

template <class Fields>
void visit_identification(Fields& f, estimator::IdentificationOptions& o) {
  f.number("tolerance_floor_m", o.tolerance_floor_m, kNonNegative,
           "distances agree within floor + sigmas * sigma(distance)");
  f.number("tolerance_sigmas", o.tolerance_sigmas, kNonNegative, "see tolerance_floor_m");
  f.number("max_rms_m", o.max_rms_m, kPositive, "the fitted pose must explain the points this well");
  f.integer("min_markers", o.min_markers, 3, 1024, "markers that must match");
  f.integer("max_points", o.max_points, 3, 1 << 20, "points offered beyond this are ignored");
  f.integer("max_clique_steps", o.max_clique_steps, 1, 1LL << 40, "bound on the clique search");
}

template <class Fields>
void visit_led_marker(Fields& f, estimator::LedMarkerOptions& o) {
  f.number("line_tolerance", o.line_tolerance, kPositive, "collinearity tolerance (seed 004)");
  f.number("cross_ratio_tolerance", o.cross_ratio_tolerance, kPositive, "relative cross-ratio tolerance");
  f.number("cross_ratio_sigmas", o.cross_ratio_sigmas, kNonNegative, "... or this many sigmas of it");
  f.integer("seed", o.seed, 0, std::numeric_limits<long long>::max(), "k-means initialisation");
  f.integer("kmeans_iterations", o.kmeans_iterations, 1, 10000, "k-means iterations per clustering");
  f.flag("retry_extra_cluster", o.retry_extra_cluster, "retry with one more cluster for partial markers");
}

template <class Fields>
void visit_bodies(Fields& f, estimator::BodyTrackerOptions& o) {
  f.section("noise", "body motion model", [&](auto& s) {
    s.number("jerk", o.noise.jerk, kPositive, "sigma^2 of white jerk, m^2/s^5");
    s.number("angular_accel", o.noise.angular_accel, kPositive,
             "sigma^2 of white angular acceleration, rad^2/s^3");
    s.number("angular_jerk", o.noise.angular_jerk, kNonNegative,
             "sigma^2 of white angular jerk, rad^2/s^5 (0: constant angular velocity)");
  });
  f.number("measurement_noise_px", o.measurement_noise_px, kPositive, "sigma of a marker's centroid, px");
  f.number("gate_chi2", o.gate_chi2, kPositive, "chi^2_2 gate for a marker's blob");
  f.section("identification", "bodies from 3D points",
            [&](auto& s) { visit_identification(s, o.identification); });
  f.integer("identify_interval_ns", o.identify_interval_ns, 0, kHourNs,
            "how often untracked bodies are looked for");
  f.integer("verify_interval_ns", o.verify_interval_ns, 0, kHourNs, "how often a tracked body is checked");
  f.number("verify_position_m", o.verify_position_m, kPositive,
           "identification and EKF disagree more: re-identify");
  f.number("verify_angle_rad", o.verify_angle_rad, kPositive, "... or in angle, rad");
  f.integer("lost_after_ns", o.lost_after_ns, 0, kHourNs, "no marker update for this long: lost");
  f.number("max_nis", o.max_nis, kPositive, "moving average of a marker's d^2 above this: lost");
  f.number("process_noise_max_scale", o.process_noise_max_scale, between(1.0, 1e6),
           "adaptive process noise: a body's noise is scaled by at most this (1: off)");
  f.number("process_noise_adapt_gain", o.process_noise_adapt_gain, kPositive,
           "adaptive process noise: the scale changes by exp(gain x innovation correlation) per update");
  f.number("process_noise_adapt_weight", o.process_noise_adapt_weight, between(1e-6, 1.0),
           "adaptive process noise: weight of an update in the innovation correlation's averages");
  f.number("process_noise_adapt_correlation", o.process_noise_adapt_correlation, between(-1.0, 1.0),
           "adaptive process noise: innovation correlation above this raises the scale, below lowers it");
  f.number("init_position_sigma_m", o.init_position_sigma_m, kPositive,
           "initial 1-sigma of an acquired body, m");
  f.number("init_velocity_sigma_mps", o.init_velocity_sigma_mps, kPositive, "m/s");
  f.number("init_accel_sigma_mps2", o.init_accel_sigma_mps2, kPositive, "m/s^2");
  f.number("init_angle_sigma_rad", o.init_angle_sigma_rad, kPositive, "rad");
  f.number("init_angular_velocity_sigma", o.init_angular_velocity_sigma, kPositive, "rad/s");
  f.number("init_angular_accel_sigma", o.init_angular_accel_sigma, kPositive, "rad/s^2");
  f.integer("quality_window_ns", o.quality_window_ns, 0, kHourNs,
            "BodyPose quality: markers seen in this window");
  f.integer("smoothing_ns", o.smoothing_ns, 0, kNsPerSecond,
            "poses reported this far behind the newest frame, fixed-lag smoothed (0: off)");
  f.section("led_marker", "7-LED markers (seed 004)", [&](auto& s) { visit_led_marker(s, o.led_marker); });
}

template <class Fields>
void visit_calibration(Fields& f, estimator::CalibrationHealthOptions& o) {
  f.text("mode", o.mode, check_continuous_calibration,
         "off | detect: quarantine a camera whose residuals are biased | correct: and re-estimate its pose");
  f.integer("resection_frames", o.resection_frames, 6, 1 << 16,
            "correct: monitored frames of a quarantined camera its new pose is estimated from");
  f.integer("resection_retry_ns", o.resection_retry_ns, 0, kHourNs,
            "correct: not determined: tried again after");
  f.number("max_correction_deg", o.resection.max_rotation_change_deg, kPositive,
           "correct: a bump correction turning the camera more than this is not applied ...");
  f.number("max_correction_mm", o.resection.max_translation_change_mm, kPositive,
           "... nor one moving it more");
  f.flag("follow_drift", o.follow_drift, "correct: refine the cameras in use too (slow drift)");
  f.number("refine_max_change_deg", o.refine_max_change_deg, kPositive,
           "a refinement turning a camera in use more than this is not applied ...");
  f.number("refine_max_change_mm", o.refine_max_change_mm, kPositive, "... nor one moving it more");
  f.integer("refine_sample_interval_ns", o.refine_sample_interval_ns, 0, kHourNs,
            "correct, follow_drift: one monitored frame of a camera in use this often ...");
  f.integer("refine_frames", o.refine_frames, 6, 1 << 16, "... and a refinement from this many of them");
  f.integer("settle_refine_ns", o.settle_refine_ns, 0, kHourNs,
            "after a bump's correction, one more refinement from every monitored frame this long (0: none)");
  f.number("refine_max_rotation_sigma_deg", o.refine_max_rotation_sigma_deg, kPositive,
           "a refinement is applied only when determined this well ...");
  f.number("refine_max_translation_sigma_mm", o.refine_max_translation_sigma_mm, kPositive, "... and this");
  f.number("refine_significance", o.refine_significance, kNonNegative,
           "... and it moves the camera by more than this many sigma");
  f.number("refine_min_rotation_deg", o.refine_min_rotation_deg, kNonNegative,
           "... and by more than this rotation ...");
  f.number("refine_min_translation_mm", o.refine_min_translation_mm, kNonNegative, "... or this translation");
  f.integer("refine_anchored_frames", o.refine_anchored_frames, 6, 1 << 16,
            "refine_frames when anchors are given");
  f.number("refine_anchored_min_rotation_deg", o.refine_anchored_min_rotation_deg, kNonNegative,
           "the rotation's floor when anchors are given");
  f.number("anchor_weight", o.anchor_weight, kPositive, "an anchor's residual weighs this many tracks'");
  f.number("anchor_radius_m", o.anchor_radius_m, kPositive, "tracks this near an anchor are left out");
  f.number("refine_centre_prior_mm", o.refine_centre_prior_mm, kNonNegative,
           "1-sigma prior that a refined camera's centre stays (0: none)");
  f.integer("window_ns", o.window_ns, 1'000'000, kHourNs, "residuals this recent are judged");
  f.integer("sample_interval_ns", o.sample_interval_ns, 0, kHourNs,
            "one residual per track and camera this often");
  f.integer("min_samples", o.min_samples, 3, 1 << 24, "fewer residuals in a region: not judged");
  f.number("false_alarm", o.false_alarm, between(1e-300, 0.5), "alpha per judgement (regions share it)");
  f.number("min_bias_px", o.min_bias_px, kPositive, "a significant bias below this is only reported");
  f.number("release_fraction", o.release_fraction, between(0, 1),
           "released when every bias < this x min_bias_px");
  f.number("release_p", o.release_p, between(0, 1), "... or p above this, for a full window");
  f.number("search_px", o.search_px, kPositive, "a track's blob is the nearest within this");
  f.number("unique_ratio", o.unique_ratio, between(1, 1000), "... and the next is this much farther");
  f.number("isolation_px", o.isolation_px, kNonNegative, "no other track predicted this close");
  f.number("max_predicted_sigma_px", o.max_predicted_sigma_px, kPositive, "prediction at least this good");
  f.number("min_seen_fraction", o.min_seen_fraction, between(0, 1),
           "fewer predictions with a blob in the gate: quarantined");
  f.number("release_seen_fraction", o.release_seen_fraction, between(0, 1), "... released above this share");
  f.integer("min_blind_predictions", o.min_blind_predictions, 1, 1 << 24,
            "predictions needed to judge the share");
  f.number("max_explained_blob_fraction", o.max_explained_blob_fraction, between(0, 1),
           "... and fewer of its blobs within search_px of a track");
  f.integer("min_other_cameras", o.min_other_cameras, 1, 64, "other cameras that updated the track recently");
  f.integer("other_camera_window_ns", o.other_camera_window_ns, 0, kHourNs, "... within this");
}

// The tracker's keys for markers that one camera alone sees (docs/estimator.md, issue 35 item 3),
// in visit_tracker's order.
template <class Fields>
void visit_one_view_tracks(Fields& f, estimator::TrackerOptions& o) {
  f.flag("reanchor_one_view_tracks", o.reanchor_one_view_tracks,
         "a track only one camera updated for 30 ms moves where that camera's blob and a second camera's "
         "put its marker (within reacquire_max_seen_distance_m of its last two-camera position, or 0.1 m "
         "of where its neighbours carried it), while another camera's applied frame missed it");
  f.number("return_velocity_cap_mps", o.return_velocity_cap_mps, kNonNegative,
           "a second camera's update after 30 ms of one camera's changes a track's velocity by at most "
           "this, m/s, unless fast (0: off)");
  f.integer("one_view_velocity_time_constant_ns", o.one_view_velocity_time_constant_ns, 0, kHourNs,
            "a track one camera alone has updated for 10 ms while another camera's frame missed it: its "
            "velocity along that camera's ray decays with this time constant (0: off, constant velocity)");
  f.number("one_view_carried_sigma_m", o.one_view_carried_sigma_m, kNonNegative,
           "... and its depth along that ray is measured where its neighbours carried it (within 3 cm of "
           "the ray), with this sigma, m (0: off)");
  f.integer("ray_twin_wait_ns", o.ray_twin_wait_ns, 0, kHourNs,
            "two tracks one camera alone updates and sees within 6 px of each other: a blob of another "
            "camera that both gate is left to neither for up to this long (0: off)");
  f.number("blob_owner_px", o.blob_owner_px, kNonNegative,
           "a track one camera alone updates, its depth uncertain, takes no blob of another camera that "
           "continues (within this, px) a blob another track took there (0: off)");
  f.number("return_max_seen_distance_m", o.return_max_seen_distance_m, kNonNegative,
           "... and a blob of another camera only if the update puts it within this of its last "
           "two-camera position, or of where its velocity then carries it, plus 3 m/s (or its top speed) "
           "since, m (0: off; fast tracks exempt)");
  f.number("return_max_carried_distance_m", o.return_max_carried_distance_m, kNonNegative,
           "... and none whose update puts it further than this from where its neighbours carried it "
           "since its last two-camera update, m (0: off; fast tracks exempt; only an anchor taken 0.5 s "
           "after its birth or later, its point not within 5 cm of another track)");
  f.number("return_fresh_max_jump_m", o.return_fresh_max_jump_m, kNonNegative,
           "... and a blob of another camera that continues no blob of that camera's previous frame "
           "(within 20 px) only if the update moves it at most this far, or to within 0.15 m of where "
           "its neighbours carried it, m (0: off; fast tracks and tracks younger than 0.5 s at their "
           "anchor exempt)");
}

// A track's life: its confirmation, and when it is deleted.
template <class Fields>
void visit_track_lifecycle(Fields& f, estimator::TrackerOptions& o) {
  f.integer("confirm_cameras", o.confirm_cameras, 2, 64, "distinct cameras that confirm a track ...");
  f.integer("confirm_updates", o.confirm_updates, 1, 1 << 20, "... or this many updates from at least two");
  f.integer("tentative_max_misses", o.tentative_max_misses, 1, 1 << 20,
            "tentative track unseen this often: ghost");
  f.number("tentative_max_nis", o.tentative_max_nis, kPositive, "moving average of d^2 above this: deleted");
  f.number("confirmed_max_nis", o.confirmed_max_nis, kPositive, "... for a confirmed track");
  f.integer("coast_after_ns", o.coast_after_ns, 0, kHourNs, "no update for this long: coasting");
  f.integer("delete_after_ns", o.delete_after_ns, 0, kHourNs, "no update for this long: deleted");
  f.integer("tentative_delete_after_ns", o.tentative_delete_after_ns, 0, kHourNs,
            "... for a tentative track");
  f.integer("one_view_ghost_ns", o.one_view_ghost_ns, 0, kHourNs,
            "a track never published that no two cameras updated together for this long, while another "
            "camera's frame had it in view and missed it: deleted as a ghost (0: off)");
}

template <class Fields>
void visit_tracker(Fields& f, estimator::TrackerOptions& o) {
  f.number("process_noise", o.process_noise, kPositive,
           "sigma^2 of white acceleration, m^2/s^3 (seed 003 A.48)");
  f.number("process_noise_max_scale", o.process_noise_max_scale, kPositive,
           "adaptive process noise: a track's sigma^2 grows from its innovations up to this times "
           "process_noise (1: off)");
  f.number("process_noise_nis_target", o.process_noise_nis_target, kPositive,
           "adaptive process noise: averaged d^2 above this raises a track's sigma^2");
  f.integer("process_noise_adapt_decay_ns", o.process_noise_adapt_decay_ns, 1, kHourNs,
            "adaptive process noise: time constant of the return to process_noise");
  f.flag(
      "recover_manoeuvres", o.recover_manoeuvres,
      "adaptive process noise: a confirmed track that missed takes the one blob left in its manoeuvre gate");
  f.flag("rejoin_fast_tracks", o.rejoin_fast_tracks,
         "adaptive process noise: a new track takes the id of the one fast track lost nearby moments ago");
  f.number("rejoin_rigid_margin_m", o.rejoin_rigid_margin_m, kNonNegative,
           "a fast track's id returns only this close to its distance from its rigid partner (0: off)");
  f.number("partner_update_margin_m", o.partner_update_margin_m, kNonNegative,
           "a fast track takes no blob that would put it further than this from its distance to its rigid "
           "partner (0: off)");
  f.flag("delete_runaway_tracks", o.delete_runaway_tracks,
         "a track made fast by one camera's updates (dragged along its ray) is deleted");
  visit_one_view_tracks(f, o);
  f.number("fast_process_noise_scale", o.fast_process_noise_scale, kNonNegative,
           "adaptive process noise: a fast track (above 10 m/s: a swung or thrown object) keeps this times "
           "process_noise (0: off)");
  f.integer("fast_hold_ns", o.fast_hold_ns, 0, kHourNs,
            "... until this long after its last update above 10 m/s");
  f.number("fast_isolated_process_noise_scale", o.fast_isolated_process_noise_scale, kNonNegative,
           "... or this times process_noise while no other confirmed track is within fast_isolation_m "
           "(0: off)");
  f.number("fast_isolation_m", o.fast_isolation_m, kNonNegative, "... that distance, m");
  f.integer("fast_acceleration_time_constant_ns", o.fast_acceleration_time_constant_ns, 0, kHourNs,
            "an isolated fast track predicts with its acceleration: its velocity's change per update, "
            "low-passed with this time constant (0: off, constant velocity)");
  f.number("measurement_noise_px", o.measurement_noise_px, kPositive, "sigma of a centroid, px");
  f.number("gate_chi2", o.gate_chi2, kPositive, "verify region (seed 003 2.2.3.2)");
  f.section("init", "pairing of unmatched blobs into new points",
            [&](auto& s) { visit_initiator(s, o.init); });
  f.number("init_position_sigma_m", o.init_position_sigma_m, kPositive, "initial 1-sigma of a new point, m");
  f.number("init_velocity_sigma_mps", o.init_velocity_sigma_mps, kPositive, "velocity unknown at initiation");
  f.number("init_measured_velocity_sigma_mps", o.init_measured_velocity_sigma_mps, kPositive,
           "velocity from the tracklets' pixel velocities ...");
  f.number("init_velocity_relative_sigma", o.init_velocity_relative_sigma, kNonNegative,
           "... at least this fraction of the measured speed (fast markers)");
  visit_track_lifecycle(f, o);
  f.number("publish_max_sigma_m", o.publish_max_sigma_m, kNonNegative,
           "confirmed tracks are published while their position 1-sigma is within this, m (0: always)");
  f.number("fast_publish_max_sigma_m", o.fast_publish_max_sigma_m, kNonNegative,
           "... a fast track (above 10 m/s) while within this, m (0: publish_max_sigma_m)");
  f.number("fast_publish_innovation_px", o.fast_publish_innovation_px, kNonNegative,
           "... or a fast track while every camera that updated it in the last 10 ms found its blob within "
           "this of the prediction, px, up to 2.5 ms after a two-camera update (0: off)");
  f.number("publish_max_innovation_px", o.publish_max_innovation_px, kNonNegative,
           "a track (not fast) that two or more cameras updated in the last 10 ms is published only while "
           "each finds its blobs within this of the predictions, px, on a moving average (0: off)");
  f.flag("dispute_odd_views", o.dispute_odd_views,
         "a track whose views disagree gives up for 100 ms the one view that misses the point its other "
         "views agree on, when that view's blob pairs with another camera's unmatched blob (a neighbour's)");
  f.number("merge_distance_m", o.merge_distance_m, kNonNegative,
           "two tracks closer than this are one marker");
  f.number("reacquire_sigma_m", o.reacquire_sigma_m, kNonNegative,
           "a confirmed track lost for 10 ms and 4 frames, predicted less certain than this (1-sigma, m), "
           "takes no blob; "
           "a new track confirmed near it takes its id (0: off)");
  f.number("reacquire_distance_ratio", o.reacquire_distance_ratio, kNonNegative,
           "... and only when the next held-back track is this many times farther (m; 1 or less: no test)");
  f.number("reacquire_max_seen_distance_m", o.reacquire_max_seen_distance_m, kNonNegative,
           "... and within this of the held-back marker's last two-camera position, or of where its "
           "velocity then carries it, m (0: no test; fast tracks exempt)");
  f.number(
      "reacquire_way_m", o.reacquire_way_m, kNonNegative,
      "a new track this close to one held-back track's way (from its last two-camera position to "
      "where its velocity then carries it) takes its id if every other one's is twice as far, m (0: off)");
  f.number("reacquire_neighbours_m", o.reacquire_neighbours_m, kNonNegative,
           "then: a new track this close to where a lost track's neighbours (a rigid fit of 3-6 tracks "
           "near it when two cameras last saw it) carried it takes its id if every other one's is twice "
           "as far; deleted tracks count for 2 s, m (0: off)");
  f.flag("reacquire_crowd_relative", o.reacquire_crowd_relative,
         "... a followed track crowds the new one out only within twice its distance from the carried point "
         "(at most 6 cm; false: within 6 cm)");
  f.flag("reacquire_group", o.reacquire_group,
         "... neighbours lost with it that came back as new tracks stand in for them, placed by their "
         "distances (false: only followed neighbours)");
  f.integer("recent_camera_window_ns", o.recent_camera_window_ns, 0, kHourNs, "for a track record's cameras");
  f.integer("rewind_horizon_ns", o.rewind_horizon_ns, 0, 60 * 1'000'000'000LL,
            "late frames up to this much older than the newest are replayed");
  f.integer("checkpoint_interval_ns", o.checkpoint_interval_ns, 0, kHourNs, "state snapshots for rewinding");
  f.integer("dense_checkpoint_window_ns", o.dense_checkpoint_window_ns, 0, 1'000'000'000LL,
            "a snapshot before every frame this recent (cheap replays of slightly late frames)");
  f.flag("reuse_replay_associations", o.reuse_replay_associations,
         "a replayed frame keeps its first association while every pair still gates");
  f.number("grid_cell_px", o.grid_cell_px, kPositive, "spatial index of a frame's blobs");
  f.integer("max_unmatched_per_frame", o.max_unmatched_per_frame, 0, 1 << 20,
            "unmatched blobs of one frame offered to initiation");
  f.section("bodies", "rigid bodies (docs/bodies.md)", [&](auto& s) { visit_bodies(s, o.bodies); });
  f.section("calibration", "continuous calibration (docs/continuous_calibration.md)",
            [&](auto& s) { visit_calibration(s, o.calibration); });
}

// A tf2 frame id: not empty, no leading '/' (tf2 rejects it), no whitespace or control characters.
std::string check_frame_id(const std::string& id) {
  if (id.empty()) return "must not be empty";
  if (id.front() == '/') return "must not start with '/' (tf2 frame ids are relative)";
  for (const char c : id) {
    if (static_cast<unsigned char>(c) <= ' ') return "must not contain spaces or control characters";
  }
  return "";
}

std::string check_frame_prefix(const std::string& prefix) {
  return prefix.empty() ? "" : check_frame_id(prefix);
}

}  // namespace

std::string check_ros2_namespace(const std::string& ns) {
  if (ns.size() > kMaxRos2NamespaceLength)
    return "must be at most " + std::to_string(kMaxRos2NamespaceLength) + " characters";
  const std::string prefix = ros2_namespace_prefix(ns);
  if (!prefix.empty() && prefix.back() == '/') return "'" + ns + "': must not end with '/'";
  for (std::size_t i = 1; i < prefix.size(); ++i) {  // prefix[0] is '/'
    const char c = prefix[i];
    const char before = prefix[i - 1];
    if (c == '/' && before == '/') return "'" + ns + "': must not contain '//'";
    if (c != '/' && c != '_' && std::isalnum(static_cast<unsigned char>(c)) == 0)
      return "'" + ns + "': ROS 2 names hold only A-Z, a-z, 0-9, '_' and '/'";
    if (before == '/' && std::isdigit(static_cast<unsigned char>(c)) != 0)
      return "'" + ns + "': a name token must not start with a digit";
    if (c == '_' && before == '_') return "'" + ns + "': must not contain '__'";
  }
  return "";
}

std::string ros2_namespace_prefix(const std::string& ns) {
  if (ns.empty() || ns == "/") return "";
  return ns.front() == '/' ? ns : "/" + ns;
}

namespace {

template <class Fields>
void visit_ros2(Fields& f, Ros2Settings& o) {
  f.flag("enabled", o.enabled, "live: publish the ROS 2 topics (estimator_node --ros2 / --no-ros2)");
  f.text("frame_id", o.frame_id, check_frame_id, "header.frame_id: the world frame (tf parent)");
  f.text("child_frame_prefix", o.child_frame_prefix, check_frame_prefix,
         "tf child frame id = this + the body's name");
  f.integer("tf_rate_hz", o.tf_rate_hz, 0, kMaxTfRateHz,
            "/tf at most this often, on a grid of the capture clock (0: every output frame)");
  f.text("namespace", o.topic_namespace, check_ros2_namespace,
         "ROS 2 namespace of every topic but /tf, e.g. /lab1 (\"\": none)");
}

template <class Fields>
void visit_subjects(Fields& f, LabellingSettings& o) {
  f.names("models", o.models,
          "subject model files (panoptes_label model), relative to this file; none: no labelling");
  f.names("soft_segments", o.soft_segments, "segments that deform while moving (e.g. Torso)");
  f.number("rate_hz", o.rate_hz, between(0, 100000), "the labeller runs at most this often (0: every frame)");
  f.integer("min_track_age", o.min_track_age, 1, 1000000,
            "a track processed fewer frames does not acquire a subject");
  f.flag("segment_poses", o.segment_poses, "publish each segment's pose like a body, <subject>/<segment>");
  f.text("static_up", o.static_up, check_axis_name, "the static trials' vertical axis (anatomical frames)");
  f.text("static_forward", o.static_forward, check_axis_name, "the direction the subject faced in them");
}

template <class Fields>
void visit_config(Fields& f, EstimatorConfig& config) {
  f.section("node", "the session and the live node", [&](auto& s) { visit_node(s, config.node); });
  f.section("screen", "the gate for bad input", [&](auto& s) { visit_screen(s, config.screen); });
  f.section("tracker", "the multi-point tracker (docs/estimator.md)",
            [&](auto& s) { visit_tracker(s, config.tracker); });
  f.section("ros2", "ROS 2 topics on the wire (docs/ros2.md)", [&](auto& s) { visit_ros2(s, config.ros2); });
  f.section("subjects", "live auto-labelling of marker sets (docs/marker_sets.md)",
            [&](auto& s) { visit_subjects(s, config.subjects); });
}

}  // namespace

EstimatorConfig estimator_config_from_yaml(const YamlReader& reader) {
  EstimatorConfig config;
  FieldReader fields(reader);
  visit_config(fields, config);
  fields.elsewhere("surface");
  fields.finish();
  return config;
}

EstimatorConfig load_estimator_config(const std::filesystem::path& path) {
  const YAML::Node root = load_yaml_file(path);
  EstimatorConfig config = estimator_config_from_yaml(YamlReader(path.string(), root));
  for (auto& model : config.subjects.models) {
    if (std::filesystem::path(model).is_relative())
      model = (path.parent_path() / model).lexically_normal().string();
  }
  return config;
}

std::string estimator_config_to_yaml(const EstimatorConfig& config) {
  EstimatorConfig copy = config;  // the visitor takes references for reading and writing alike
  FieldWriter fields;
  visit_config(fields, copy);
  return "# estimator_node configuration (docs/estimator.md, \"Configuration\"); durations *_ns in "
         "nanoseconds\n" +
         fields.text();
}

bool operator==(const EstimatorConfig& a, const EstimatorConfig& b) {
  // Exact: every field is written, doubles in their shortest round-trip form.
  return estimator_config_to_yaml(a) == estimator_config_to_yaml(b);
}

}  // namespace panoptes::session
