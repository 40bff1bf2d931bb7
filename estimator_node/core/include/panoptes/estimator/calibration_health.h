// SPDX-License-Identifier: Apache-2.0
// Per-camera calibration health (issue 36, docs/continuous_calibration.md): the residuals of a
// camera's blobs against the predictions of confirmed tracks that other cameras determine, kept
// over a sliding window, whole image and by region; a Hotelling T² test of their mean against
// zero with a stated false-alarm rate and a bias floor; quarantine of a camera whose residuals
// are significantly biased (a bump), and its release once they are not. Maths only: no DDS, no I/O.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/estimator/camera_resection.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

// What the tracker does about a camera found biased: nothing (no monitoring), or quarantine it
// (stop fusing its blobs until its residuals are unbiased again).
// kCorrect: as kDetect, and a quarantined camera's pose is estimated again from the tracks the
// others determine and applied when well determined (camera_resection.h).
enum class CalibrationMode : std::uint8_t { kOff = 0, kDetect = 1, kCorrect = 2 };
const char* to_string(CalibrationMode mode);
// "off", "detect" or "correct"; throws ConfigError naming `key` otherwise.
CalibrationMode parse_calibration_mode(const std::string& text,
                                       const std::string& key = "continuous_calibration");

struct CalibrationHealthOptions {
  std::string mode = "detect";  // off | detect | correct (parse_calibration_mode)
  // correct: the quarantined camera's pose from this many monitored frames (one per
  // sample_interval_ns), tried again at most every resection_retry_ns while it is not determined.
  // After a correction the camera's residuals on its new pose have resection_settle_ns to release
  // it before another try (each correction restarts its window: tried every second, it never was).
  std::size_t resection_frames = 25;
  TimeNs resection_retry_ns = 500'000'000;
  TimeNs resection_settle_ns = 3'000'000'000;
  ResectionOptions resection;
  // A refinement of a camera in use that would turn it by more than this or move it by more is
  // not applied (a bump is the monitor's to find); a bump correction's bounds are in `resection`.
  double refine_max_change_deg = 0.5;
  double refine_max_change_mm = 20.0;
  // correct: every camera that is not quarantined is refined the same way (no vote, the camera is
  // near right) from each refine_frames monitored frames in turn: a slow drift is followed and a
  // bump correction's remaining error taken out (docs/continuous_calibration.md, "Following
  // drift"). The new pose is applied when determined to refine_max_*_sigma and it differs from
  // the pose in use by more than refine_significance sigma and by refine_min_rotation_deg or
  // refine_min_translation_mm: the tracks' own errors are correlated over the window, so the
  // sigma from the residuals understates the noise (unmoved cameras of walk8 came out up to
  // 0.013 deg and 1.0 mm from where they were, from 150 frames). With anchors (their positions
  // are known) a refinement takes refine_anchored_frames and the rotation's floor is
  // refine_anchored_min_rotation_deg: less lag behind a drift (with no floor an unmoved, anchored
  // walk8 was refined 67 times in 60 s by at most 0.002 deg; with 0.004 and 50 frames, never).
  bool follow_drift = true;
  TimeNs refine_sample_interval_ns = 100'000'000;  // one monitored frame per camera this often
  std::size_t refine_frames = 60;
  double refine_max_rotation_sigma_deg = 0.005;
  double refine_max_translation_sigma_mm = 0.5;
  double refine_significance = 2.0;
  double refine_min_rotation_deg = 0.02;
  double refine_min_translation_mm = 2.0;
  std::size_t refine_anchored_frames = 20;
  double refine_anchored_min_rotation_deg = 0.006;
  double refine_centre_prior_mm = 1.0;  // the centre moves by about this per refinement at most
  // After a bump's correction the camera is refined once more from every monitored frame over
  // settle_refine_ns since that correction (the samples, world points and blobs, do not depend on
  // the pose, so they are gathered through the quarantine too), without the centre prior and the
  // floors: over seconds the tracks sweep the volume, which tells a turn from a shift, and their
  // errors average out (walk8, 0.5 deg bump, no anchors: 1.09 -> 0.44 mm from the true pose; 0:
  // none).
  TimeNs settle_refine_ns = 12'500'000'000;
  // Anchor markers (`estimator_node --anchors`, a landmarks file): fixed markers at known
  // positions. A refinement pairs each camera's blobs with them as well as with the tracks, each
  // anchor's residual weighing anchor_weight times a track's, and the tracks on an anchor (within
  // anchor_radius_m) are left out: the world frame is held by the anchors instead of by the
  // cameras' mean (which moves with their drift).
  std::vector<Eigen::Vector3d> anchors;
  double anchor_weight = 10.0;
  double anchor_radius_m = 0.03;
  TimeNs window_ns = 1'000'000'000;        // residuals this recent are judged
  TimeNs sample_interval_ns = 40'000'000;  // one residual per track and camera this often (decorrelation)
  std::size_t min_samples = 30;            // a region (or the camera) with fewer is not judged
  double false_alarm = 1e-9;               // α per judgement (whole camera; regions share it, Bonferroni)
  double min_bias_px = 1.5;                // a significant mean below this is reported, not acted on
  double release_fraction = 0.3;        // quarantined: released when every |bias| < this × min_bias_px ...
  double release_p = 0.01;              // ... or p > this, over a full window
  double search_px = 25.0;              // a confirmed track's blob is the nearest within this ...
  double unique_ratio = 2.0;            // ... and the next nearest is this much farther
  double isolation_px = 25.0;           // no other track predicted within this of the track
  double max_predicted_sigma_px = 2.0;  // the track's prediction is this good (1σ, largest axis)
  // A camera whose blobs miss the tracks: of at least min_samples predictions in its image, fewer
  // than this share had a blob in their gate (a bump beyond search_px); released above the second.
  double min_seen_fraction = 0.05;
  std::size_t min_blind_predictions = 100;  // ... judged from this many predictions in the window
  double release_seen_fraction = 0.2;
  // ... and its own blobs are unexplained: fewer than this share of them lie within search_px of
  // any live track's predicted pixel. A camera on a sparse rig whose qualified tracks (seen by
  // min_other_cameras others) are mostly the markers the body hides from it predicts many and sees
  // few, yet its blobs sit on the tracks it does see; a bumped camera's blobs sit on none.
  double max_explained_blob_fraction = 0.6;
  int min_other_cameras = 2;  // cameras other than this one updated the track recently
  TimeNs other_camera_window_ns = 100'000'000;
};

inline constexpr int kCalibrationRegionsX = 3;
inline constexpr int kCalibrationRegionsY = 3;
inline constexpr int kCalibrationRegions = kCalibrationRegionsX * kCalibrationRegionsY;

enum class CalibrationState : std::uint8_t {
  kUnknown = 0,      // too few residuals in the window to judge
  kOk = 1,           // no significant bias
  kSmallBias = 2,    // a significant bias below min_bias_px: reported, the camera is still used
  kQuarantined = 3,  // a significant bias of at least min_bias_px: its blobs are not fused
};
const char* to_string(CalibrationState state);

// Residual statistics of one image region (or the whole image) over the window.
struct ResidualStats {
  std::size_t samples = 0;
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();  // mean residual, px (observed − predicted)
  double spread_px = 0;                            // RMS distance of the residuals from their mean
  double t2 = 0;                                   // Hotelling T² of the mean against zero
  double p_value = 1;                              // P(T² this large | no bias), F(2, n−2)
};

struct CameraCalibrationHealth {
  std::string camera_id;
  CalibrationState state = CalibrationState::kUnknown;
  ResidualStats whole;
  std::array<ResidualStats, kCalibrationRegions> regions{};  // row-major 3 × 3 over the image
  std::size_t predicted = 0;  // window: predictions of qualified tracks in its image ...
  std::size_t seen = 0;       // ... and of those, with a blob in the gate
  std::size_t blobs = 0;      // window: blobs of the monitored frames ...
  std::size_t explained = 0;  // ... and of those, within search_px of a live track's prediction
  std::string reason;         // why it is quarantined or biased (empty when ok)
  TimeNs quarantined_since_ns = 0;
  std::uint64_t residuals = 0;       // residuals collected since the start
  std::uint64_t quarantines = 0;     // times it was quarantined
  std::uint64_t releases = 0;        // times it was brought back
  std::uint64_t blobs_withheld = 0;  // blobs not fused while quarantined
};

// Hotelling T² of the mean of `n` 2-vectors against zero, from their sum and sum of outer
// products, and its p-value (exact for Gaussian residuals: (n−2)/(2(n−1)) T² ~ F(2, n−2), whose
// tail is (1 + T²/(n−1))^−(n−2)/2). `floor_px`: the covariance is at least floor² I (a window of
// identical residuals, a still marker, is not infinitely significant).
ResidualStats residual_stats(std::size_t n, const Eigen::Vector2d& sum, const Eigen::Matrix2d& sum_outer,
                             double floor_px);

// A camera's quarantine began or ended (Tracker::take_calibration_transitions): the live estimator
// logs each with its capture stamp, which the once-a-second status line cannot give.
struct CalibrationTransition {
  std::string camera_id;
  bool quarantined = false;  // true: quarantined at stamp_ns; false: released
  TimeNs stamp_ns = 0;
  std::string reason;  // the quarantine's
};

class CalibrationMonitor {
 public:
  explicit CalibrationMonitor(CalibrationHealthOptions options = {}, double centroid_sigma_px = 0.5);

  void set_cameras(const std::vector<std::string>& camera_ids,
                   const std::vector<Eigen::Vector2d>& image_sizes);
  // Whether `camera`'s frame at `stamp_ns` is to be monitored and judged: one frame per sample
  // interval (each track gives at most one residual per interval anyway). Marks it done.
  bool due(int camera, TimeNs stamp_ns);
  // Whether a residual of `track_id` in `camera` at `stamp_ns` is wanted (one per sample interval).
  bool wants(int camera, std::int64_t track_id, TimeNs stamp_ns) const;
  // A qualified track predicted in the camera's image; `seen`: a blob fell in its gate.
  void add_prediction(int camera, std::int64_t track_id, TimeNs stamp_ns, bool seen);
  // A monitored frame's blobs, and how many lie within search_px of a live track's prediction.
  void add_blobs(int camera, TimeNs stamp_ns, std::size_t blobs, std::size_t explained);
  // A residual: blob minus predicted pixel, at the predicted pixel `at`.
  void add(int camera, std::int64_t track_id, TimeNs stamp_ns, const Eigen::Vector2d& at,
           const Eigen::Vector2d& residual);
  // Judges the camera's window at `stamp_ns` (after its frame's residuals): may quarantine or
  // release it. Returns whether its state changed.
  bool judge(int camera, TimeNs stamp_ns);
  bool quarantined(int camera) const;
  // The camera's pose changed (a correction): its window starts again, so that it is judged (and
  // released) on residuals of the new pose only; its state and counters stay.
  void restart(int camera);
  void note_withheld(int camera, std::size_t blobs);
  // Mode correct: why the last try to correct a quarantined camera was not applied (too few
  // blobs paired, not determined, implausibly far); appended to its reason while it stays
  // quarantined, so status and the console say why it is not back.
  void note_correction(int camera, const std::string& why);
  const CameraCalibrationHealth& health(int camera) const { return cameras_.at(camera).health; }
  std::vector<CameraCalibrationHealth> health() const;
  const CalibrationHealthOptions& options() const { return options_; }
  // The quarantines begun and ended since the last call (at most kMaxTransitions kept).
  std::vector<CalibrationTransition> take_transitions();
  static constexpr std::size_t kMaxTransitions = 1024;

 private:
  struct Sums {
    std::size_t n = 0;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
    void add(const Eigen::Vector2d& r);
    void remove(const Sums& part);  // a part that was added before
  };
  // What one monitored frame added to the window (its residuals all carry the frame's stamp, so
  // a frame leaves the window at once: one entry per frame instead of one per residual, as the
  // window's expiry walked a second's residuals of every camera through the cache).
  struct Frame {
    TimeNs stamp_ns = 0;
    std::array<Sums, kCalibrationRegions> regions{};
    std::size_t predicted = 0;
    std::size_t seen = 0;
    std::size_t blobs = 0;
    std::size_t explained = 0;
  };
  struct PerCamera {
    Eigen::Vector2d image_size{1, 1};
    std::deque<Frame> window;  // by monitored frame, oldest first
    Sums whole;
    std::array<Sums, kCalibrationRegions> regions{};
    // (track id, stamp of its last sample), sorted by id: a flat table, since a camera's entries
    // are visited once per sample_interval_ns and a node per track was a cache miss per track.
    std::vector<std::pair<std::int64_t, TimeNs>> last_sample;
    mutable std::size_t hint = 0;  // where the last lookup in last_sample ended (find_sample)
    std::size_t predicted = 0;     // over the window
    std::size_t seen = 0;
    std::size_t blobs = 0;
    std::size_t explained = 0;
    TimeNs calm_since_ns = 0;  // quarantined: residuals unbiased since (0: not calm)
    TimeNs last_monitored_ns = 0;
    CameraCalibrationHealth health;
  };
  // The window's entry of the frame at `stamp_ns` (the newest, or a new one).
  static Frame& frame_at(PerCamera& camera, TimeNs stamp_ns);
  // Where `track_id` is, or would go, in camera.last_sample.
  static std::size_t find_sample(const PerCamera& camera, std::int64_t track_id);
  static void note_sample(PerCamera& camera, std::int64_t track_id, TimeNs stamp_ns);
  void expire(PerCamera& camera, TimeNs stamp_ns);
  // The judgement of the window: biased (quarantine), calm (release) and the reason.
  void update_stats(PerCamera& camera) const;

  CalibrationHealthOptions options_;
  double floor_px_;
  // The newest quarantine: for a window after it no other camera is quarantined (their residuals
  // were measured against tracks the quarantined camera had been pulling).
  TimeNs last_quarantine_ns_ = 0;
  std::string last_quarantined_;
  std::vector<PerCamera> cameras_;
  std::vector<CalibrationTransition> transitions_;
  void note_transition(const CameraCalibrationHealth& health, bool quarantined, TimeNs stamp_ns);
};

}  // namespace panoptes::estimator
