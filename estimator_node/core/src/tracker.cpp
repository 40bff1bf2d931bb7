// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/tracker.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>

#include <Eigen/Core>

#include "blob_grid.h"
#include "panoptes/covariance_bound.h"
#include "panoptes/errors.h"
#include "panoptes/estimator/assignment.h"
#include "panoptes/estimator/neighbour_anchor.h"
#include "panoptes/triangulation.h"
#include "points_by_x.h"

namespace panoptes::estimator {

void TrackerOptions::print(std::ostream& out) const {
  out << "tracker options:\n"
      << "  process_noise            " << process_noise << " m^2/s^3\n"
      << "  measurement_noise_px     " << measurement_noise_px << " px\n"
      << "  gate_chi2                " << gate_chi2 << "\n"
      << "  init window              " << ns_to_seconds(init.window_ns) * 1e3 << " ms\n"
      << "  init epipolar / reproj   " << init.epipolar_px << " / " << init.reprojection_px << " px\n"
      << "  confirm                  " << confirm_cameras << " cameras, or " << confirm_updates
      << " updates from 2\n"
      << "  coast_after              " << ns_to_seconds(coast_after_ns) * 1e3 << " ms\n"
      << "  delete_after             " << ns_to_seconds(delete_after_ns) * 1e3 << " ms\n"
      << "  publish_max_sigma        " << publish_max_sigma_m * 1e3
      << " mm (fast: " << fast_publish_max_sigma_m * 1e3 << " mm, or innovations within "
      << fast_publish_innovation_px << " px; views within " << publish_max_innovation_px << " px, odd views "
      << (dispute_odd_views ? "disputed" : "kept") << ")\n"
      << "  reacquire_sigma          " << reacquire_sigma_m * 1e3 << " mm\n"
      << "  fast tracks              sigma^2 x " << fast_process_noise_scale << " for "
      << ns_to_seconds(fast_hold_ns) * 1e3 << " ms (x " << fast_isolated_process_noise_scale
      << " with no confirmed track within " << fast_isolation_m << " m), acceleration input "
      << ns_to_seconds(fast_acceleration_time_constant_ns) * 1e3 << " ms\n"
      << "  one-view velocity        decays along the ray with "
      << ns_to_seconds(one_view_velocity_time_constant_ns) * 1e3 << " ms; ray twins wait "
      << ns_to_seconds(ray_twin_wait_ns) * 1e3 << " ms; blob owners within " << blob_owner_px << " px\n"
      << "  merge_distance           " << merge_distance_m * 1e3 << " mm\n"
      << "  rewind horizon           " << ns_to_seconds(rewind_horizon_ns) * 1e3 << " ms\n"
      << "  continuous calibration   " << calibration.mode << " (window "
      << ns_to_seconds(calibration.window_ns) * 1e3 << " ms, alpha " << calibration.false_alarm
      << ", min bias " << calibration.min_bias_px << " px)\n";
}

namespace {

// A swung or thrown object: the markers of a walking, running or dancing body stay below (the
// accuracy grid's walk lost 23 more identities when slower tracks took manoeuvre gates).
constexpr double kFastSpeed = 10.0;
// Longer than any gap between the frames of a rig's cameras at >= 100 Hz: a track not updated for
// longer has lost its marker.
constexpr TimeNs kFrameGapNs = 10'000'000;
// A track with fewer updates is young: a wrong pairing's ghost lives a few updates.
constexpr std::uint64_t kSettledUpdates = 10;
constexpr int kFastUpdates = 5;
// An update that moves a track's projection further than this is a reacquisition (a club head
// back in view after the top of the swing: 30-335 px), not a step of a manoeuvre followed frame by
// frame (a ball's catch with the acceleration input: at most 5.3 px on the grid): its change of
// velocity is no acceleration sample (estimate_acceleration).
constexpr double kSteadyInnovationPx = 10.0;
// A second camera's update this long after the last update two cameras made together ends a
// stretch of one camera's updates (return_velocity_cap_mps).
constexpr TimeNs kReturnGapNs = 30'000'000;
// A track that no second camera has updated for longer than this is held by one camera's blobs
// alone: its depth along that camera's ray is its prediction's (one_view, initiate).
constexpr TimeNs kOneViewNs = 30'000'000;
// A one-view track moves to a candidate only if no other track is this near it: between two
// neighbours a few centimetres apart (clavicles, heel and ankle) a two-view point may be a pairing
// of one's blob with the other's.
constexpr double kOneViewClearM = 0.1;
// A one-view track may also move to a point this near where its neighbours carried it (may_reanchor).
constexpr double kReanchorCarriedM = 0.1;
// A track whose predicted position's covariance has a trace above this times reacquire_sigma_m²
// is uncertain: held back once out of sight (held_back); kept off other tracks' blobs in a second
// camera while one camera alone updates it (owned_elsewhere).
constexpr double kUncertainFactor = 3.0;
// return_max_seen_distance_m: how fast the reach of a one-view track's second view grows with the
// time since its last two-camera update, m/s (a running foot's marker over a stride's fraction), or
// the track's own top speed if higher (a club head slowed at the top of its swing).
constexpr double kReturnSpeed = 3.0;
// return_max_carried_distance_m: where a track's neighbours carried it says where its marker is only
// if its anchor was taken this long after its birth or later (a pair made in the first frames may
// have lost its marker before its own two-camera updates began: its anchor is a ghost's), and if no
// other track updated within kFrameGapNs is this near that point (the marker has a track there: this
// one is left over from it).
constexpr TimeNs kCarriedAnchorAgeNs = 500'000'000;
constexpr double kCarriedTakenM = 0.05;
// return_fresh_max_jump_m: a blob continues a blob of its camera's previous frame if one was within
// this (px; a false blob lasts one frame, a marker's moves a few px: a running ankle's up to 19 px a
// frame in ceiling4/run/c0/s2, near this bound; faster markers leave it, which the 0.5 m jump and the
// carried point's confirmation allow for), and an update within this of the trusted carried point is
// a second view its neighbours confirm (m).
constexpr double kFreshBlobPx = 20.0;
constexpr double kFreshCarriedM = 0.15;
// dispute_odd_views: how long a track is not offered the blobs of a camera whose view was disputed,
// and how well (px, worst reprojection) its other views' last blobs must agree for one view to be odd.
constexpr TimeNs kDisputedViewNs = 100'000'000;
constexpr double kOddViewAgreePx = 1.0;
// Blob owners (blob_owner_px): a camera's previous frame older than this tells nothing of its
// blobs now; a blob no track took is its last owner's for this long after their last update.
constexpr TimeNs kOwnerFrameNs = 30'000'000;
constexpr TimeNs kOwnerMemoryNs = 100'000'000;
constexpr double kReacquireGateChi2 = 16.27;  // χ²₃ at p = 0.999
// The speed a marker is allowed during a pause of the input at least, whatever its track's
// velocity before (within_seen_reach): a person's marker slow at the pause's start (a turning
// point) moves on at a walker's speed.
constexpr double kPausedMinSpeed = 1.5;
// Tracks that expire() removed return when frames come back within this of the newest stamp then
// (Core::suspended): a stall of the input, not cameras stopped.
constexpr TimeNs kMaxSuspendNs = 3'000'000'000;
// A fast track's rigid partner (Track::partner_id): the settled track nearest it, kept while their
// distance stays within kRigidToleranceM of what it was when chosen; rigid once kept for
// kRigidMinNs (a club's head and shaft markers; a thrown ball leaves its hand's markers at once).
// A new track takes the fast track's identity only within rejoin_rigid_margin_m of that distance
// from the partner, if the partner is still followed (keeps_partner_distance).
constexpr double kRigidToleranceM = 0.03;
constexpr TimeNs kRigidMinNs = 100'000'000;
// An isolated fast track takes the larger factor (isolated) only after this many fast updates of
// its own: with kFastUpdates, ghosts of clutter or of a walk's wrong pairings took it too.
constexpr int kIsolatedFastUpdates = 20;
// A fast track lends its speed to new tracks near it (nearby_fast_speed) only after this many
// fast updates: on a ring of four cameras a walk's ghosts (wrong pairings flying off along a ray)
// reached 5 and their priors made more such ghosts.
constexpr int kPriorFastUpdates = 30;
// Reacquisition by neighbours (reacquire_neighbours_m; docs/estimator.md, "Reacquisition by
// neighbours"). A track's neighbours are the tracks within kNeighbourRadiusM of it at its last
// two-camera update, ranked by distance plus kNeighbourHorizonS times their difference in velocity
// (a limb's markers before the other foot's passing by). A deleted track is remembered for
// kNeighbourMemoryNs after that update. The rigid fit of the neighbours' motion must leave them
// within kNeighbourMaxFitRmsM RMS (a knee's bend moves a foot off its thigh's motion). Every other
// lost track's carried position must be kNeighbourClearRatio times farther (a nearer one than
// kNeighbourFloorM counts as that far: the ratio of two tiny distances is noise), and no followed
// track within kNeighbourCrowdM of the new one: the two clavicles 5 cm apart swapped ids in the
// corridor4 run cells without it (28 -> 39 swaps in 12 s). With reacquire_crowd_relative only
// within kNeighbourClearRatio times the new track's distance from the carried position (at least
// kNeighbourFloorM), as for the other lost tracks' carried positions.
constexpr double kNeighbourRadiusM = 0.5;
constexpr double kNeighbourHorizonS = 0.2;
constexpr TimeNs kNeighbourMemoryNs = 2'000'000'000;
constexpr double kNeighbourMaxFitRmsM = 0.03;
constexpr double kNeighbourClearRatio = 2.0;
constexpr double kNeighbourFloorM = 0.01;
constexpr double kNeighbourCrowdM = 0.06;
// Group returns (reacquire_group): a new track stands in for a lost neighbour when its distances
// from the neighbours placed agree within kStandInToleranceM; the fit must leave them within
// kStandInMaxFitRmsM RMS, and the new track must lie within kStandInReachM of the carried point
// (not reacquire_neighbours_m: a fit of new tracks is exact or wrong, and the feet's markers are a
// few centimetres apart). Chosen on LateData's stalls (docs/estimator.md, "Group returns").
constexpr double kStandInToleranceM = 0.02;
constexpr double kStandInMaxFitRmsM = 0.01;
constexpr double kStandInReachM = 0.02;
// ... and the carried point must lie within kStandInDriftM plus half kStandInAccelerationMps2 times
// the time since its own track's last update squared of that track's prediction.
constexpr double kStandInDriftM = 0.03;
constexpr double kStandInAccelerationMps2 = 40.0;
// pin_one_view_depth: the carried point must lie this near the updating camera's ray.
constexpr double kPinRayM = 0.03;

struct Track {
  std::int64_t id = 0;
  PointState state;
  TimeNs created_ns = 0;
  TimeNs last_update_ns = 0;
  TimeNs resumed_ns = 0;  // when an update last ended a coast (none for > coast_after_ns); 0: never
  std::uint64_t updates = 0;
  bool confirmed = false;
  int misses = 0;          // tentative only: frames that should have shown it
  double nis_average = 0;  // moving average of the normalised innovation d²
  int nis_updates = 0;
  // Adaptive process noise: σ² = process_noise × q_scale, q_scale raised by nis_adapt (a short
  // average of d²) and decaying to 1 since q_stamp_ns (adapt_process_noise).
  double q_scale = 1.0;
  double nis_adapt = 0;
  TimeNs q_stamp_ns = 0;
  int distinct_cameras = 0;  // cameras that ever updated it
  // Confirmed and kFastUpdates updates above kFastSpeed once settled (commit_pair), or rejoined
  // to such a track's identity: a swung or thrown object, which may rejoin its identity after a
  // gap (rejoin_fast_tracks).
  bool fast = false;
  double peak_speed = 0;      // m/s, the fastest it went while confirmed (carried over by a rejoin)
  int fast_updates = 0;       // updates while confirmed with a speed above kFastSpeed
  int seen_fast_updates = 0;  // of those, updates made while a second camera's was within kFrameGapNs
  bool runaway = false;       // fast by one camera's updates (delete_runaway_tracks): deleted by prune
  TimeNs last_fast_ns = 0;    // its last update above kFastSpeed while confirmed (or its rejoin)
  // Where it was at its last update with a second camera's within kFrameGapNs (0: never): a track
  // that only one camera still updates slides along that camera's ray (a club head leaving the
  // views), so a rejoin measures from here.
  Eigen::Vector3d seen_position = Eigen::Vector3d::Zero();
  Eigen::Vector3d seen_velocity = Eigen::Vector3d::Zero();  // its velocity then
  TimeNs seen_ns = 0;
  // The newest frame applied that had it in view and did not update it, and its camera (-1: none):
  // a camera that ran and did not see its marker (damp_one_view_velocity).
  TimeNs missed_ns = 0;
  int missed_camera = -1;
  // Since when a blob it was assigned has been left to neither of it and a ray twin (0: not waiting).
  TimeNs twin_wait_since_ns = 0;
  // A fast track's rigid partner (kRigidToleranceM): its id (0: none), their distance when it was
  // chosen and since when it held (note_partner).
  std::int64_t partner_id = 0;
  double partner_distance_m = 0;
  TimeNs partner_since_ns = 0;
  // Its position and its neighbours' at its last two-camera update, taken once no second camera
  // has updated it for kFrameGapNs (note_anchors; reacquire_by_neighbours). stamp_ns 0: none.
  // A later two-camera update with fewer than three neighbours around (a one-view track that
  // took a stray blob in a second camera, far from its limb) leaves the anchor it had.
  NeighbourAnchor anchor;
  TimeNs anchored_seen_ns = 0;  // the seen_ns note_anchors last looked at
  // A camera whose blobs it is not offered until disputed_until_ns (-1: none; dispute_views).
  int disputed_camera = -1;
  TimeNs disputed_until_ns = 0;
  bool disputed_in(int camera_index, TimeNs stamp) const {
    return camera_index == disputed_camera && stamp < disputed_until_ns;
  }
  Eigen::Vector3d last_seen_position() const { return seen_ns != 0 ? seen_position : state.position(); }
  // Where its last two-camera state puts it at `stamp` (constant velocity since), not where one
  // camera's updates dragged it along that camera's ray since.
  Eigen::Vector3d seen_position_at(TimeNs stamp) const {
    return seen_ns != 0 ? Eigen::Vector3d(seen_position + ns_to_seconds(stamp - seen_ns) * seen_velocity)
                        : position_at(stamp);
  }
  TimeNs last_seen_ns() const { return seen_ns != 0 ? seen_ns : last_update_ns; }
  std::vector<TimeNs> camera_last_update;   // by camera index; 0 = never
  std::vector<float> camera_innovation_px;  // by camera index: its last update's innovation, px (publishable)
  std::vector<float> camera_innovation_avg_px;  // by camera index: its innovations' moving average, px
  struct LastBlob {
    Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
    TimeNs stamp_ns = 0;  // 0: none
  };
  std::vector<LastBlob> camera_last_blob;  // by camera index: the blob of its last update there (odd_view)
  // reacquire_sigma_m: made by initiation under a new id (not a rejoined one, nor one that took a
  // held-back track's id; a replay that makes an undone one again keeps its flag), and confirmed
  // in the frame just applied: it may take a held-back track's id (reacquire_confirmed).
  bool fresh = false;
  bool pending_reacquire = false;
  // rejoin_fast_tracks: the lost fast track whose id this track takes once confirmed (0: none).
  std::int64_t rejoin_id = 0;
  std::uint64_t frames_at_update = 0;  // Core::frames_applied at its last update (held_back)
  // Whether the last record made of it was published (determined): then it stays published up to
  // kKeepPublishedFactor × publish_max_sigma_m (hysteresis, issue 32 item 9). Set by tracks_at.
  mutable bool published = false;

  double sigma2(double process_noise) const { return process_noise * q_scale; }

  Eigen::Vector3d position_at(TimeNs stamp_ns) const {
    return position_after(state, ns_to_seconds(stamp_ns - state.stamp_ns));
  }
  // fast_acceleration_time_constant_ns: the stamp and velocity of its last update (0: none).
  TimeNs acceleration_sample_ns = 0;
  Eigen::Vector3d acceleration_sample_velocity = Eigen::Vector3d::Zero();
};

// Everything a rewind restores.
struct Core {
  std::vector<Track> tracks;
  // Confirmed tracks deleted as implausible (a club's shaft marker that lost its way at the top
  // of the swing), kept until delete_after_ns after their last update for rejoin_fast_track.
  std::vector<Track> lost;
  // Confirmed tracks that expire() removed while no frame came (the live estimator, after
  // delete_after + rewind_horizon without a frame), with the newest stamp then: if frames come
  // back within kMaxSuspendNs of it, they return as tracks that coasted through a pause of the
  // input (held back, reacquirable); otherwise they are gone (resume_suspended).
  std::vector<Track> suspended;
  TimeNs suspended_at_ns = std::numeric_limits<TimeNs>::min();
  // Confirmed tracks deleted after a silence, with their anchors, for kNeighbourMemoryNs after it
  // (reacquire_by_neighbours): a marker out of every view for longer than delete_after_ns.
  struct Departed {
    std::int64_t id = 0;
    NeighbourAnchor anchor;
  };
  std::vector<Departed> departed;
  Initiator initiator;
  TimeNs last_stamp_ns = std::numeric_limits<TimeNs>::min();
  TimeNs last_merge_check_ns = std::numeric_limits<TimeNs>::min();
  std::uint64_t manoeuvres_recovered = 0;  // blobs taken in a manoeuvre gate (recover_manoeuvres)
  std::uint64_t fast_tracks_rejoined = 0;  // new tracks that took a lost fast track's id (rejoin_fast_tracks)
  std::uint64_t fast_off_partner = 0;      // blobs refused off the rigid partner (partner_update_margin_m)
  std::uint64_t runaway_tracks_deleted = 0;           // delete_runaway_tracks
  std::uint64_t one_view_depths_pinned = 0;           // one_view_carried_sigma_m
  std::uint64_t return_velocities_capped = 0;         // return_velocity_cap_mps
  std::uint64_t ray_twin_waits = 0;                   // ray_twin_wait_ns
  std::uint64_t tracks_reacquired = 0;                // confirmed new tracks that took a held-back track's id
  std::uint64_t tracks_reacquired_by_neighbours = 0;  // ... by reacquire_by_neighbours
  std::uint64_t tracks_reanchored = 0;  // one-view tracks moved to where two views put their marker
  std::uint64_t input_pauses = 0;       // pauses of the input (note_interval)
  std::uint64_t frames_applied = 0;     // frames apply() has applied (held_back)
  // Input pauses (every camera stalled at once): the usual interval between applied frames' stamps
  // (a moving average), the stamp of the frame that ended the last pause (paused()) and of the
  // applied frame before it (its start: silence()). A pause lasts while fewer cameras than confirm
  // a track have delivered since (pause_cameras, cleared once enough have).
  double frame_interval_ns = 0;
  TimeNs pause_start_ns = std::numeric_limits<TimeNs>::min();
  TimeNs pause_end_ns = std::numeric_limits<TimeNs>::min();
  std::vector<int> pause_cameras;
  std::uint64_t tracks_created = 0, tracks_confirmed = 0, tracks_deleted = 0, tracks_merged = 0,
                ghosts_deleted = 0, one_view_ghosts_deleted = 0, blobs_associated = 0,
                blobs_not_initiated = 0;
  std::vector<std::uint64_t> associated_per_camera;
  // By camera: the innovations' typical length, px, a slow moving average over the updates of
  // confirmed tracks (views_agree: a noisy camera's own scale).
  std::vector<double> camera_innovation_level;
  // By camera (blob_owner_px): the stamp of its last applied frame, the blobs tracks took in it, and
  // the blobs no track has taken since their owner lost them, for up to kOwnerMemoryNs.
  struct BlobOwner {
    Eigen::Vector2d pixel;
    std::int64_t id;
    TimeNs since_ns;  // the owner's last update with this blob
  };
  struct BlobOwners {
    TimeNs stamp_ns = 0;
    std::vector<BlobOwner> owners;
  };
  std::vector<BlobOwners> blob_owners;
  // Each camera's last associated frame: its stamp and finite blobs (return_fresh_max_jump_m).
  struct LastFrame {
    TimeNs stamp_ns = 0;
    std::vector<Eigen::Vector2d> pixels;
  };
  std::vector<LastFrame> last_frames;
  std::uint64_t owned_blobs_kept = 0;      // blobs an uncertain one-view track was refused (blob_owner_px)
  std::uint64_t returns_beyond_reach = 0;  // ... and second views it was refused (return_max_seen_distance_m)
  // ... and second views far from where its neighbours carried it (return_max_carried_distance_m)
  std::uint64_t returns_far_from_carried = 0;
  std::uint64_t returns_fresh_far = 0;  // ... and fresh blobs too far (return_fresh_max_jump_m)
  std::uint64_t views_disputed = 0;     // odd views whose blob started another marker (dispute_odd_views)
  BodySet bodies;
};

struct Checkpoint {
  TimeNs stamp_ns;    // stamp of the first history frame the state does not include (spacing)
                      // (core.last_stamp_ns: of the last it includes, for rewinding)
  std::size_t index;  // absolute history index of that frame
  Core core;
};

struct Entry {
  int camera;
  FeatureFrame frame;
  // The association the frame's last application chose, (track id, blob), and a digest of the
  // tracks (ids and confirmation) it chose among: a replay tries it first (reassociate).
  std::vector<std::pair<std::int64_t, std::size_t>> associations;
  std::uint64_t tracks_digest = 0;
  bool associated = false;
};

// A track predicted to a frame's stamp and projected into its camera.
struct Projected {
  PointState state;
  PointProjection projection;
};

// A track, a blob of the frame and the track's prediction projected for it: a pair to commit.
struct ProjectedPair {
  std::size_t track;
  std::size_t blob;
  Projected projected;
};

// `state` predicted to `stamp` with white-acceleration σ² `sigma2` and projected into `camera`;
// nullopt when it lies closer than `min_depth` in front of the camera or does not project.
std::optional<Projected> project_prediction(const PointState& state, TimeNs stamp, double sigma2,
                                            const CameraModel& camera, double min_depth, double noise_px) {
  Projected full;
  full.state = predicted(state, stamp, sigma2);
  if (camera.T_cam_world().apply(full.state.position()).z() < min_depth) return std::nullopt;
  const auto projection = project_point(full.state, camera, noise_px);
  if (!projection) return std::nullopt;
  full.projection = *projection;
  return full;
}

// The tracks and blobs of one frame that may belong together.
struct Gating {
  std::vector<GatedPair> gated;                       // (track, blob, d²)
  std::vector<std::optional<Projected>> projected;    // by track; set when a blob came near it
  std::vector<char> in_view;                          // by track: predicted inside the image
  std::vector<char> near;                             // by blob: within some track's search radius
  std::vector<std::optional<Eigen::Vector2d>> pixel;  // by track: its predicted position's pixel
};

}  // namespace

struct Tracker::Impl {
  explicit Impl(const TrackerOptions& o)
      : options(o),
        calibration_mode(parse_calibration_mode(o.calibration.mode, "tracker.calibration.mode")),
        monitor(o.calibration, o.measurement_noise_px) {
    core.initiator = Initiator(o.init);
  }

  const TrackerOptions options;
  const CalibrationMode calibration_mode;
  // Not part of Core: a rewind does not undo what the residuals showed (replays add none).
  CalibrationMonitor monitor;
  std::vector<std::unique_ptr<CameraModel>> models;  // by camera index; pointers stay valid
  // Mode correct: per camera, the monitored frames collected while it is quarantined, when a
  // resection was last tried, and the corrections not yet taken by the session.
  std::vector<std::deque<ResectionSample>> resection_samples;
  std::vector<std::vector<ResectionSample>> refine_samples;  // not quarantined: drift followed
  std::vector<TimeNs> refine_sampled_ns;                     // ... the last one's stamp
  std::vector<TimeNs> settle_since_ns;  // after a bump's correction: its stamp, until the settling refinement
  std::vector<TimeNs> resection_tried_ns;
  std::vector<TimeNs> resection_settle_until_ns;  // after a correction: none before this
  std::vector<CalibrationCorrection> corrections;
  std::vector<std::string> camera_ids;
  std::map<std::string, int> camera_index;
  Core core;
  // Track ids are never restored by a rewind: an id once published names one marker. The next new
  // id, and during a replay the tracks the rewind undid (created after the restored state): a track
  // the replay creates again where one of them was takes its id (docs/estimator.md, "Track ids
  // across a rewind"). Restoring the id counter instead gave the re-created tracks each other's
  // ids whenever the replay created them in another order (a late frame first): under CPU
  // contention tens of tracks moved to other markers at once, and the names on them with them.
  std::int64_t next_track_id = 1;
  std::vector<Track> undone;
  // By id: whether a record of that id was published (one_view_ghost_ns). Not part of Core either:
  // the records are made after the frames are applied, so a rewind's restored state would forget them.
  mutable std::vector<char> published_ids;
  void note_published(std::int64_t id) const {
    const auto index = static_cast<std::size_t>(id);
    if (index >= published_ids.size()) published_ids.resize(index + 1, 0);
    published_ids[index] = 1;
  }
  bool was_published(std::int64_t id) const {
    const auto index = static_cast<std::size_t>(id);
    return index < published_ids.size() && published_ids[index] != 0;
  }
  std::deque<Entry> history;     // applied frames in stamp order, within the rewind horizon
  std::size_t history_base = 0;  // absolute index of history.front()
  // Rewind points in stamp order: `checkpoints` every checkpoint_interval_ns over the rewind
  // horizon, `recent` before every frame of the last dense_checkpoint_window_ns (most late frames
  // are late by a few frames: rewinding to just before them replays only those). A recent
  // checkpoint that ages out of the dense window moves to `checkpoints` or is recycled.
  std::deque<Checkpoint> checkpoints;
  std::deque<Checkpoint> recent;
  std::vector<Core> spare;  // recycled states: copying into them reuses their allocations
  TrackerStats stats;
  mutable TrackerStats merged_stats;

  int required_cameras() const {
    return std::max(2, std::min<int>(options.confirm_cameras, static_cast<int>(models.size())));
  }

  void cameras_changed() {
    std::vector<const CameraModel*> pointers;
    for (const auto& model : models) pointers.push_back(model.get());
    core.initiator.set_cameras(pointers);
    core.associated_per_camera.resize(models.size(), 0);
    core.camera_innovation_level.resize(models.size(), 0.0);
    std::vector<Eigen::Vector2d> sizes;
    for (const auto& model : models)
      sizes.emplace_back(model->intrinsics().width, model->intrinsics().height);
    monitor.set_cameras(camera_ids, sizes);
    history.clear();
    checkpoints.clear();
    recent.clear();
    history_base = 0;
  }

  Checkpoint make_checkpoint(TimeNs stamp_ns, std::size_t absolute_index) {
    if (spare.empty()) return {stamp_ns, absolute_index, core};
    Checkpoint checkpoint{stamp_ns, absolute_index, std::move(spare.back())};
    spare.pop_back();
    checkpoint.core = core;
    return checkpoint;
  }

  void recycle(Checkpoint&& checkpoint) {
    if (spare.size() < 64) spare.push_back(std::move(checkpoint.core));
  }

  const Checkpoint* newest_checkpoint() const {
    if (!recent.empty()) return &recent.back();
    return checkpoints.empty() ? nullptr : &checkpoints.back();
  }
  const Checkpoint* oldest_checkpoint() const {
    if (!checkpoints.empty()) return &checkpoints.front();
    return recent.empty() ? nullptr : &recent.front();
  }

  // Before applying the frame at `absolute_index` (stamped `stamp_ns`).
  void maybe_checkpoint(TimeNs stamp_ns, std::size_t absolute_index) {
    const Checkpoint* newest = newest_checkpoint();
    if (newest == nullptr) {
      // The empty initial state comes before any frame, however old.
      const bool pristine = core.tracks.empty() && core.last_stamp_ns == std::numeric_limits<TimeNs>::min();
      checkpoints.push_back(
          make_checkpoint(pristine ? std::numeric_limits<TimeNs>::min() : stamp_ns, absolute_index));
      return;
    }
    if (newest->index == absolute_index) return;
    if (options.dense_checkpoint_window_ns > 0) {
      recent.push_back(make_checkpoint(stamp_ns, absolute_index));
      age_recent(stamp_ns - options.dense_checkpoint_window_ns);
    } else if (newest->stamp_ns == std::numeric_limits<TimeNs>::min() ||
               stamp_ns - newest->stamp_ns >= options.checkpoint_interval_ns) {
      checkpoints.push_back(make_checkpoint(stamp_ns, absolute_index));
    }
  }

  // Recent checkpoints older than `dense_from` keep one per checkpoint_interval_ns.
  void age_recent(TimeNs dense_from) {
    while (recent.size() > 1 && recent.front().stamp_ns < dense_from) {
      const bool keep =
          checkpoints.empty() || checkpoints.back().stamp_ns == std::numeric_limits<TimeNs>::min() ||
          recent.front().stamp_ns - checkpoints.back().stamp_ns >= options.checkpoint_interval_ns;
      if (keep) {
        checkpoints.push_back(std::move(recent.front()));
      } else {
        recycle(std::move(recent.front()));
      }
      recent.pop_front();
    }
  }

  // Restores the newest state that includes no frame stamped after `stamp_ns` and drops the
  // checkpoints after it. Returns the absolute history index to replay from.
  std::size_t rewind_to(TimeNs stamp_ns) {
    // A state may be restored if every frame it includes is stamped at or before `stamp_ns`.
    const auto after = [](TimeNs stamp, const Checkpoint& c) { return stamp < c.core.last_stamp_ns; };
    std::deque<Checkpoint>* tier = &recent;
    auto found = std::upper_bound(recent.begin(), recent.end(), stamp_ns, after);
    if (found == recent.begin()) {
      while (!recent.empty()) {
        recycle(std::move(recent.back()));
        recent.pop_back();
      }
      tier = &checkpoints;
      found = std::upper_bound(checkpoints.begin(), checkpoints.end(), stamp_ns, after);
    }
    --found;  // exists: the caller checked the oldest checkpoint
    core = found->core;
    const std::size_t index = found->index;
    while (tier->end() != found + 1) {
      recycle(std::move(tier->back()));
      tier->pop_back();
    }
    return index;
  }

  void trim() {
    const TimeNs oldest_kept = core.last_stamp_ns - options.rewind_horizon_ns;
    while (checkpoints.size() >= 2 && checkpoints[1].stamp_ns <= oldest_kept) {
      recycle(std::move(checkpoints.front()));
      checkpoints.pop_front();
    }
    const Checkpoint* oldest = oldest_checkpoint();
    if (oldest == nullptr) return;
    while (history_base < oldest->index && !history.empty()) {
      history.pop_front();
      ++history_base;
    }
  }

  // Adaptive process noise (docs/estimator.md, "Adaptive process noise"): the prior d² of each
  // update is χ²₂ (mean 2) while the motion model holds; a manoeuvre the white-acceleration model
  // does not cover pushes it up for several updates before the marker leaves the gate. A short
  // average above the target multiplies the track's σ² (by at most 4 per update, up to max_scale);
  // without such evidence the factor decays back to 1, so a slow marker keeps the low noise.
  void adapt_process_noise(Track& track, double d2, TimeNs stamp_ns) const {
    const double max_scale = std::max(1.0, options.process_noise_max_scale);
    if (max_scale <= 1.0) return;
    if (track.q_stamp_ns != 0 && stamp_ns > track.q_stamp_ns) {
      const double decay = std::exp(-ns_to_seconds(stamp_ns - track.q_stamp_ns) /
                                    ns_to_seconds(options.process_noise_adapt_decay_ns));
      track.q_scale = 1.0 + (track.q_scale - 1.0) * decay;
    }
    track.q_stamp_ns = std::max(track.q_stamp_ns, stamp_ns);
    track.nis_adapt = track.nis_updates <= 1 ? d2 : 0.5 * track.nis_adapt + 0.5 * d2;
    const double target = options.process_noise_nis_target;
    if (track.nis_adapt > target) {
      track.q_scale = std::min(max_scale, track.q_scale * std::min(track.nis_adapt / target, 4.0));
    }
  }

  // fast_acceleration_time_constant_ns: an isolated fast track's acceleration input follows the
  // rate of change of its velocity between consecutive updates (within kFrameGapNs), low-passed;
  // any other track, or one after a gap, predicts with constant velocity.
  void estimate_acceleration(Track& track, TimeNs stamp, double innovation_px) const;
  // one_view_carried_sigma_m: the depth along the camera's ray of a one-view update from where the
  // track's neighbours carried it.
  void pin_one_view_depth(Track& track, int camera_index, TimeNs stamp);
  void damp_one_view_velocity(Track& track, int camera_index, TimeNs stamp, TimeNs previous_update_ns) const;
  int one_view_camera(const Track& track, TimeNs stamp) const;
  bool uncertain_elsewhere(const Track& track, int camera_index, TimeNs stamp) const;
  bool beyond_return_reach(std::size_t t, const Projected& projected, const Eigen::Vector2d& pixel,
                           int camera_index, TimeNs stamp);
  std::optional<Eigen::Vector3d> trusted_carried_position(const Track& track, TimeNs stamp) const;
  // return_fresh_max_jump_m: whether `pixel` of camera_index continues no blob of that camera's
  // previous frame (within kFreshBlobPx), offered to an established `track` (beyond_return_reach).
  bool fresh_blob(const Track& track, const Eigen::Vector2d& pixel, int camera_index, TimeNs stamp) const;
  // Keeps the camera's blobs for the next frame's fresh_blob.
  void note_last_frame(int camera_index, TimeNs stamp, const std::vector<Eigen::Vector2d>& pixels);
  // The points of the tracks a second camera updated within kFrameGapNs of `now_ns` (anchor_neighbour).
  std::vector<AnchorPoint> neighbour_points(TimeNs now_ns) const;
  // Where `track`'s anchor's neighbours carried it by `now_ns` (a fit within kNeighbourMaxFitRmsM),
  // if its anchor has three neighbours or more and is within kNeighbourMemoryNs.
  std::optional<Eigen::Vector3d> carried_by_neighbours(const Track& track, TimeNs now_ns) const;
  bool owned_elsewhere(std::size_t t, std::size_t b, const std::vector<Eigen::Vector2d>& pixels,
                       int camera_index, TimeNs stamp, const Core::BlobOwners& last,
                       const std::vector<GatedPair>& gated);
  Core::BlobOwners start_owners(int camera_index, TimeNs stamp);
  void carry_owners(const Core::BlobOwners& last, int camera_index, TimeNs stamp,
                    const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& used);
  bool twin_waits(std::size_t t, std::size_t b, const std::vector<GatedPair>& pairs,
                  const std::vector<std::pair<std::size_t, std::size_t>>& assignment, int camera_index,
                  TimeNs stamp);

  // A fast track (a swung or thrown object) keeps σ² × fast_process_noise_scale while it moves
  // fast and for fast_hold_ns after (a ball's catch, a club's turn at the top): its next
  // manoeuvre comes without the few updates of evidence the adaptive factor waits for
  // (docs/estimator.md, "Fast tracks").
  void hold_fast_process_noise(Track& track, TimeNs stamp_ns) const {
    // Part of the adaptive process noise: off with it (process_noise_max_scale 1).
    if (options.fast_process_noise_scale <= 0 || options.process_noise_max_scale <= 1.0 || !track.fast ||
        stamp_ns - track.last_fast_ns > options.fast_hold_ns)
      return;
    double scale = options.fast_process_noise_scale;
    if (options.fast_isolated_process_noise_scale > 0 && lone_fast(track))
      scale = options.fast_isolated_process_noise_scale;
    track.q_scale = std::max(track.q_scale, scale);
  }
  // Fast by kIsolatedFastUpdates updates of its own (not yet a rejoined track: a ghost of clutter
  // that took a lost club head's id would spread its gate over more clutter) and no other confirmed
  // track within fast_isolation_m: a gate as wide as its own factor gives has no neighbour's blob
  // to take, and its acceleration input no neighbour to be confused with (a thrown ball; not a
  // club's marker, 0.4 m from the next).
  bool lone_fast(const Track& track) const {
    if (!track.fast || track.fast_updates < kIsolatedFastUpdates) return false;
    const double r2 = options.fast_isolation_m * options.fast_isolation_m;
    const Eigen::Vector3d p = track.state.position();
    for (const Track& other : core.tracks)
      if (other.confirmed && other.id != track.id && (other.state.position() - p).squaredNorm() < r2)
        return false;
    return true;
  }

  // Confirmed, settled and updated within kFrameGapNs: its marker is followed.
  static bool followed(const Track& track, TimeNs stamp_ns) {
    return track.confirmed && track.updates >= kSettledUpdates &&
           stamp_ns - track.last_update_ns <= kFrameGapNs;
  }
  // The track with this id (nullptr: none). Tracks stay in id order: created with increasing ids,
  // removed in place, a reused id inserted before the newer ones.
  const Track* find_track(std::int64_t id) const {
    const auto found = std::lower_bound(core.tracks.begin(), core.tracks.end(), id,
                                        [](const Track& track, std::int64_t key) { return track.id < key; });
    return found != core.tracks.end() && found->id == id ? &*found : nullptr;
  }
  // The followed track with this id (nullptr: none).
  const Track* followed_track(std::int64_t id, TimeNs stamp_ns) const {
    const Track* track = find_track(id);
    return track != nullptr && followed(*track, stamp_ns) ? track : nullptr;
  }

  // Keeps a fast track's rigid partner while their distance holds; otherwise chooses the nearest
  // followed, settled track again (Track::partner_id).
  void note_partner(Track& track, TimeNs stamp_ns) {
    const Eigen::Vector3d p = track.state.position();
    if (const Track* partner = track.partner_id != 0 ? followed_track(track.partner_id, stamp_ns) : nullptr;
        partner != nullptr &&
        std::abs((partner->position_at(stamp_ns) - p).norm() - track.partner_distance_m) <= kRigidToleranceM)
      return;
    track.partner_id = 0;
    double best = std::numeric_limits<double>::infinity();
    for (const Track& other : core.tracks) {
      if (other.id == track.id || !followed(other, stamp_ns)) continue;
      const double d = (other.position_at(stamp_ns) - p).norm();
      if (d < best) {
        best = d;
        track.partner_id = other.id;
      }
    }
    track.partner_distance_m = best;
    track.partner_since_ns = stamp_ns;
  }

  void note_update(Track& track, int camera, TimeNs stamp_ns) {
    if (stamp_ns - track.last_update_ns > options.coast_after_ns) track.resumed_ns = stamp_ns;
    track.last_update_ns = std::max(track.last_update_ns, stamp_ns);
    track.frames_at_update = core.frames_applied;
    ++track.updates;
    if (track.camera_last_update.size() < models.size()) track.camera_last_update.resize(models.size(), 0);
    if (track.camera_last_update[camera] == 0) ++track.distinct_cameras;
    track.camera_last_update[camera] = std::max<TimeNs>(track.camera_last_update[camera], stamp_ns);
    for (std::size_t k = 0; k < track.camera_last_update.size(); ++k) {
      if (static_cast<int>(k) != camera && stamp_ns - track.camera_last_update[k] <= kFrameGapNs &&
          track.camera_last_update[k] != 0) {
        track.seen_position = track.state.position();
        track.seen_velocity = track.state.velocity();
        track.seen_ns = stamp_ns;
        if (track.fast) note_partner(track, stamp_ns);
        break;
      }
    }
    if (!track.confirmed && (track.distinct_cameras >= required_cameras() ||
                             (track.distinct_cameras >= 2 &&
                              track.updates >= static_cast<std::uint64_t>(options.confirm_updates)))) {
      track.confirmed = true;
      track.pending_reacquire = track.fresh && options.reacquire_sigma_m > 0;
      ++core.tracks_confirmed;
    }
  }

  // Applies a history entry's frame; `replaying`: the entry was applied before (rewind).
  void apply(Entry& entry, bool replaying);
  // The frame's residuals against the confirmed tracks the other cameras determine, to the
  // calibration monitor (docs/continuous_calibration.md, "Residuals").
  // `gating`: the frame's gating, which association then uses (its projections are shared).
  void monitor_frame(const Entry& entry, const std::vector<Eigen::Vector2d>& pixels, const Gating& gating);
  // Whether this monitored frame of `camera` is sampled for a correction (quarantined) or a
  // refinement (following drift, one per refine_sample_interval_ns): `correct` mode only.
  bool wants_positions(int camera, TimeNs stamp) const;
  // The stamp of the bump correction whose settling refinement is pending (0: none).
  TimeNs settling_since(int camera) const {
    return camera < static_cast<int>(settle_since_ns.size()) ? settle_since_ns[camera] : 0;
  }
  // Mode correct, a quarantined camera's monitored frame: collected; with enough, its pose is
  // estimated again and, when well determined, applied (docs/continuous_calibration.md).
  void collect_for_resection(int camera, TimeNs stamp, std::vector<Eigen::Vector3d> points,
                             const std::vector<Eigen::Vector2d>& pixels);
  // Mode correct, a camera in use: collected; every refine_frames its pose is refined and, when
  // determined and significantly different, applied (docs/continuous_calibration.md).
  void collect_for_refinement(int camera, TimeNs stamp, std::vector<Eigen::Vector3d> points,
                              const std::vector<Eigen::Vector2d>& pixels);
  void apply_correction(int camera, TimeNs stamp, const ResectionResult& result,
                        CalibrationCorrection::Kind kind = CalibrationCorrection::Kind::kBump);
  // `early`: the gating already made for this frame (a monitored frame), if any.
  void associate(Entry& entry, const std::vector<Eigen::Vector2d>& pixels, std::vector<char>& used,
                 bool replaying, std::optional<Gating> early = std::nullopt);
  // A replayed frame's previous association, checked against today's states: every pair must
  // still pass its gate. Then applied (true); otherwise nothing changes (false).
  bool reassociate(const Entry& entry, const std::vector<Eigen::Vector2d>& pixels, std::vector<char>& used);
  // Updates track `t` with blob `blob` through its prediction to the frame's stamp.
  void commit_pair(std::size_t t, const Projected& projected, const Eigen::Vector2d& pixel, std::size_t blob,
                   int camera_index, TimeNs stamp, std::vector<char>& used);
  // At a second camera's update that ends a stretch of one camera's: caps the velocity's change.
  void cap_return_velocity(Track& track, const Eigen::Vector3d& predicted_velocity);
  // Tentative tracks inside the image that took no blob were not seen.
  void count_misses(const std::vector<char>& track_done, const std::vector<char>& in_view);
  // Confirmed tracks in view of `camera_index`'s frame at `stamp` that it did not update: missed_ns.
  void note_missed(const std::vector<char>& track_done, const std::vector<char>& in_view, int camera_index,
                   TimeNs stamp);
  // Adaptive process noise on: a fast confirmed track in view that took no blob although it was
  // updated a moment ago takes the one blob left in its manoeuvre gate (σ² ×
  // process_noise_max_scale), if no other such track claims it (docs/estimator.md, "Manoeuvres").
  void recover_manoeuvres(Entry& entry, const std::vector<Eigen::Vector2d>& pixels, std::vector<char>& used,
                          std::vector<char>& track_done, const std::vector<char>& in_view);
  std::uint64_t tracks_digest() const;
  Gating gate(const CameraModel& camera, TimeNs stamp, const std::vector<Eigen::Vector2d>& pixels,
              const std::vector<char>& used) const;
  void initiate(const FeatureFrame& frame, int camera_index, const std::vector<Eigen::Vector2d>& pixels,
                const std::vector<char>& used,
                const std::vector<std::pair<std::int64_t, std::size_t>>& associations);
  // Whether only one camera has updated `track` for kOneViewNs (or ever).
  static bool one_view(const Track& track, TimeNs stamp) {
    return !track.fast && (track.seen_ns == 0 || stamp - track.seen_ns > kOneViewNs);
  }
  // Whether another camera's frame, applied within kFrameGapNs of `stamp`, had `track` in view and
  // did not update it (missed_ns). Live, a frame of another camera that has not arrived yet is no
  // evidence that the marker left that view: the one-view rules wait until it is applied.
  static bool missed_elsewhere(const Track& track, int camera_index, TimeNs stamp) {
    return track.missed_ns != 0 && track.missed_camera != camera_index &&
           stamp - track.missed_ns <= kFrameGapNs;
  }
  // one_view_ghost_ns: `track` was never published, no two cameras have updated it together for
  // that long, and another camera's frame applied within kFrameGapNs had it in view and missed it.
  bool one_view_ghost(const Track& track, TimeNs now_ns) const {
    const TimeNs limit = options.one_view_ghost_ns;
    return limit > 0 && !track.fast && !was_published(track.id) && now_ns - track.last_seen_ns() > limit &&
           track.missed_ns != 0 && now_ns - track.missed_ns <= kFrameGapNs;
  }
  // Moves the one-view `track` to `candidate` (made with its blob and another camera's) under its
  // id, unless it is already there or may_reanchor refuses: whether it did.
  bool reanchor(Track& track, const InitiationCandidate& candidate, TimeNs stamp);
  // The σ of a new track's velocity measured by its candidate (init_measured_velocity_sigma_mps,
  // or init_velocity_relative_sigma of its speed), or init_velocity_sigma_mps without one.
  double candidate_velocity_sigma(const InitiationCandidate& candidate) const {
    return candidate.has_velocity ? std::max(options.init_measured_velocity_sigma_mps,
                                             options.init_velocity_relative_sigma * candidate.velocity.norm())
                                  : options.init_velocity_sigma_mps;
  }
  // Whether the one-view `track` may move to `position`: within its reach from where two cameras
  // last placed it (within_seen_reach: else the point is another marker's) or within
  // kReanchorCarriedM of where its neighbours carried it (a track that a stray view took far from
  // its marker: its last two-camera position is that wrong point), and no other track within
  // kOneViewClearM of it.
  bool may_reanchor(const Track& track, const Eigen::Vector3d& position, TimeNs stamp) const {
    if (!within_seen_reach(track, position, stamp)) {
      const auto carried = carried_by_neighbours(track, stamp);
      if (!carried || (*carried - position).norm() > kReanchorCarriedM) return false;
    }
    return std::none_of(core.tracks.begin(), core.tracks.end(), [&](const Track& other) {
      return &other != &track && (other.position_at(stamp) - position).norm() < kOneViewClearM;
    });
  }
  // A new track's id: an undone track's within kReuseIdGate of `position` at `stamp` (the nearest,
  // with its pending rejoin), else a new one. Near a lost fast track (rejoin_fast_track) the new
  // one takes that track's id once confirmed (`rejoin_id`; `rejoined_peak_speed` is then that
  // track's peak speed, else 0); otherwise `fresh` is set.
  std::int64_t id_for(const Eigen::Vector3d& position, TimeNs stamp, double& rejoined_peak_speed,
                      std::int64_t& rejoin_id, bool& fresh);
  // rejoin_fast_tracks: the id and peak speed of the confirmed fast track that lost its marker
  // within reach of `position`, clearly the nearest of all that lost theirs. None when ambiguous.
  std::optional<std::pair<std::int64_t, double>> rejoin_fast_track(const Eigen::Vector3d& position,
                                                                   TimeNs stamp);
  // The highest peak speed of the confirmed fast tracks that lost their marker (not updated for
  // kFrameGapNs; a followed one has its blobs) and could be at `position` now (within their peak
  // speed x max(gap, 50 ms) + 5 cm); 0 when none.
  double nearby_fast_speed(const Eigen::Vector3d& position, TimeNs stamp) const;
  // The trace of a track's predicted position covariance at `stamp` (a bound: the process
  // noise's share taken as σ² dt³).
  double predicted_position_trace(const Track& track, TimeNs stamp) const;
  // reacquire_sigma_m: a confirmed track lost for longer than kFrameGapNs, through at least
  // kFramesWithoutIt applied frames (or through a pause of the input, paused()), whose predicted
  // position is less certain than that (`trace`: predicted_position_trace, if known) takes no blob
  // of its own; initiation finds its marker again (reacquire).
  bool held_back(const Track& track, TimeNs stamp, std::optional<double> trace = std::nullopt) const;
  // The interval since the previous applied frame: a pause of the input ends here when it is far
  // longer than usual (pause_end_ns).
  void note_interval(TimeNs stamp_ns, int camera_index);
  // The first frame newer than the suspension: the suspended tracks return in id order, or are
  // dropped when the input stopped for longer than kMaxSuspendNs.
  void resume_suspended(TimeNs stamp_ns);
  // Confirmed and last updated before the input's last pause: it coasted through it.
  bool paused(const Track& track) const {
    return track.confirmed && track.last_update_ns < core.pause_end_ns;
  }
  // How long `track` has gone without an update at `now_ns`, less the input's last pause when it
  // coasted through it: a pause says nothing of its marker (a loaded machine held every camera's
  // frames for 0.44-0.6 s, and every track of the demo came back under a new id: test_hostile).
  TimeNs silence(const Track& track, TimeNs now_ns) const {
    const TimeNs since = now_ns - track.last_update_ns;
    // A pause longer than kMaxSuspendNs is cameras stopped, not a stall: it counts.
    if (track.last_update_ns > core.pause_start_ns || now_ns < core.pause_end_ns ||
        core.pause_end_ns - core.pause_start_ns > kMaxSuspendNs)
      return since;
    return since - (core.pause_end_ns - core.pause_start_ns);
  }
  // The id of the one held-back track whose prediction gates `position` (χ²₃), every other
  // held-back track that gates it at least kClearRatio times farther (d²) and lies
  // reacquire_distance_ratio times farther (m), and (unless fast) within reacquire_max_seen_distance_m
  // of its last two-camera position or of where its velocity then carries it. None when ambiguous.
  // Held-back tracks in `claimed` (ids other new tracks took at this instant) are no candidates.
  std::optional<std::int64_t> reacquire(const Eigen::Vector3d& position, TimeNs stamp,
                                        const std::vector<std::int64_t>& claimed = {}) const;
  // Whether `track` is a candidate of reacquire: held back, not waited for by a rejoin
  // (rejoin_fast_track), not in `claimed`.
  // `one_view_too`: a confirmed track that one camera alone has updated for kOneViewNs qualifies as
  // well as a held-back one (reacquire_by_neighbours).
  bool reacquire_candidate(const Track& track, TimeNs stamp, const std::vector<std::int64_t>& claimed,
                           bool one_view_too = false) const;
  // reacquire's first test (reacquire_way_m): the one candidate whose prediction gates `position`
  // (χ²₃) best and whose way (way_distance) passes within reacquire_way_m of it, every other gating
  // candidate's way kWayClearRatio times farther.
  std::optional<std::int64_t> reacquire_on_way(const Eigen::Vector3d& position, TimeNs stamp,
                                               const std::vector<std::int64_t>& claimed) const;
  // The distance of `position` from `track`'s way: the segment from where two cameras last placed
  // it to where its velocity then carries it at `stamp` (its position when never seen by two).
  double way_distance(const Track& track, const Eigen::Vector3d& position, TimeNs stamp) const;
  // Mahalanobis d² of `position` from `track`'s prediction at `stamp`, with init_position_sigma_m
  // added (reacquire's gate: kReacquireGateChi2).
  double reacquire_d2(const Track& track, const Eigen::Vector3d& position, TimeNs stamp) const;
  // Whether `position` lies within reacquire_max_seen_distance_m of where two cameras last placed
  // `track` (or of where its velocity then carries it), plus its speed times the input's pause if
  // it coasted through it; always for a fast track.
  bool within_seen_reach(const Track& track, const Eigen::Vector3d& position, TimeNs stamp) const;
  // After the rounds of reacquire_confirmed, after a pause of the input: the `pending` new tracks
  // (at most kMaxAssigned) and the paused held-back tracks not `claimed`, matched as a whole
  // (renames). See the definition.
  void reacquire_by_assignment(std::vector<Track*>& pending, TimeNs now_ns,
                               std::vector<std::int64_t>& claimed,
                               std::vector<std::pair<std::int64_t, std::int64_t>>& renames) const;
  // Whether a new track at `position` is as far from `lost`'s rigid partner (Track::partner_id) as
  // `lost` was, within rejoin_rigid_margin_m; true when it has none or the partner is not followed.
  bool keeps_partner_distance(const Track& lost, const Eigen::Vector3d& position, TimeNs stamp) const;
  // `track`'s rigid partner (held kRigidMinNs before its last two-camera update) if it is followed at
  // `stamp`, else nullptr.
  const Track* rigid_partner(const Track& track, TimeNs stamp) const;
  // partner_update_margin_m: whether the fast track t, taking `pixel`, would land further off its
  // distance to its rigid partner than the margin (or than its prediction's offset plus the margin,
  // when the prediction is already further off): refused (true).
  bool off_rigid_partner(std::size_t t, const Projected& projected, const Eigen::Vector2d& pixel,
                         TimeNs stamp);
  // Tracks confirmed in this frame take the id of the held-back track whose marker they are
  // (reacquire); tracks stay in id order.
  void reacquire_confirmed(TimeNs now_ns);
  // reacquire_neighbours_m: anchors the confirmed tracks that no second camera updated for
  // kFrameGapNs since their last anchor (Track::anchor), to the followed tracks near them (with
  // reacquire_group, then to those lost with them).
  void note_anchors(TimeNs now_ns);
  // After the other tests of reacquire_confirmed (with reacquire_group, before them too): each
  // `pending` new track takes the id of the held-back, one-view or departed track whose neighbours
  // carried its anchor within reacquire_neighbours_m of it (with new tracks standing in for some
  // of them: within kStandInReachM, held-back and one-view tracks only), when every other such
  // track's is kNeighbourClearRatio times farther, no other pending track is that near it, and no
  // followed track within kNeighbourCrowdM of it (renames).
  void reacquire_by_neighbours(std::vector<Track*>& pending, TimeNs now_ns,
                               std::vector<std::int64_t>& claimed,
                               std::vector<std::pair<std::int64_t, std::int64_t>>& renames) const;
  // Tracks confirmed with a pending rejoin take the lost fast track's id, which is removed, once
  // they would be published (determined), unless its marker was found again or another track
  // took it first.
  void rejoin_confirmed(TimeNs now_ns);
  void prune(TimeNs now_ns);
  std::vector<TrackedPoint> confirmed_points(TimeNs stamp_ns) const;
  // Inserts `late` (in stamp order, each older than the newest applied frame, none older than the
  // oldest checkpoint) into the history and replays from before the oldest of them: one rewind.
  void replay_with(std::vector<Entry> late);
  TrackRecord to_record(const Track& track, TimeNs stamp_ns) const;
  // Whether a record's position is known well enough to publish (publish_max_sigma_m).
  // With `published` (the track's last record was), up to kKeepPublishedFactor times the limit.
  bool determined(const TrackRecord& record, bool published, bool fast = false) const;
  // Whether `track` is published at `stamp_ns`: determined, or a fast track whose cameras confirm
  // its predictions (fast_publish_innovation_px).
  bool publishable(const Track& track, const TrackRecord& record, TimeNs stamp_ns) const;
  // publish_max_innovation_px: whether the cameras that updated `track` in the last 10 ms find its
  // blobs near its predictions.
  bool views_agree(const Track& track) const;
  // A camera's limit for views_agree: publish_max_innovation_px, or kInnovationLevels × its level.
  double innovation_limit(std::size_t camera) const;
  // Whether the other cameras' last blobs of `track` (each within kOneViewNs, moved to `stamp` along
  // its motion) triangulate consistently, at least two of them, to a point that `pixel` in
  // camera_index misses by more than that camera's innovation limit: that view is the odd one.
  bool odd_view(const Track& track, int camera_index, const Eigen::Vector2d& pixel, TimeNs stamp) const;
  // dispute_odd_views: a confirmed track whose views disagree (views_agree), whose average
  // innovation in camera_index is beyond that camera's limit and whose view there is odd
  // (odd_view) offers the blob it took there to the initiator as a probe. If the blob pairs with
  // another camera's unmatched tracklet into a point no track explains, it is another marker's:
  // the track is not offered camera_index's blobs for kDisputedViewNs, and the blob, unmatched from
  // the next frame on, starts that marker's track (docs/estimator.md, "Odd views").
  void dispute_views(int camera_index, TimeNs stamp, const std::vector<Eigen::Vector2d>& pixels,
                     const std::vector<std::pair<std::int64_t, std::size_t>>& associations,
                     const std::function<bool(const Eigen::Vector3d&)>& occupied);
  // An update's innovation (px) in `camera`: the track's last and moving average there (views_agree,
  // publishable), and the camera's typical innovation over confirmed tracks.
  void note_innovation(Track& track, std::size_t camera, float innovation) {
    track.camera_innovation_px.resize(track.camera_last_update.size(), 0.0F);
    track.camera_innovation_avg_px.resize(track.camera_last_update.size(), 0.0F);
    track.camera_innovation_px[camera] = innovation;
    float& average = track.camera_innovation_avg_px[camera];
    average = average == 0.0F ? innovation : 0.7F * average + 0.3F * innovation;
    double& level = core.camera_innovation_level[camera];
    if (track.confirmed) level = level == 0.0 ? innovation : 0.99 * level + 0.01 * innovation;
  }
};

void Tracker::Impl::apply(Entry& entry, bool replaying) {
  const FeatureFrame& frame = entry.frame;
  const int camera_index = entry.camera;
  note_interval(frame.stamp_ns, camera_index);
  if (!core.suspended.empty() && frame.stamp_ns > core.suspended_at_ns) resume_suspended(frame.stamp_ns);
  core.last_stamp_ns = std::max(core.last_stamp_ns, frame.stamp_ns);
  ++core.frames_applied;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(frame.blobs.size());
  std::vector<char> used(frame.blobs.size(), 0);
  for (std::size_t j = 0; j < frame.blobs.size(); ++j) {
    pixels.emplace_back(frame.blobs[j].x, frame.blobs[j].y);
    if (!std::isfinite(pixels.back().x()) || !std::isfinite(pixels.back().y())) used[j] = 1;
  }
  // Bodies and point tracks use the same blobs: the point tracks of body markers feed
  // identification, and the poses stay independent of the point tracks' lifecycle.
  const std::vector<char> excluded = used;
  std::optional<Gating> early;  // a monitored frame's gating, made once for monitor and association
  if (calibration_mode != CalibrationMode::kOff) {
    if (!replaying && monitor.due(camera_index, frame.stamp_ns)) {
      early = gate(*models[camera_index], frame.stamp_ns, pixels, used);
      monitor_frame(entry, pixels, *early);
      monitor.judge(camera_index, frame.stamp_ns);
    }
    // A quarantined camera's blobs are not fused: tracking continues on the other cameras.
    if (monitor.quarantined(camera_index)) {
      if (!replaying) monitor.note_withheld(camera_index, pixels.size());
      prune(frame.stamp_ns);
      return;
    }
  }
  associate(entry, pixels, used, replaying, std::move(early));
  note_last_frame(camera_index, frame.stamp_ns, pixels);
  initiate(frame, camera_index, pixels, used, entry.associations);
  prune(frame.stamp_ns);
  if (!core.bodies.empty()) {
    std::vector<char> taken(pixels.size(), 0);
    core.bodies.process_frame(camera_index, *models[camera_index], frame.stamp_ns, pixels, excluded, taken);
    if (core.bodies.wants_points(frame.stamp_ns))
      core.bodies.identify(frame.stamp_ns, confirmed_points(frame.stamp_ns));
  }
}

namespace {

// Largest eigenvalue of a symmetric 2 × 2 matrix.
double largest_eigenvalue(const Eigen::Matrix2d& S) {
  const double half_trace = 0.5 * (S(0, 0) + S(1, 1));
  const double half_difference = 0.5 * (S(0, 0) - S(1, 1));
  return half_trace + std::sqrt(half_difference * half_difference + S(0, 1) * S(1, 0));
}

}  // namespace

// A monitored track's blob is usually this near its prediction: the nearest-two search looks
// within unique_ratio times this first (PointsByX::nearest_two).
constexpr double kUsuallyNearPx = 4.0;

// Residuals are taken with the fusion path's own prediction and projection (predicted(),
// project_point()), but associated by a wider, unambiguous nearest-blob rule instead of the gate:
// a bumped camera's blobs fall outside the gate (0.5° is ~9 px at f = 1000 px, the gate of a
// well-tracked marker ~3 px), and gated innovations alone would hide the bias by censoring it.
// Issue 36's cost (32 cameras x 120 Hz): every monitored frame walks every track, so the walk
// does only what the residuals need (docs/continuous_calibration.md, "Cost").
void Tracker::Impl::monitor_frame(const Entry& entry, const std::vector<Eigen::Vector2d>& pixels,
                                  const Gating& gating) {
  constexpr std::size_t kMaxBlobs = 1024;  // a frame of garbage is not worth monitoring
  if (pixels.empty() || pixels.size() > kMaxBlobs) return;
  const auto& o = options.calibration;
  const CameraModel& camera = *models[entry.camera];
  const TimeNs stamp = entry.frame.stamp_ns;
  // Positions are collected only for a frame that a correction or a refinement will sample.
  const bool collect = wants_positions(entry.camera, stamp);
  std::vector<Eigen::Vector2d> predicted_pixels;  // every live track in view, for isolation
  std::vector<std::size_t> candidates;            // indices into core.tracks
  std::vector<std::size_t> candidate_pixel;       // ... and into predicted_pixels
  std::vector<Eigen::Vector3d> determined;        // their positions, for a correction
  predicted_pixels.reserve(core.tracks.size());
  candidates.reserve(core.tracks.size());
  candidate_pixel.reserve(core.tracks.size());
  for (std::size_t i = 0; i < core.tracks.size(); ++i) {
    const Track& track = core.tracks[i];
    const auto& pixel = gating.pixel[i];  // gate(): the same position_at(stamp), depth and projection
    if (!pixel) continue;
    predicted_pixels.push_back(*pixel);
    if (!track.confirmed || stamp - track.last_update_ns > options.coast_after_ns) continue;
    if (!camera.in_image(*pixel, 0.0)) continue;
    // Another camera's recent update is the cheaper test (the monitor's is a lookup).
    int others = 0;
    for (std::size_t k = 0; k < track.camera_last_update.size() && others < o.min_other_cameras; ++k) {
      const TimeNs last = track.camera_last_update[k];
      if (static_cast<int>(k) != entry.camera && last != 0 && stamp - last <= o.other_camera_window_ns)
        ++others;
    }
    if (others < o.min_other_cameras) continue;
    if (!monitor.wants(entry.camera, track.id, stamp)) continue;
    if (collect) determined.push_back(track.position_at(stamp));
    candidates.push_back(i);
    candidate_pixel.push_back(predicted_pixels.size() - 1);
  }
  if (collect) {
    // Quarantined and settling after a bump's correction: both (a new try at the bump, and the
    // settling refinement's window, gathered through the quarantine).
    const bool quarantined = monitor.quarantined(entry.camera);
    if (quarantined && settling_since(entry.camera) != 0) {
      collect_for_resection(entry.camera, stamp, determined, pixels);
      collect_for_refinement(entry.camera, stamp, std::move(determined), pixels);
    } else if (quarantined) {
      collect_for_resection(entry.camera, stamp, std::move(determined), pixels);
    } else {
      collect_for_refinement(entry.camera, stamp, std::move(determined), pixels);
    }
  }
  // The frame's blobs near some live track's prediction (a bumped camera's are near none). Most
  // blobs are in the gate of a track whose prediction is that near; the others are searched.
  const double search2 = o.search_px * o.search_px;
  std::vector<char> near(pixels.size(), 0);
  for (const GatedPair& pair : gating.gated)
    if ((pixels[pair.col] - *gating.pixel[pair.row]).squaredNorm() <= search2) near[pair.col] = 1;
  const PointsByX predictions(predicted_pixels);
  for (std::size_t j = 0; j < pixels.size(); ++j)
    if (!near[j]) near[j] = predictions.any_within(pixels[j], o.search_px) ? 1 : 0;
  const auto explained = static_cast<std::size_t>(std::count(near.begin(), near.end(), 1));
  monitor.add_blobs(entry.camera, stamp, pixels.size(), explained);
  const std::vector<char> crowded = predictions.crowded(o.isolation_px);
  const PointsByX blobs(pixels);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    if (crowded[candidate_pixel[c]]) continue;
    const Track& track = core.tracks[candidates[c]];
    // The gating's projection when it made one with the same process noise (not adapted).
    std::optional<PointProjection> projection;
    const auto& shared = gating.projected[candidates[c]];
    if (shared && track.sigma2(options.process_noise) == options.process_noise) {
      projection = shared->projection;
    } else {
      projection = project_point(predicted(track.state, stamp, options.process_noise), camera,
                                 options.measurement_noise_px);
    }
    if (!projection ||
        largest_eigenvalue(projection->S) > o.max_predicted_sigma_px * o.max_predicted_sigma_px)
      continue;
    // Within unique_ratio x search_px: the blob taken (<= search_px) and the next one it is
    // compared with; the gate of `seen` (<= max_predicted_sigma_px wide) is far inside.
    const NearestTwo nearest =
        blobs.nearest_two(projection->pixel, kUsuallyNearPx, o.search_px, o.unique_ratio);
    const bool seen = std::isfinite(nearest.d1) &&
                      inside_gate(mahalanobis2(*projection, pixels[nearest.index]), options.gate_chi2);
    monitor.add_prediction(entry.camera, track.id, stamp, seen);
    // The nearest blob, if near enough and unambiguous (the next is unique_ratio times farther).
    if (nearest.d1 <= o.search_px && nearest.d2 >= o.unique_ratio * nearest.d1) {
      monitor.add(entry.camera, track.id, stamp, projection->pixel,
                  pixels[nearest.index] - projection->pixel);
    }
  }
}

bool Tracker::Impl::wants_positions(int camera, TimeNs stamp) const {
  if (calibration_mode != CalibrationMode::kCorrect) return false;
  if (monitor.quarantined(camera) || settling_since(camera) != 0) return true;
  if (!options.calibration.follow_drift) return false;
  return camera >= static_cast<int>(refine_sampled_ns.size()) ||
         stamp - refine_sampled_ns[camera] >= options.calibration.refine_sample_interval_ns;
}

namespace {

ResectionSample make_sample(std::vector<Eigen::Vector3d> points, const std::vector<Eigen::Vector2d>& pixels) {
  ResectionSample sample;
  sample.points_world = std::move(points);
  for (const Eigen::Vector2d& pixel : pixels)
    if (pixel.allFinite()) sample.blobs.push_back(pixel);
  return sample;
}

}  // namespace

void Tracker::Impl::collect_for_resection(int camera, TimeNs stamp, std::vector<Eigen::Vector3d> points,
                                          const std::vector<Eigen::Vector2d>& pixels) {
  const auto& o = options.calibration;
  if (resection_samples.size() < models.size()) {
    resection_samples.resize(models.size());
    resection_tried_ns.resize(models.size(), 0);
    resection_settle_until_ns.resize(models.size(), 0);
  }
  // Gathered for drift before the bump: not of this pose. Gathered since its correction: kept.
  if (settling_since(camera) == 0 && camera < static_cast<int>(refine_samples.size()))
    refine_samples[camera].clear();
  auto& samples = resection_samples[camera];
  samples.push_back(make_sample(std::move(points), pixels));
  while (samples.size() > o.resection_frames) samples.pop_front();
  if (samples.size() < o.resection_frames || stamp - resection_tried_ns[camera] < o.resection_retry_ns ||
      stamp < resection_settle_until_ns[camera])
    return;
  resection_tried_ns[camera] = stamp;
  const std::vector<ResectionSample> evidence(samples.begin(), samples.end());
  const ResectionResult result = resect_camera(*models[camera], evidence, o.resection);
  if (result.ok) {
    apply_correction(camera, stamp, result);
  } else {
    monitor.note_correction(camera, result.reason);
  }
}

void Tracker::Impl::collect_for_refinement(int camera, TimeNs stamp, std::vector<Eigen::Vector3d> points,
                                           const std::vector<Eigen::Vector2d>& pixels) {
  const auto& o = options.calibration;
  if (refine_samples.size() < models.size()) {
    refine_samples.resize(models.size());
    refine_sampled_ns.resize(models.size(), 0);
  }
  // One sample per refine_sample_interval_ns: the tracks' errors are correlated over longer than
  // that, so denser samples cost time and add little.
  // Settling after a bump: every monitored frame, for one long window.
  const TimeNs settling = settling_since(camera);
  if (settling == 0 && stamp - refine_sampled_ns[camera] < o.refine_sample_interval_ns) return;
  refine_sampled_ns[camera] = stamp;
  auto& samples = refine_samples[camera];
  if (!o.anchors.empty()) {
    const double r2 = o.anchor_radius_m * o.anchor_radius_m;
    std::erase_if(points, [&](const Eigen::Vector3d& p) {
      return std::any_of(o.anchors.begin(), o.anchors.end(),
                         [&](const Eigen::Vector3d& a) { return (a - p).squaredNorm() <= r2; });
    });
  }
  const std::size_t tracked = points.size();
  points.insert(points.end(), o.anchors.begin(), o.anchors.end());
  samples.push_back(make_sample(std::move(points), pixels));
  if (!o.anchors.empty()) {
    samples.back().weights.assign(samples.back().points_world.size(), 1.0);
    std::fill(samples.back().weights.begin() + static_cast<std::ptrdiff_t>(tracked),
              samples.back().weights.end(), o.anchor_weight);
  }
  if (settling != 0 ? stamp - settling < o.settle_refine_ns
                    : samples.size() < (o.anchors.empty() ? o.refine_frames : o.refine_anchored_frames))
    return;
  // The camera is near right: no vote for a shift, one narrow association, a few iterations.
  ResectionOptions refine = o.resection;
  refine.vote_radius_px = 0.0;
  refine.associate_px = std::min(refine.associate_px, 2.0 * refine.inlier_px);
  refine.rounds = 1;
  refine.iterations = 4;
  // 0.1 µrad, 0.1 µm: far below what a refinement resolves (0.005°, 0.5 mm); the second step of
  // a refinement is ~1e-9, the first ~1e-4 (a third step cost 1/6 of the refinement).
  refine.converged = 1e-7;
  refine.centre_prior_mm = settling != 0 ? 0.0 : o.refine_centre_prior_mm;
  refine.max_rotation_change_deg = o.refine_max_change_deg;
  refine.max_translation_change_mm = o.refine_max_change_mm;
  refine.max_rotation_sigma_deg = o.refine_max_rotation_sigma_deg;
  refine.max_translation_sigma_mm = o.refine_max_translation_sigma_mm;
  const ResectionResult result = resect_camera(*models[camera], samples, refine);
  samples.clear();
  if (settling != 0) settle_since_ns[camera] = 0;
  if (!result.ok) return;
  // Significant: the change in rotation, or in the camera's centre, beyond k sigma (the
  // translation's sigma bounds the centre's, camera_resection.cpp) and beyond the floor.
  // With anchors (known positions, not the tracks' correlated errors) the rotation's floor is lower.
  const double k = o.refine_significance;
  // Settling: the window is long, the σ honest enough; no floor.
  const double floor_deg = settling != 0       ? 0.0
                           : o.anchors.empty() ? o.refine_min_rotation_deg
                                               : o.refine_anchored_min_rotation_deg;
  const double floor_mm = settling != 0 ? 0.0 : o.refine_min_translation_mm;
  const bool turned = result.rotation_change_deg > std::max(k * result.rotation_sigma_deg, floor_deg);
  const bool moved = result.translation_change_mm > std::max(k * result.translation_sigma_mm, floor_mm);
  if (!turned && !moved) return;
  apply_correction(
      camera, stamp, result,
      settling != 0 ? CalibrationCorrection::Kind::kSettle : CalibrationCorrection::Kind::kDrift);
}

void Tracker::Impl::apply_correction(int camera, TimeNs stamp, const ResectionResult& result,
                                     CalibrationCorrection::Kind kind) {
  CalibrationCorrection correction;
  correction.kind = kind;
  correction.camera_id = camera_ids[camera];
  correction.stamp_ns = stamp;
  correction.before = models[camera]->T_world_cam();
  correction.after = result.T_world_cam;
  correction.result = result;
  *models[camera] = CameraModel(models[camera]->intrinsics(), result.T_world_cam);
  // The model object stays (pointers stay valid); what the initiator derived from it is made
  // again. The rewind history stays: this runs inside apply() on one of its entries, and the
  // camera's frames in it were withheld (quarantined) anyway; it is released only a window later,
  // past the rewind horizon.
  std::vector<const CameraModel*> pointers;
  for (const auto& model : models) pointers.push_back(model.get());
  core.initiator.set_cameras(pointers);
  corrections.push_back(std::move(correction));
  if (kind != CalibrationCorrection::Kind::kBump) return;  // small: its residual window stays
  monitor.restart(camera);
  resection_samples[camera].clear();
  // The settling refinement's window starts at the newest correction of a bump (a second one may
  // follow another bump: blobs gathered before it may be of the camera before that bump).
  if (options.calibration.settle_refine_ns > 0) {
    if (refine_samples.size() < models.size()) {
      refine_samples.resize(models.size());
      refine_sampled_ns.resize(models.size(), 0);
    }
    settle_since_ns.resize(models.size(), 0);
    settle_since_ns[camera] = stamp;
    refine_samples[camera].clear();
  }
  resection_settle_until_ns[camera] = stamp + options.calibration.resection_settle_ns;
}

std::vector<TrackedPoint> Tracker::Impl::confirmed_points(TimeNs stamp_ns) const {
  std::vector<TrackedPoint> points;
  for (const Track& track : core.tracks) {
    if (!track.confirmed || stamp_ns - track.last_update_ns > options.coast_after_ns) continue;
    TrackedPoint point;
    point.p = track.position_at(stamp_ns);
    point.v = track.state.velocity();
    point.sigma_m = std::sqrt(std::max(0.0, track.state.P.matrix().block<3, 3>(0, 0).trace() / 3.0));
    points.push_back(point);
  }
  return points;
}

// Gating (verify region, seed 003 §2.2.3.2). A cheap bound on the gate's radius from the position
// covariance selects the blobs worth the full projection and Mahalanobis test.
Gating Tracker::Impl::gate(const CameraModel& camera, TimeNs stamp,
                           const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& used) const {
  const auto& intrinsics = camera.intrinsics();
  const double focal = std::max(intrinsics.fx, intrinsics.fy);
  const double sigma2_px = options.measurement_noise_px * options.measurement_noise_px;
  const BlobGrid grid(pixels, intrinsics.width, intrinsics.height, options.grid_cell_px);
  Gating gating;
  auto& gated = gating.gated;
  auto& projected = gating.projected;
  projected.resize(core.tracks.size());
  gating.near.assign(pixels.size(), 0);
  gating.in_view.assign(core.tracks.size(), 0);
  gating.pixel.assign(core.tracks.size(), std::nullopt);
  for (std::size_t i = 0; i < core.tracks.size(); ++i) {
    const Track& track = core.tracks[i];
    const Eigen::Vector3d p = track.position_at(stamp);
    const Eigen::Vector3d p_cam = camera.T_cam_world().apply(p);
    if (p_cam.z() < options.init.min_depth_m) continue;
    const auto pixel = camera.project_camera_point(p_cam);
    if (!pixel) continue;
    gating.pixel[i] = pixel;
    const double trace = predicted_position_trace(track, stamp);
    if (held_back(track, stamp, trace)) continue;
    const double lateral = (p_cam.x() * p_cam.x() + p_cam.y() * p_cam.y()) / (p_cam.z() * p_cam.z());
    const double gain = 1.3 * focal / p_cam.z() * std::sqrt(1.0 + lateral);  // 1.3: distortion slack
    const double radius =
        std::min(std::sqrt(options.gate_chi2 * (gain * gain * trace + sigma2_px)) + 1.0, 400.0);
    if (!camera.in_image(*pixel, radius)) continue;
    gating.in_view[i] = camera.in_image(*pixel, 0.0);
    grid.for_each_near(*pixel, radius, [&](std::size_t j) {
      if (used[j]) return;
      if ((pixels[j] - *pixel).squaredNorm() > radius * radius) return;
      gating.near[j] = 1;
      if (!projected[i]) {
        Projected full;
        full.state = predicted(track.state, stamp, track.sigma2(options.process_noise));
        const auto projection = project_point(full.state, camera, options.measurement_noise_px);
        if (!projection) return;
        full.projection = *projection;
        projected[i] = std::move(full);
      }
      const double d2 = mahalanobis2(projected[i]->projection, pixels[j]);
      if (inside_gate(d2, options.gate_chi2)) gated.push_back({i, j, d2});
    });
  }
  return gating;
}

double Tracker::Impl::predicted_position_trace(const Track& track, TimeNs stamp) const {
  const double dt = ns_to_seconds(stamp - track.state.stamp_ns);
  const auto& P = track.state.P.matrix();
  return P.block<3, 3>(0, 0).trace() + 2.0 * dt * P.block<3, 3>(0, 3).trace() +
         dt * dt * P.block<3, 3>(3, 3).trace() + track.sigma2(options.process_noise) * std::abs(dt * dt * dt);
}

bool Tracker::Impl::held_back(const Track& track, TimeNs stamp, std::optional<double> trace) const {
  // Frames applied since its last update: a marker out of sight, not a pause in the input.
  constexpr std::uint64_t kFramesWithoutIt = 4;
  const double limit = options.reacquire_sigma_m;
  if (limit <= 0 || !track.confirmed || stamp - track.last_update_ns <= kFrameGapNs) return false;
  const auto uncertain = [&](double factor) {
    return trace.value_or(predicted_position_trace(track, stamp)) > factor * limit * limit;
  };
  // Coasted through a pause of the input (every camera stalled): every track near it is as
  // uncertain, and the first frames after the pause would pair tracks and blobs almost at will
  // (an id moving along a leg's markers). Held back from a third of the σ² (docs/estimator.md,
  // "After every camera stalled").
  if (paused(track)) return uncertain(1.0);
  if (core.frames_applied - track.frames_at_update < kFramesWithoutIt) return false;
  return uncertain(kUncertainFactor);
}

void Tracker::Impl::resume_suspended(TimeNs stamp_ns) {
  // Every camera's frames held for 0.9 s under attack (test_hostile: the rogue's FeatureFrames of
  // 10^6 blobs crowd the transport); the live estimator had removed every track after 0.8 s and
  // the demo's markers came back under new ids. As after a shorter pause (silence(), the
  // reach allowance in reacquire()), their new tracks now take their ids when unambiguous.
  if (stamp_ns - core.suspended_at_ns <= kMaxSuspendNs) {
    for (Track& track : core.suspended) {
      const auto at = std::lower_bound(core.tracks.begin(), core.tracks.end(), track.id,
                                       [](const Track& t, std::int64_t id) { return t.id < id; });
      core.tracks.insert(at, std::move(track));
    }
  }
  core.suspended.clear();
}

void Tracker::Impl::note_interval(TimeNs stamp_ns, int camera_index) {
  // A pause: longer than 25 ms and 8 usual intervals (a rig of one 30 Hz camera is not paused).
  constexpr double kMinPauseNs = 25e6;
  constexpr double kPauseIntervals = 8.0;
  if (core.last_stamp_ns == std::numeric_limits<TimeNs>::min() || stamp_ns <= core.last_stamp_ns) return;
  const auto interval = static_cast<double>(stamp_ns - core.last_stamp_ns);
  if (core.frame_interval_ns > 0 &&
      interval > std::max(kMinPauseNs, kPauseIntervals * core.frame_interval_ns)) {
    core.pause_start_ns = core.last_stamp_ns;
    core.pause_end_ns = stamp_ns;
    core.pause_cameras.clear();
    if (models.size() > 1) core.pause_cameras.push_back(camera_index);
    ++core.input_pauses;
    return;  // not part of the usual interval
  }
  // Frames of fewer cameras than confirm a track: the pause goes on for the tracks (test_hostile
  // under load: after a stall, one camera's held frames came 100 ms before the others'; the
  // tracks' reach from their last two-camera positions and their silence counted from the first
  // of them, and the markers came back under new ids).
  if (!core.pause_cameras.empty()) {
    if (std::find(core.pause_cameras.begin(), core.pause_cameras.end(), camera_index) ==
        core.pause_cameras.end())
      core.pause_cameras.push_back(camera_index);
    if (static_cast<int>(core.pause_cameras.size()) < required_cameras() &&
        stamp_ns - core.pause_start_ns <= kMaxSuspendNs)
      core.pause_end_ns = stamp_ns;
    else
      core.pause_cameras.clear();
  }
  core.frame_interval_ns =
      core.frame_interval_ns > 0 ? 0.95 * core.frame_interval_ns + 0.05 * interval : interval;
}

bool Tracker::Impl::keeps_partner_distance(const Track& lost, const Eigen::Vector3d& position,
                                           TimeNs stamp) const {
  // Markers of one rigid object keep their distance: a club head comes back as far from its
  // shaft's marker as it went; a clutter ghost within the head's reach, elsewhere, does not.
  if (options.rejoin_rigid_margin_m <= 0) return true;
  const Track* partner = rigid_partner(lost, stamp);
  return partner == nullptr || std::abs((position - partner->position_at(stamp)).norm() -
                                        lost.partner_distance_m) <= options.rejoin_rigid_margin_m;
}

const Track* Tracker::Impl::rigid_partner(const Track& track, TimeNs stamp) const {
  return track.partner_id != 0 && track.seen_ns - track.partner_since_ns >= kRigidMinNs
             ? followed_track(track.partner_id, stamp)
             : nullptr;
}

bool Tracker::Impl::off_rigid_partner(std::size_t t, const Projected& projected, const Eigen::Vector2d& pixel,
                                      TimeNs stamp) {
  // A club head's track at the top of the swing, followed by one camera with its depth uncertain
  // to decimetres, gates clutter blobs in the other cameras that would move it a metre; the
  // marker's own blob keeps it as far from the shaft's marker as the club is long. Only a track
  // no two cameras placed within kFrameGapNs, against a partner two cameras did: head and shaft
  // are each other's partners, and the shaft's own blobs must not be refused for a head astray.
  const double margin = options.partner_update_margin_m;
  const Track& track = core.tracks[t];
  if (margin <= 0 || !track.fast || track.partner_id == 0 || stamp - track.seen_ns <= kFrameGapNs)
    return false;
  const Track* partner = rigid_partner(track, stamp);
  if (partner == nullptr || stamp - partner->seen_ns > kFrameGapNs) return false;
  // Only an update that moves it off: a track already off (its partner astray, or a walker's
  // marker made fast by an old runaway) may take a blob that leaves it where it is.
  const Eigen::Vector3d at = partner->position_at(stamp);
  const auto off = [&](const Eigen::Vector3d& p) {
    return std::abs((p - at).norm() - track.partner_distance_m);
  };
  PointState state = projected.state;
  update(state, projected.projection, pixel, options.measurement_noise_px);
  const double before = off(projected.state.position());
  if (off(state.position()) <= (before <= margin ? margin : before + margin)) return false;
  ++core.fast_off_partner;
  return true;
}

std::optional<std::int64_t> Tracker::Impl::reacquire(const Eigen::Vector3d& position, TimeNs stamp,
                                                     const std::vector<std::int64_t>& claimed) const {
  constexpr double kClearRatio = 4.0;  // another candidate inside the gate must be this much farther (d²)
  struct Candidate {
    const Track* track = nullptr;
    double d2 = std::numeric_limits<double>::infinity();
    double distance_m = std::numeric_limits<double>::infinity();
  };
  if (const auto id = reacquire_on_way(position, stamp, claimed)) return id;
  Candidate best;
  double other_d2 = best.d2, other_m = best.distance_m;
  for (const Track& track : core.tracks) {
    if (!reacquire_candidate(track, stamp, claimed)) continue;
    const Candidate candidate{&track, reacquire_d2(track, position, stamp),
                              (position - track.position_at(stamp)).norm()};
    if (candidate.d2 < best.d2) {
      other_d2 = best.d2;
      other_m = std::min(other_m, best.distance_m);
      best = candidate;
    } else {
      other_d2 = std::min(other_d2, candidate.d2);
      other_m = std::min(other_m, candidate.distance_m);
    }
  }
  if (best.track == nullptr || best.d2 > kReacquireGateChi2 ||
      (other_d2 <= kReacquireGateChi2 && other_d2 < kClearRatio * best.d2))
    return std::nullopt;
  // In metres too: a held-back track's σ grows to decimetres (after a pause of 150 ms, 0.26 m),
  // where d² no longer tells a marker's prediction from its neighbour's 5 cm farther.
  if (options.reacquire_distance_ratio > 1.0 && other_m < options.reacquire_distance_ratio * best.distance_m)
    return std::nullopt;
  if (!keeps_partner_distance(*best.track, position, stamp) ||
      !within_seen_reach(*best.track, position, stamp))
    return std::nullopt;
  return best.track->id;
}

bool Tracker::Impl::reacquire_candidate(const Track& track, TimeNs stamp,
                                        const std::vector<std::int64_t>& claimed, bool one_view_too) const {
  // A lost fast track that a new track waits to rejoin (rejoin_confirmed) is that track's.
  const auto rejoin_pending = [this](std::int64_t id) {
    return std::any_of(core.tracks.begin(), core.tracks.end(),
                       [id](const Track& t) { return t.rejoin_id == id; });
  };
  return (held_back(track, stamp) || (one_view_too && track.confirmed && one_view(track, stamp))) &&
         !rejoin_pending(track.id) && std::find(claimed.begin(), claimed.end(), track.id) == claimed.end();
}

std::optional<std::int64_t> Tracker::Impl::reacquire_on_way(const Eigen::Vector3d& position, TimeNs stamp,
                                                            const std::vector<std::int64_t>& claimed) const {
  // A foot that lands while one camera alone sees it: its held-back track's prediction ran on, its
  // depth is uncertain and the next marker of the foot gates the new track nearly as well (d²
  // 0.41 against 0.98 in ceiling4/walk/c0/s1), and it came to rest 0.31 m from where two cameras
  // last placed it. It lies on its own way (0.04 m) and 0.10 m from its neighbour's.
  constexpr double kWayClearRatio = 2.0;
  // Ways nearer than this count as this near: the ratio of two tiny distances is noise.
  constexpr double kWayFloorM = 0.01;
  if (options.reacquire_way_m <= 0) return std::nullopt;
  struct Nearest {
    const Track* track = nullptr;
    double value = std::numeric_limits<double>::infinity();
  };
  Nearest by_way, by_d2;
  double second_way = by_way.value;
  for (const Track& track : core.tracks) {
    // A track that coasted through a pause of the input has no way: its marker went on along a
    // path its velocity does not follow for that long (within_seen_reach, reacquire_by_assignment).
    if (track.fast || paused(track) || !reacquire_candidate(track, stamp, claimed)) continue;
    const double d2 = reacquire_d2(track, position, stamp);
    if (d2 > kReacquireGateChi2) continue;
    if (d2 < by_d2.value) by_d2 = {&track, d2};
    const double way = way_distance(track, position, stamp);
    if (way < by_way.value) {
      second_way = by_way.value;
      by_way = {&track, way};
    } else {
      second_way = std::min(second_way, way);
    }
  }
  // The way settles what d² leaves within the clear ratio or what the reach refuses, never against
  // d²: without that test the run grid's swaps rose (12 s cells: 146 -> 155), a landing heel's new
  // track given another foot marker's held-back id, whose way passed nearer than its own.
  if (by_way.track == nullptr || by_way.track != by_d2.track || by_way.value > options.reacquire_way_m ||
      second_way < kWayClearRatio * std::max(by_way.value, kWayFloorM) ||
      !keeps_partner_distance(*by_way.track, position, stamp))
    return std::nullopt;
  return by_way.track->id;
}

double Tracker::Impl::way_distance(const Track& track, const Eigen::Vector3d& position, TimeNs stamp) const {
  const Eigen::Vector3d from = track.last_seen_position(), to = track.seen_position_at(stamp);
  const Eigen::Vector3d way = to - from;
  const double along =
      way.squaredNorm() > 0 ? std::clamp((position - from).dot(way) / way.squaredNorm(), 0.0, 1.0) : 0.0;
  return (position - (from + along * way)).norm();
}

double Tracker::Impl::reacquire_d2(const Track& track, const Eigen::Vector3d& position, TimeNs stamp) const {
  const double sp2 = options.init_position_sigma_m * options.init_position_sigma_m;
  const PointState state = predicted(track.state, stamp, track.sigma2(options.process_noise));
  const Eigen::Matrix3d S = state.P.matrix().block<3, 3>(0, 0) + sp2 * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d e = position - state.position();
  return e.dot(S.ldlt().solve(e));
}

bool Tracker::Impl::within_seen_reach(const Track& track, const Eigen::Vector3d& position,
                                      TimeNs stamp) const {
  // Where two cameras last placed it: a held-back track that one camera alone kept updating slid
  // along that camera's ray, and its prediction (1-9 m off at 8-65 m/s on the walk grid's
  // four-camera rigs) gated markers it never was (an elbow's id given to the sacrum). One that
  // coasted through a pause of the input was seen by two cameras until the pause, and its marker
  // went on along a path its velocity does not follow for that long (the demo's markers, 1.3 m/s
  // on curves, were 0.37-0.46 m from both after a 0.54 s pause): the allowance grows by its
  // speed times the pause.
  const TimeNs pause_ns = core.pause_end_ns - core.pause_start_ns;
  if (paused(track) && pause_ns > kMaxSuspendNs) return false;  // cameras stopped: its marker is anywhere
  const double pause_reach =
      paused(track) ? std::max(track.state.velocity().norm(), kPausedMinSpeed) * ns_to_seconds(pause_ns)
                    : 0.0;
  return options.reacquire_max_seen_distance_m <= 0 || track.fast ||
         std::min((position - track.last_seen_position()).norm(),
                  (position - track.seen_position_at(stamp)).norm()) <=
             options.reacquire_max_seen_distance_m + pause_reach;
}

std::uint64_t Tracker::Impl::tracks_digest() const {
  std::uint64_t digest = 0xcbf29ce484222325ULL;
  for (const Track& track : core.tracks) {
    digest ^= static_cast<std::uint64_t>(track.id) * 2 + (track.confirmed ? 1 : 0);
    digest *= 0x100000001b3ULL;
  }
  return digest;
}

void Tracker::Impl::commit_pair(std::size_t t, const Projected& projected, const Eigen::Vector2d& pixel,
                                std::size_t blob, int camera_index, TimeNs stamp, std::vector<char>& used) {
  Track& track = core.tracks[t];
  // Track quality: a real marker's d² follows χ²₂ (mean 2, less while R is generous); blobs
  // of clutter that happen to fall in a wide gate land anywhere in it (mean ~χ²/2).
  const double d2 = mahalanobis2(projected.projection, pixel);
  track.nis_average = track.nis_updates == 0 ? d2 : 0.8 * track.nis_average + 0.2 * d2;
  ++track.nis_updates;
  adapt_process_noise(track, d2, stamp);
  hold_fast_process_noise(track, stamp);
  if (static_cast<std::size_t>(camera_index) < core.blob_owners.size() &&
      core.blob_owners[static_cast<std::size_t>(camera_index)].stamp_ns == stamp)
    core.blob_owners[static_cast<std::size_t>(camera_index)].owners.push_back({pixel, track.id, stamp});
  const TimeNs seen_before_ns = track.seen_ns;
  track.state = projected.state;
  update(track.state, projected.projection, pixel, options.measurement_noise_px);
  // A tentative track that a camera sees again cancels one miss: a marker that the body hides
  // from the other cameras is seen by two as often as it is missed by two and survives to be
  // confirmed; a ghost, starved of blobs in its own views, still reaches tentative_max_misses.
  if (!track.confirmed && track.misses > 0) --track.misses;
  const TimeNs previous_update_ns = track.last_update_ns;
  note_update(track, camera_index, stamp);
  track.camera_last_blob.resize(models.size());
  track.camera_last_blob[static_cast<std::size_t>(camera_index)] = {pixel, stamp};
  damp_one_view_velocity(track, camera_index, stamp, previous_update_ns);
  pin_one_view_depth(track, camera_index, stamp);
  note_innovation(track, static_cast<std::size_t>(camera_index),
                  static_cast<float>((pixel - projected.projection.pixel).norm()));
  if (track.seen_ns == stamp && seen_before_ns != 0 && stamp - seen_before_ns > kReturnGapNs)
    cap_return_velocity(track, projected.state.velocity());
  // Fast once kFastUpdates updates of a settled track (kSettledUpdates) were above kFastSpeed: a
  // ghost of a wrong pairing, or a walking marker's track in a moment of confusion, may show such
  // a speed for an update or two. A runaway if fewer than kFastUpdates of them were made while a
  // second camera updated it (note_update's seen_ns): one camera alone dragged it along its ray,
  // where its own updates cannot tell depth (docs/estimator.md, "Runaway tracks").
  if (track.confirmed && track.state.velocity().squaredNorm() >= kFastSpeed * kFastSpeed) {
    ++track.fast_updates;
    if (track.seen_ns == stamp) ++track.seen_fast_updates;
    track.last_fast_ns = stamp;
    track.peak_speed = std::max(track.peak_speed, track.state.velocity().norm());
    if (!track.fast && track.fast_updates >= kFastUpdates && track.updates >= kSettledUpdates) {
      track.fast = true;
      track.runaway = options.delete_runaway_tracks && track.seen_fast_updates < kFastUpdates;
    }
  }
  estimate_acceleration(track, stamp, (pixel - projected.projection.pixel).norm());
  used[blob] = 1;
  ++core.blobs_associated;
  ++core.associated_per_camera[camera_index];
}

// The separate-bias idea (Friedland's two-stage filter): the constant-velocity filter stays as it
// is, and the acceleration it does not model is estimated beside it from what it does estimate, the
// velocity's change from update to update (its own prediction by the current input included, so the
// estimate converges to the true acceleration, not to the part the filter missed). A first-order
// low-pass: weight 1 - exp(-Δt/τ) per update, τ = fast_acceleration_time_constant_ns. Only for
// isolated fast tracks (a lone ball): at a walker's few m/s² the velocity's update noise (±0.1-1
// m/s per update at 1-3 ms apart) would make the input noise, not signal, and a club's markers,
// whose head leaves the views at the top of the swing, lost identities with it (docs/estimator.md,
// "Acceleration input").
void Tracker::Impl::estimate_acceleration(Track& track, TimeNs stamp, double innovation_px) const {
  const TimeNs tau_ns = options.fast_acceleration_time_constant_ns;
  if (tau_ns <= 0 || !lone_fast(track)) {
    track.state.acceleration.setZero();
    track.acceleration_sample_ns = 0;
    return;
  }
  const TimeNs since = stamp - track.acceleration_sample_ns;
  if (track.acceleration_sample_ns == 0 || since < 0 || since > kFrameGapNs ||
      innovation_px > kSteadyInnovationPx || track.seen_ns != stamp) {
    // No input to predict the manoeuvre with: the allowance of a fast track that has none (the
    // club's factor) until the input is back (ceiling4's ball at a catch's end, 10 ms between one
    // camera's frames: false records 3.99 -> 0.47 %).
    track.state.acceleration.setZero();
    track.q_scale = std::max(track.q_scale, options.fast_process_noise_scale);
  } else if (since > 0) {  // a second camera at the same stamp: its update refines the velocity only
    const double dt = ns_to_seconds(since);
    const Eigen::Vector3d sample = (track.state.velocity() - track.acceleration_sample_velocity) / dt;
    const double weight = 1.0 - std::exp(-dt / ns_to_seconds(tau_ns));
    track.state.acceleration += weight * (sample - track.state.acceleration);
  }
  track.state.acceleration_horizon_s = ns_to_seconds(kFrameGapNs);
  track.acceleration_sample_ns = stamp;
  track.acceleration_sample_velocity = track.state.velocity();
}

// One camera alone cannot see an error along its ray, and its updates let the track slide there
// (d² ~ 0). The second camera's update that ends such a stretch pulls the position back, and the
// gain's position-velocity terms turn that pull into velocity: an elbow at 1.5 m/s left at 8-9 m/s,
// its prediction in a neighbour's gate at the next frames (docs/estimator.md, "Runaway tracks").
// The change of the velocity vector that update makes is capped; a fast track (a club head, a
// ball) and one predicted faster than kFastSpeed keep theirs: they do change speed that fast.
void Tracker::Impl::cap_return_velocity(Track& track, const Eigen::Vector3d& predicted_velocity) {
  const double cap = options.return_velocity_cap_mps;
  if (cap <= 0 || track.fast || predicted_velocity.squaredNorm() > kFastSpeed * kFastSpeed) return;
  const Eigen::Vector3d change = track.state.velocity() - predicted_velocity;
  const double size = change.norm();
  if (size <= cap) return;
  track.state.x.tail<3>() = predicted_velocity + change * (cap / size);
  track.seen_velocity = track.state.velocity();
  ++core.return_velocities_capped;
}

// A track that one camera alone updates has no depth but its prediction's: constant velocity (damped
// along the ray by damp_one_view_velocity) carries it on, and a stray pairing drags it along the ray
// (the left thigh's markers, seen by one ceiling camera for 0.8 s, 0.4 m off and then each on the
// other's marker). Its neighbours, still followed by two cameras, carried its anchor to where its
// marker is (trusted_carried_position); where that point lies on this camera's ray (within
// kPinRayM: the view agrees with it), it measures the depth along the ray with σ
// one_view_carried_sigma_m. Across the ray the camera's pixel rules. Fast tracks keep their own
// rules (docs/estimator.md, "Depth from the neighbours").
void Tracker::Impl::pin_one_view_depth(Track& track, int camera_index, TimeNs stamp) {
  const double sigma = options.one_view_carried_sigma_m;
  if (sigma <= 0 || track.fast || !track.confirmed || track.seen_ns == 0 ||
      stamp - track.seen_ns <= kFrameGapNs)
    return;
  const auto carried = trusted_carried_position(track, stamp);
  if (!carried) return;
  const Eigen::Vector3d centre = models[static_cast<std::size_t>(camera_index)]->center_world();
  const Eigen::Vector3d ray = (track.state.position() - centre).normalized();
  const Eigen::Vector3d offset = *carried - centre;
  if ((offset - offset.dot(ray) * ray).norm() > kPinRayM) return;
  update_along(track.state, ray, ray.dot(*carried), sigma);
  ++core.one_view_depths_pinned;
}

// One camera alone observes a track's motion across its ray, not along it: the velocity there is
// what it was when the second view was lost, and constant velocity carries the depth on with it. A
// marker seen by one camera for a while has often slowed (a foot landing, a hand reaching the end
// of a movement): the component along the ray decays with one_view_velocity_time_constant_ns at
// each update of such a track (docs/estimator.md, "One-view velocity"). A fast track keeps its
// velocity (a club head, a ball: its own rules), and so does any track a second camera updated
// within kFrameGapNs.
void Tracker::Impl::damp_one_view_velocity(Track& track, int camera_index, TimeNs stamp,
                                           TimeNs previous_update_ns) const {
  const TimeNs tau_ns = options.one_view_velocity_time_constant_ns;
  if (tau_ns <= 0 || track.fast || track.seen_ns == 0 || stamp - track.seen_ns <= kFrameGapNs ||
      previous_update_ns == 0 || stamp <= previous_update_ns ||
      track.state.velocity().squaredNorm() >= kFastSpeed * kFastSpeed) {
    return;
  }
  // Only while another camera's frames, applied, had it in view and did not show it (missed_ns):
  // with one camera left for the whole system (the others stopped), its rays are all there is, and
  // constant velocity is what the body filter's identification relies on
  // (BodyScenes.OneOfFourMarkersHidden...: a single camera for 2 s, a tool re-identified wrongly
  // for 10 frames with the decay). Live, another camera's frame for this instant may not have
  // arrived yet: it is no evidence until applied (in order, or by the replay it causes).
  if (!missed_elsewhere(track, camera_index, stamp)) return;
  const Eigen::Vector3d ray =
      (track.state.position() - models[static_cast<std::size_t>(camera_index)]->center_world()).normalized();
  const double along = track.state.velocity().dot(ray);
  const double decay = 1.0 - std::exp(-ns_to_seconds(stamp - previous_update_ns) / ns_to_seconds(tau_ns));
  track.state.x.tail<3>() -= decay * along * ray;
}

// The camera that alone has updated a track for kOneViewNs (its latest), or -1.
int Tracker::Impl::one_view_camera(const Track& track, TimeNs stamp) const {
  const auto& updates = track.camera_last_update;
  if (track.seen_ns == 0 || stamp - track.seen_ns <= kOneViewNs || updates.empty()) return -1;
  return static_cast<int>(std::max_element(updates.begin(), updates.end()) - updates.begin());
}

// Whether one camera other than camera_index alone has updated `track` for kOneViewNs and its
// position is uncertain as held_back judges it (no track is, with reacquire_sigma_m 0).
bool Tracker::Impl::uncertain_elsewhere(const Track& track, int camera_index, TimeNs stamp) const {
  const int camera = one_view_camera(track, stamp);
  if (camera < 0 || camera == camera_index) return false;
  const double sigma = options.reacquire_sigma_m;
  return sigma > 0 && predicted_position_trace(track, stamp) > kUncertainFactor * sigma * sigma;
}

// Whether the uncertain one-view track t, if it took `pixel` of another camera, would land far from
// where its neighbours carried it (return_max_carried_distance_m), beyond reach of where two cameras
// last placed it (return_max_seen_distance_m), or, `pixel` being a fresh blob (fresh_blob), further
// than return_fresh_max_jump_m from its prediction and not near the carried point: refused (true).
// One trial update and one carried point serve the three tests.
bool Tracker::Impl::beyond_return_reach(std::size_t t, const Projected& projected,
                                        const Eigen::Vector2d& pixel, int camera_index, TimeNs stamp) {
  const double reach_m = options.return_max_seen_distance_m;
  const double carried_m = options.return_max_carried_distance_m;
  const Track& track = core.tracks[t];
  // The one-view test first: the fresh-blob test scans the camera's previous frame, for every gated
  // pair, and matters only for the few tracks that pass it.
  if (track.fast || track.seen_ns == 0 || !uncertain_elsewhere(track, camera_index, stamp)) return false;
  const bool fresh = fresh_blob(track, pixel, camera_index, stamp);
  if (reach_m <= 0 && carried_m <= 0 && !fresh) return false;
  // The point to compare with first: without one (and no other test) the update is not needed.
  auto carried = carried_m > 0 ? trusted_carried_position(track, stamp) : std::nullopt;
  if (!carried && reach_m <= 0 && !fresh) return false;
  PointState state = projected.state;
  update(state, projected.projection, pixel, options.measurement_noise_px);
  const Eigen::Vector3d position = state.position();
  if (carried && (position - *carried).norm() > carried_m) {
    ++core.returns_far_from_carried;
    return true;
  }
  if (reach_m > 0) {
    const double reach =
        reach_m + std::max(kReturnSpeed, track.peak_speed) * ns_to_seconds(stamp - track.seen_ns);
    if (std::min((position - track.last_seen_position()).norm(),
                 (position - track.seen_position_at(stamp)).norm()) > reach) {
      ++core.returns_beyond_reach;
      return true;
    }
  }
  if (!fresh || (position - projected.state.position()).norm() <= options.return_fresh_max_jump_m)
    return false;
  if (carried_m <= 0) carried = trusted_carried_position(track, stamp);
  if (carried && (position - *carried).norm() <= kFreshCarriedM) return false;  // its neighbours confirm it
  ++core.returns_fresh_far;
  return true;
}

bool Tracker::Impl::fresh_blob(const Track& track, const Eigen::Vector2d& pixel, int camera_index,
                               TimeNs stamp) const {
  const auto camera = static_cast<std::size_t>(camera_index);
  if (options.return_fresh_max_jump_m <= 0 || camera >= core.last_frames.size()) return false;
  const Core::LastFrame& previous = core.last_frames[camera];
  // An established track only: a young one, or a ghost since its birth, has no place to keep.
  if (previous.stamp_ns == 0 || stamp - previous.stamp_ns > kOwnerFrameNs ||
      track.anchor.stamp_ns - track.created_ns < kCarriedAnchorAgeNs)
    return false;
  return std::none_of(previous.pixels.begin(), previous.pixels.end(),
                      [&](const Eigen::Vector2d& p) { return (p - pixel).norm() <= kFreshBlobPx; });
}

void Tracker::Impl::note_last_frame(int camera_index, TimeNs stamp,
                                    const std::vector<Eigen::Vector2d>& pixels) {
  if (options.return_fresh_max_jump_m <= 0) return;
  const auto camera = static_cast<std::size_t>(camera_index);
  if (core.last_frames.size() <= camera) core.last_frames.resize(camera + 1);
  Core::LastFrame& last = core.last_frames[camera];
  last.stamp_ns = stamp;
  last.pixels.clear();
  for (const Eigen::Vector2d& pixel : pixels)
    if (pixel.allFinite()) last.pixels.push_back(pixel);
}

// Where `track`'s neighbours carried its marker by `stamp` (carried_by_neighbours), if that point
// says where its marker is (kCarriedAnchorAgeNs, kCarriedTakenM); none otherwise.
std::optional<Eigen::Vector3d> Tracker::Impl::trusted_carried_position(const Track& track,
                                                                       TimeNs stamp) const {
  if (track.anchor.stamp_ns - track.created_ns < kCarriedAnchorAgeNs) return std::nullopt;
  const auto carried = carried_by_neighbours(track, stamp);
  if (!carried) return std::nullopt;
  const bool taken = std::any_of(core.tracks.begin(), core.tracks.end(), [&](const Track& other) {
    return &other != &track && other.confirmed && stamp - other.last_update_ns <= kFrameGapNs &&
           (other.position_at(stamp) - *carried).norm() < kCarriedTakenM;
  });
  return taken ? std::nullopt : carried;
}

// Blob owners (blob_owner_px, docs/estimator.md "Blob owners"): track t, which one other camera
// alone has updated for kOneViewNs and whose depth along that camera's ray is uncertain, gates blob b.
// If b continues a blob another track took in this camera's previous frame (or that track's orphan,
// carried since it lost it), b is that marker's: refused (true), unless the other track, updated
// within kFrameGapNs, gates b and another blob too (then the assignment decides between them).
bool Tracker::Impl::owned_elsewhere(std::size_t t, std::size_t b, const std::vector<Eigen::Vector2d>& pixels,
                                    int camera_index, TimeNs stamp, const Core::BlobOwners& last,
                                    const std::vector<GatedPair>& gated) {
  const double radius = options.blob_owner_px;
  if (radius <= 0 || last.owners.empty() || stamp - last.stamp_ns > kOwnerFrameNs) return false;
  const Track& track = core.tracks[t];
  if (!uncertain_elsewhere(track, camera_index, stamp)) return false;
  const auto gates = [&](std::size_t row, auto&& wanted) {
    return std::any_of(gated.begin(), gated.end(),
                       [&](const GatedPair& g) { return g.row == row && wanted(g.col); });
  };
  for (const Core::BlobOwner& owner : last.owners) {
    if (owner.id == track.id || (pixels[b] - owner.pixel).norm() > radius) continue;
    const double d2 = (pixels[b] - owner.pixel).squaredNorm();
    bool nearest = true;
    for (std::size_t j = 0; j < pixels.size() && nearest; ++j)
      nearest = j == b || (pixels[j] - owner.pixel).squaredNorm() >= d2;
    if (!nearest) continue;
    const Track* rival = find_track(owner.id);
    if (rival != nullptr && stamp - rival->last_update_ns <= kFrameGapNs) {
      const auto row = static_cast<std::size_t>(rival - core.tracks.data());
      if (gates(row, [&](std::size_t col) { return col == b; }) &&
          gates(row, [&](std::size_t col) { return col != b; }))
        continue;
    }
    ++core.owned_blobs_kept;
    return true;
  }
  return false;
}

// The camera's owners before this frame (blob_owners), its list started afresh for commit_pair.
Core::BlobOwners Tracker::Impl::start_owners(int camera_index, TimeNs stamp) {
  const auto camera = static_cast<std::size_t>(camera_index);
  if (core.blob_owners.size() <= camera) core.blob_owners.resize(camera + 1);
  Core::BlobOwners last = std::move(core.blob_owners[camera]);
  core.blob_owners[camera] = {stamp, {}};
  return last;
}

// Carries the owners of the camera's previous frame whose blob no track took in this one to the
// nearest blob within blob_owner_px, for up to kOwnerMemoryNs after the owner's last update with it.
void Tracker::Impl::carry_owners(const Core::BlobOwners& last, int camera_index, TimeNs stamp,
                                 const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& used) {
  const double radius = options.blob_owner_px;
  if (radius <= 0 || stamp - last.stamp_ns > kOwnerFrameNs) return;
  auto& now = core.blob_owners[static_cast<std::size_t>(camera_index)];
  for (const Core::BlobOwner& owner : last.owners) {
    if (stamp - owner.since_ns > kOwnerMemoryNs) continue;
    std::size_t best = pixels.size();
    double best_distance = radius;
    for (std::size_t j = 0; j < pixels.size(); ++j) {
      const double distance = (pixels[j] - owner.pixel).norm();
      if (distance <= best_distance) best = j, best_distance = distance;
    }
    if (best < pixels.size() && !used[best]) now.owners.push_back({pixels[best], owner.id, owner.since_ns});
  }
}

// Ray twins (ray_twin_wait_ns, docs/estimator.md "Ray twins"): confirmed track t was assigned blob b,
// which a confirmed track left without a blob also gated, and one camera alone has updated both for
// kOneViewNs and sees them within kRayTwinPx. In that camera, the rival is not counted as unseen
// (held_back). In another, b is left to neither (true) for up to ray_twin_wait_ns: the view's next
// frame usually shows both markers, and the assignment takes them together.
bool Tracker::Impl::twin_waits(std::size_t t, std::size_t b, const std::vector<GatedPair>& pairs,
                               const std::vector<std::pair<std::size_t, std::size_t>>& assignment,
                               int camera_index, TimeNs stamp) {
  constexpr double kRayTwinPx = 6.0;  // two blobs of ~4 px merge; a little beyond
  if (options.ray_twin_wait_ns <= 0) return false;
  Track& track = core.tracks[t];
  const int camera = one_view_camera(track, stamp);
  if (camera < 0) return false;
  const CameraModel& twin_camera = *models[static_cast<std::size_t>(camera)];
  const auto pixel = twin_camera.project(track.position_at(stamp));
  if (!pixel) return false;
  std::optional<std::size_t> rival;
  for (const GatedPair& pair : pairs) {
    if (pair.col != b || pair.row == t) continue;
    const bool assigned = std::any_of(assignment.begin(), assignment.end(),
                                      [&](const auto& taken) { return taken.first == pair.row; });
    if (assigned || one_view_camera(core.tracks[pair.row], stamp) != camera) continue;
    const auto other = twin_camera.project(core.tracks[pair.row].position_at(stamp));
    if (other && (*other - *pixel).norm() <= kRayTwinPx) rival = pair.row;
  }
  if (!rival) return false;
  core.tracks[*rival].frames_at_update = core.frames_applied;
  if (camera == camera_index) return false;
  if (track.twin_wait_since_ns != 0 && stamp - track.twin_wait_since_ns > options.ray_twin_wait_ns)
    return false;
  if (track.twin_wait_since_ns == 0) track.twin_wait_since_ns = stamp;
  track.frames_at_update = core.frames_applied;
  ++core.ray_twin_waits;
  return true;
}

void Tracker::Impl::note_missed(const std::vector<char>& track_done, const std::vector<char>& in_view,
                                int camera_index, TimeNs stamp) {
  for (std::size_t i = 0; i < core.tracks.size(); ++i) {
    Track& track = core.tracks[i];
    if (!track.confirmed || track_done[i] || !in_view[i]) continue;
    track.missed_ns = stamp;
    track.missed_camera = camera_index;
  }
}

void Tracker::Impl::count_misses(const std::vector<char>& track_done, const std::vector<char>& in_view) {
  // A tentative track inside this image that took no blob was not seen: ghosts of wrong pairings
  // are seen by no further camera (seed 000 §4.5 suppresses them the same way, by a third view).
  for (std::size_t i = 0; i < core.tracks.size(); ++i) {
    Track& track = core.tracks[i];
    if (track.confirmed || track_done[i] || !in_view[i]) continue;
    ++track.misses;
  }
}

// A replay applies frames again to states that differ from their first application only by the
// late frames' updates, far less than a gate: the association chosen then almost always still
// holds. Re-checking each chosen pair's gate costs only the predictions the updates need anyway;
// gating every track against the blob grid and solving the assignment again is skipped. When the
// tracks differ (created, deleted, confirmed since) or a pair left its gate, the caller associates
// from scratch. What this cannot see: a blob left unmatched then that would now enter a gate, or
// a different assignment now cheaper; both need a state change comparable to the gate.
bool Tracker::Impl::reassociate(const Entry& entry, const std::vector<Eigen::Vector2d>& pixels,
                                std::vector<char>& used) {
  const CameraModel& camera = *models[entry.camera];
  const TimeNs stamp = entry.frame.stamp_ns;
  std::vector<ProjectedPair> chosen;
  chosen.reserve(entry.associations.size());
  for (const auto& [id, blob] : entry.associations) {
    const Track* found = find_track(id);
    if (found == nullptr || blob >= pixels.size() || used[blob] || found->disputed_in(entry.camera, stamp))
      return false;
    auto full = project_prediction(found->state, stamp, found->sigma2(options.process_noise), camera,
                                   options.init.min_depth_m, options.measurement_noise_px);
    if (!full || !inside_gate(mahalanobis2(full->projection, pixels[blob]), options.gate_chi2)) return false;
    chosen.push_back({static_cast<std::size_t>(found - core.tracks.data()), blob, std::move(*full)});
  }
  std::vector<char> track_done(core.tracks.size(), 0);
  for (const ProjectedPair& pair : chosen) {
    commit_pair(pair.track, pair.projected, pixels[pair.blob], pair.blob, entry.camera, stamp, used);
    track_done[pair.track] = 1;
  }
  std::vector<char> in_view(core.tracks.size(), 0);
  for (std::size_t i = 0; i < core.tracks.size(); ++i) {
    const Track& track = core.tracks[i];
    if (track_done[i]) continue;
    // As gate() decides it: in front of the camera and projected inside the image.
    const Eigen::Vector3d p_cam = camera.T_cam_world().apply(track.position_at(stamp));
    if (p_cam.z() < options.init.min_depth_m) continue;
    const auto pixel = camera.project_camera_point(p_cam);
    in_view[i] = pixel && camera.in_image(*pixel, 0.0);
  }
  count_misses(track_done, in_view);
  note_missed(track_done, in_view, entry.camera, stamp);
  return true;
}

void Tracker::Impl::associate(Entry& entry, const std::vector<Eigen::Vector2d>& pixels,
                              std::vector<char>& used, bool replaying, std::optional<Gating> early) {
  const std::uint64_t digest = tracks_digest();
  const int camera_index = entry.camera;
  const TimeNs stamp = entry.frame.stamp_ns;
  const Core::BlobOwners last_owners = start_owners(camera_index, stamp);
  if (replaying && options.reuse_replay_associations && entry.associated && entry.tracks_digest == digest &&
      reassociate(entry, pixels, used)) {
    ++stats.replayed_reassociated;
    carry_owners(last_owners, camera_index, stamp, pixels, used);
    return;
  }
  entry.associations.clear();
  entry.tracks_digest = digest;
  const Gating gating = early ? std::move(*early) : gate(*models[camera_index], stamp, pixels, used);
  const auto& gated = gating.gated;
  const auto& projected = gating.projected;
  const auto& in_view = gating.in_view;

  // Global assignment, confirmed tracks first, then tentative ones on the blobs left (a young,
  // uncertain track must not take a blob from an established one). The gated pairs split into
  // independent clusters; each is solved optimally (Hungarian), so the cost follows the clusters.
  std::vector<char> track_done(core.tracks.size(), 0);
  for (int stage = 0; stage < 2; ++stage) {
    const bool want_confirmed = stage == 0;
    std::vector<GatedPair> pairs;
    for (const auto& g : gated) {
      if (core.tracks[g.row].confirmed == want_confirmed && !used[g.col] && !track_done[g.row] &&
          !core.tracks[g.row].disputed_in(camera_index, stamp) &&
          !owned_elsewhere(g.row, g.col, pixels, camera_index, stamp, last_owners, gated) &&
          !beyond_return_reach(g.row, *projected[g.row], pixels[g.col], camera_index, stamp) &&
          !off_rigid_partner(g.row, *projected[g.row], pixels[g.col], stamp))
        pairs.push_back(g);
    }
    if (pairs.empty()) continue;
    // Leaving a track and a blob both unmatched costs the gate: any gated pair is preferred.
    const auto assignment = assign_gated(pairs, 0.5 * options.gate_chi2);
    for (const auto& [t, b] : assignment) {
      if (want_confirmed && twin_waits(t, b, pairs, assignment, camera_index, stamp)) continue;
      core.tracks[t].twin_wait_since_ns = 0;
      commit_pair(t, *projected[t], pixels[b], b, camera_index, stamp, used);
      track_done[t] = 1;
      entry.associations.emplace_back(core.tracks[t].id, b);
    }
  }
  recover_manoeuvres(entry, pixels, used, track_done, in_view);
  carry_owners(last_owners, camera_index, stamp, pixels, used);
  count_misses(track_done, in_view);
  note_missed(track_done, in_view, camera_index, stamp);
  // Kept for replays only when nothing competed: every gated pair was taken and no blob left over
  // came within a track's search radius (a circle well beyond the gate). A replay's small change
  // of the states then cannot bring another pair into play; a contested frame is associated again.
  bool contested = entry.associations.size() != gated.size();
  for (std::size_t j = 0; j < pixels.size() && !contested; ++j) contested = gating.near[j] && !used[j];
  entry.associated = !contested;
}

void Tracker::Impl::recover_manoeuvres(Entry& entry, const std::vector<Eigen::Vector2d>& pixels,
                                       std::vector<char>& used, std::vector<char>& track_done,
                                       const std::vector<char>& in_view) {
  const double max_scale = options.process_noise_max_scale;
  if (max_scale <= 1.0 || !options.recover_manoeuvres) return;
  // Within kFrameGapNs of an update: a track lost for longer is coasting, and its wide gate would
  // take any blob. Above kFastSpeed: a swung or thrown object.
  const CameraModel& camera = *models[entry.camera];
  const TimeNs stamp = entry.frame.stamp_ns;
  std::vector<ProjectedPair> claims;
  std::vector<int> claimed(pixels.size(), 0);
  for (std::size_t i = 0; i < core.tracks.size(); ++i) {
    const Track& track = core.tracks[i];
    if (!track.confirmed || track_done[i] || !in_view[i] || stamp - track.last_update_ns > kFrameGapNs ||
        track.disputed_in(entry.camera, stamp))
      continue;
    if (track.state.velocity().squaredNorm() < kFastSpeed * kFastSpeed) continue;
    auto wide = project_prediction(track.state, stamp, options.process_noise * max_scale, camera,
                                   options.init.min_depth_m, options.measurement_noise_px);
    if (!wide) continue;
    std::optional<std::size_t> only;
    bool ambiguous = false;
    for (std::size_t j = 0; j < pixels.size() && !ambiguous; ++j) {
      if (used[j] || !inside_gate(mahalanobis2(wide->projection, pixels[j]), options.gate_chi2)) continue;
      ambiguous = only.has_value();
      only = j;
    }
    if (!only || ambiguous) continue;
    ++claimed[*only];
    claims.push_back({i, *only, std::move(*wide)});
  }
  for (const ProjectedPair& claim : claims) {
    if (claimed[claim.blob] != 1) continue;
    commit_pair(claim.track, claim.projected, pixels[claim.blob], claim.blob, entry.camera, stamp, used);
    Track& track = core.tracks[claim.track];
    // A manoeuvre: the blob was beyond the track's own gate (a fast track's held factor may be larger).
    track.q_scale = std::max(track.q_scale, max_scale);
    track_done[claim.track] = 1;
    entry.associations.emplace_back(track.id, claim.blob);
    ++core.manoeuvres_recovered;
  }
}

// A track that one camera alone has updated for kOneViewNs slides along that camera's ray: its
// depth is its prediction's. One that took its blob from a marker it does not belong to (a track
// whose own marker left the other views, sliding on to a neighbour's ray), or one whose depth ran
// off, keeps that blob from the initiator while a second camera sees the marker, and the marker
// goes untracked for as long (ring4/walk/c0/s1: L.Elbow seen by two cameras 81 deg apart for
// 450 ms, untracked, then a new id). initiate() offers its blobs to the initiator as probes (paired
// like new blobs, never pooled): a point made with one of them moves the track there under its id
// if may_reanchor allows. docs/estimator.md, "One-view tracks".
bool Tracker::Impl::reanchor(Track& track, const InitiationCandidate& candidate, TimeNs stamp) {
  if ((track.position_at(stamp) - candidate.position).norm() < 4.0 * options.merge_distance_m ||
      !may_reanchor(track, candidate.position, stamp))
    return false;
  const double sp = options.init_position_sigma_m, sv = candidate_velocity_sigma(candidate);
  Eigen::Matrix<double, 6, 6> prior = Eigen::Matrix<double, 6, 6>::Zero();
  prior.topLeftCorner<3, 3>() = sp * sp * Eigen::Matrix3d::Identity();
  prior.bottomRightCorner<3, 3>() = sv * sv * Eigen::Matrix3d::Identity();
  track.state.x.head<3>() = candidate.position;
  track.state.x.tail<3>() = candidate.has_velocity ? candidate.velocity : Eigen::Vector3d::Zero();
  track.state.P = FilterCovariance<6>(prior);
  track.state.stamp_ns = stamp;
  track.state.acceleration.setZero();
  track.state.acceleration_horizon_s = 0;
  track.acceleration_sample_ns = 0;
  for (std::size_t k = 0; k < candidate.cameras.size(); ++k)
    note_update(track, candidate.cameras[k], candidate.camera_stamps[k]);
  ++core.tracks_reanchored;
  return true;
}

bool Tracker::Impl::odd_view(const Track& track, int camera_index, const Eigen::Vector2d& pixel,
                             TimeNs stamp) const {
  std::vector<PixelObservation> others;
  const Eigen::Vector3d now = track.position_at(stamp);
  for (std::size_t k = 0; k < std::min(track.camera_last_blob.size(), models.size()); ++k) {
    const Track::LastBlob& last = track.camera_last_blob[k];
    if (static_cast<int>(k) == camera_index || last.stamp_ns == 0 || stamp - last.stamp_ns > kOneViewNs)
      continue;
    // Moved to `stamp` along the track's own motion in that image.
    const auto then_px = models[k]->project(track.position_at(last.stamp_ns));
    const auto now_px = models[k]->project(now);
    if (!then_px || !now_px) continue;
    others.push_back({models[k].get(), Eigen::Vector2d(last.pixel + (*now_px - *then_px))});
  }
  if (others.size() < 2) return false;
  const auto point = triangulate(others);
  if (!point || point->max_reprojection_px > kOddViewAgreePx) return false;
  const auto camera = static_cast<std::size_t>(camera_index);
  return reprojection_error(*models[camera], point->point, pixel) > innovation_limit(camera);
}

void Tracker::Impl::dispute_views(int camera_index, TimeNs stamp, const std::vector<Eigen::Vector2d>& pixels,
                                  const std::vector<std::pair<std::int64_t, std::size_t>>& associations,
                                  const std::function<bool(const Eigen::Vector3d&)>& occupied) {
  if (!options.dispute_odd_views) return;
  std::vector<Eigen::Vector2d> probes;
  std::vector<std::size_t> owners;  // indices into core.tracks, which the probes do not reorder
  const auto camera = static_cast<std::size_t>(camera_index);
  for (const auto& [id, blob] : associations) {
    const Track* owner = find_track(id);
    // One disputed view at a time: a track two of whose views are odd is no longer one marker's
    // track with one wrong view.
    if (owner == nullptr || blob >= pixels.size() || !owner->confirmed || owner->fast ||
        one_view(*owner, stamp) || stamp < owner->disputed_until_ns || views_agree(*owner) ||
        camera >= owner->camera_innovation_avg_px.size() ||
        owner->camera_innovation_avg_px[camera] <= innovation_limit(camera) ||
        !odd_view(*owner, camera_index, pixels[blob], stamp))
      continue;
    probes.push_back(pixels[blob]);
    owners.push_back(static_cast<std::size_t>(owner - core.tracks.data()));
  }
  if (probes.empty()) return;
  core.initiator.probe(camera_index, stamp, probes, [&](const InitiationCandidate& candidate, std::size_t j) {
    if (occupied(candidate.position)) return false;
    Track& owner = core.tracks[owners[j]];
    owner.disputed_camera = camera_index;
    owner.disputed_until_ns = stamp + kDisputedViewNs;
    ++core.views_disputed;
    return false;  // its partners stay in the pool: the blob, free from the next frame on, pairs with them
  });
}

void Tracker::Impl::initiate(const FeatureFrame& frame, int camera_index,
                             const std::vector<Eigen::Vector2d>& pixels, const std::vector<char>& used,
                             const std::vector<std::pair<std::int64_t, std::size_t>>& associations) {
  const TimeNs stamp = frame.stamp_ns;
  if (options.reanchor_one_view_tracks) {
    std::vector<Eigen::Vector2d> probes;
    std::vector<std::size_t> owners;  // indices into core.tracks, which the probes do not reorder
    for (const auto& [id, blob] : associations) {
      const Track* owner = find_track(id);
      if (owner == nullptr || blob >= pixels.size() || !one_view(*owner, stamp) ||
          !missed_elsewhere(*owner, camera_index, stamp))
        continue;
      probes.push_back(pixels[blob]);
      owners.push_back(static_cast<std::size_t>(owner - core.tracks.data()));
    }
    if (!probes.empty()) {
      core.initiator.probe(camera_index, stamp, probes,
                           [&](const InitiationCandidate& candidate, std::size_t j) {
                             return reanchor(core.tracks[owners[j]], candidate, stamp);
                           });
    }
  }
  const double near = 4.0 * options.merge_distance_m;
  const auto occupied = [&](const Eigen::Vector3d& point) {
    return std::any_of(core.tracks.begin(), core.tracks.end(), [&](const Track& track) {
      return (track.position_at(stamp) - point).norm() < near && !held_back(track, stamp);
    });
  };
  dispute_views(camera_index, stamp, pixels, associations, occupied);
  std::vector<Eigen::Vector2d> unmatched;
  for (std::size_t j = 0; j < pixels.size(); ++j) {
    if (used[j]) continue;
    // Initiation pairs blobs across cameras, so its cost grows with their square: a frame full
    // of garbage must not stall the tracker. Real frames leave a handful unmatched.
    if (unmatched.size() >= options.max_unmatched_per_frame) {
      ++core.blobs_not_initiated;
      continue;
    }
    unmatched.push_back(pixels[j]);
  }
  for (auto& candidate : core.initiator.add_frame(camera_index, stamp, unmatched, occupied)) {
    Track track;
    double rejoined_peak_speed = 0;
    track.id = id_for(candidate.position, stamp, rejoined_peak_speed, track.rejoin_id, track.fresh);
    track.state.x.head<3>() = candidate.position;
    track.state.x.tail<3>() = candidate.has_velocity ? candidate.velocity : Eigen::Vector3d::Zero();
    const double sp = options.init_position_sigma_m;
    // A measured velocity is as uncertain as it is large (finite differences of pixel positions
    // over ~10 ms, through the marker's acceleration): a club head at 25 m/s is not known to 0.5 m/s.
    double sv = candidate_velocity_sigma(candidate);
    // A swung or thrown object back from a gap (the top of the swing; rejoined), or a blob without
    // a measured velocity (no camera saw it a frame before: it just came into view) near one: its
    // next frames may see it at full speed again, so its velocity is as uncertain as half that
    // speed and its σ² starts at the manoeuvre maximum (decaying as for any track), as after a
    // recovered manoeuvre. Walking, running and dancing markers are never fast.
    if (rejoined_peak_speed > 0) {
      track.fast = true;
      track.peak_speed = rejoined_peak_speed;
      track.last_fast_ns = stamp;
    }
    const double fast_prior = rejoined_peak_speed > 0  ? rejoined_peak_speed
                              : candidate.has_velocity ? 0.0
                                                       : nearby_fast_speed(candidate.position, stamp);
    if (fast_prior > 0) {
      sv = std::max(sv, 0.5 * fast_prior);
      track.q_scale = std::max(1.0, options.process_noise_max_scale);
      track.q_stamp_ns = stamp;
    }
    Eigen::Matrix<double, 6, 6> prior = Eigen::Matrix<double, 6, 6>::Zero();
    prior.topLeftCorner<3, 3>() = sp * sp * Eigen::Matrix3d::Identity();
    prior.bottomRightCorner<3, 3>() = sv * sv * Eigen::Matrix3d::Identity();
    // Near a fast track, a birth that one view saw a frame before (a club head just come into the
    // other views) takes that view's velocity across its line of sight, as uncertain as a measured
    // one; along the line of sight it stays unknown (sv). Elsewhere the velocity stays zero: a
    // walking or running marker's one view is often linked to a neighbour's blob, and a confident
    // wrong velocity costs more than none (docs/estimator.md, "One view's velocity").
    if (candidate.has_partial_velocity && fast_prior > 0) {
      const Eigen::Matrix3d along = candidate.unknown_direction * candidate.unknown_direction.transpose();
      const double across = std::max(options.init_measured_velocity_sigma_mps,
                                     options.init_velocity_relative_sigma * candidate.velocity.norm());
      track.state.x.tail<3>() = candidate.velocity;
      prior.bottomRightCorner<3, 3>() =
          across * across * (Eigen::Matrix3d::Identity() - along) + sv * sv * along;
    }
    track.state.P = FilterCovariance<6>(prior);
    track.state.stamp_ns = stamp;
    track.created_ns = stamp;
    track.last_update_ns = stamp;
    ++core.tracks_created;
    for (std::size_t k = 0; k < candidate.cameras.size(); ++k)
      note_update(track, candidate.cameras[k], candidate.camera_stamps[k]);
    // In id order (reassociate() searches by id): a reused id goes before the newer ones.
    const auto at = std::lower_bound(core.tracks.begin(), core.tracks.end(), track.id,
                                     [](const Track& t, std::int64_t id) { return t.id < id; });
    core.tracks.insert(at, std::move(track));
  }
}

void Tracker::Impl::reacquire_by_assignment(
    std::vector<Track*>& pending, TimeNs now_ns, std::vector<std::int64_t>& claimed,
    std::vector<std::pair<std::int64_t, std::int64_t>>& renames) const {
  // After a long pause every marker moved far from its track's prediction, and one marker's
  // distance to its own held-back track is no longer 3 times less than to the next
  // (reacquire_distance_ratio): the demo after 0.9 s (test_hostile, stop 74) left two markers
  // 0.90 and 0.64 m from their own tracks and 1.96 and 1.61 m from each other's. Matched as a
  // whole: the assignment of least total distance among those whose every pair passes the gate
  // and the reach, taken when every other assignment of the same tracks costs kAssignRatio times
  // more (or none other is possible). Only for the tracks that coasted through the pause, and
  // few of them (the permutations are tried).
  constexpr std::size_t kMaxAssigned = 5;
  constexpr double kAssignRatio = 2.0;
  if (pending.empty() || pending.size() > kMaxAssigned ||
      core.pause_end_ns == std::numeric_limits<TimeNs>::min())
    return;
  std::vector<const Track*> held;
  for (const Track& track : core.tracks) {
    if (paused(track) && held_back(track, now_ns) &&
        std::find(claimed.begin(), claimed.end(), track.id) == claimed.end())
      held.push_back(&track);
  }
  if (held.size() < pending.size() || held.size() > kMaxAssigned) return;
  // cost[i][k]: pending i on held k, infinite when the pair fails the gate, partner or reach.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> cost(pending.size(), std::vector<double>(held.size(), inf));
  for (std::size_t i = 0; i < pending.size(); ++i) {
    const Eigen::Vector3d position = pending[i]->position_at(now_ns);
    for (std::size_t k = 0; k < held.size(); ++k) {
      if (reacquire_d2(*held[k], position, now_ns) <= kReacquireGateChi2 &&
          keeps_partner_distance(*held[k], position, now_ns) && within_seen_reach(*held[k], position, now_ns))
        cost[i][k] = (position - held[k]->position_at(now_ns)).norm();
    }
  }
  // Every injective map of the pending tracks onto the held ones: the order of `held` permuted,
  // pending i taking order[i]; maps that differ only beyond pending.size() are the same one.
  std::vector<std::size_t> order(held.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  double best = inf, second = inf;
  std::vector<std::size_t> best_order;
  do {
    double total = 0.0;
    for (std::size_t i = 0; i < pending.size() && total < inf; ++i) total += cost[i][order[i]];
    if (!best_order.empty() &&
        std::equal(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(pending.size()),
                   best_order.begin()))
      continue;
    if (total < best) {
      second = best;
      best = total;
      best_order = order;
    } else {
      second = std::min(second, total);
    }
  } while (std::next_permutation(order.begin(), order.end()));
  if (!(best < inf) || second < kAssignRatio * best) return;
  for (std::size_t i = 0; i < pending.size(); ++i) {
    renames.emplace_back(pending[i]->id, held[best_order[i]]->id);
    claimed.push_back(held[best_order[i]]->id);
  }
  pending.clear();
}

void Tracker::Impl::reacquire_confirmed(TimeNs now_ns) {
  // New tracks confirmed at one instant (after a pause of the input, every marker's) are matched
  // in rounds: a held-back track that one of them takes is no candidate for the others, whose
  // choice it may have made ambiguous (the demo after a 0.54 s pause: a marker 0.28 m from its
  // own track's prediction and 0.64 m from another's, which a second marker took 0.10 m away).
  std::vector<Track*> pending;
  for (Track& track : core.tracks) {
    if (!track.pending_reacquire) continue;
    track.pending_reacquire = false;
    pending.push_back(&track);
  }
  std::vector<std::pair<std::int64_t, std::int64_t>> renames;  // (new id, held-back id)
  std::vector<std::int64_t> claimed;
  // Group returns: where the neighbours (or new tracks standing in for them) carried a marker,
  // within reach, decides before the predictions do: after every camera stalled a held-back
  // track's prediction gates its neighbour's new track as well as its own, and the ratio tests
  // below see no rival once the neighbour's track is claimed (a toe's id on the next toe marker).
  if (options.reacquire_group) reacquire_by_neighbours(pending, now_ns, claimed, renames);
  const std::size_t first_by_neighbours = renames.size();
  for (bool progress = true; progress && !pending.empty();) {
    progress = false;
    std::erase_if(pending, [&](Track* track) {
      const auto id = reacquire(track->position_at(now_ns), now_ns, claimed);
      if (!id) return false;
      renames.emplace_back(track->id, *id);
      claimed.push_back(*id);
      progress = true;
      return true;
    });
  }
  reacquire_by_assignment(pending, now_ns, claimed, renames);
  const std::size_t by_others = renames.size();
  reacquire_by_neighbours(pending, now_ns, claimed, renames);
  core.tracks_reacquired_by_neighbours += renames.size() - by_others + first_by_neighbours;
  if (renames.empty()) return;
  std::erase_if(core.departed, [&](const Core::Departed& departed) {
    return std::any_of(renames.begin(), renames.end(),
                       [&](const auto& r) { return r.second == departed.id; });
  });
  const auto renamed = [&](const Track& track) {
    return std::any_of(renames.begin(), renames.end(), [&](const auto& r) { return r.second == track.id; });
  };
  std::erase_if(core.tracks, renamed);
  std::erase_if(core.lost, renamed);
  for (Track& track : core.tracks) {
    for (const auto& [from, to] : renames) {
      if (track.id != from) continue;
      track.id = to;
      track.fresh = false;  // the held-back track's identity: a replay that creates it again keeps it
      track.resumed_ns = now_ns;
      ++core.tracks_reacquired;
    }
  }
  std::sort(core.tracks.begin(), core.tracks.end(),
            [](const Track& a, const Track& b) { return a.id < b.id; });
}

namespace {

// A track that anchors belong to (note_anchors): confirmed, settled, not fast, and seen by two cameras.
bool anchorable(const Track& track) {
  return track.confirmed && !track.fast && track.updates >= kSettledUpdates && track.seen_ns != 0;
}

// A track another may be anchored to (note_anchors), or found by now (reacquire_by_neighbours):
// anchorable, and updated by a second camera within kFrameGapNs.
bool anchor_neighbour(const Track& track, TimeNs now_ns) {
  return anchorable(track) && now_ns - track.seen_ns <= kFrameGapNs;
}

}  // namespace

void Tracker::Impl::note_anchors(TimeNs now_ns) {
  if (options.reacquire_neighbours_m <= 0) return;
  std::vector<const Track*> neighbours;
  bool listed = false;
  std::vector<AnchorPoint> then;
  for (Track& track : core.tracks) {
    if (!anchorable(track) || track.anchored_seen_ns == track.seen_ns || anchor_neighbour(track, now_ns))
      continue;
    if (!listed) {
      for (const Track& other : core.tracks)
        if (anchor_neighbour(other, now_ns)) neighbours.push_back(&other);
      listed = true;
    }
    then.clear();
    for (const Track* other : neighbours)
      if (other != &track)
        then.push_back({other->id, other->position_at(track.seen_ns), other->state.velocity()});
    auto anchor = make_anchor(track.seen_ns, track.seen_position, track.seen_velocity, then,
                              kNeighbourRadiusM, kNeighbourHorizonS);
    if (options.reacquire_group && anchor.count < kAnchorNeighbours) {
      // Group returns: the slots left go to neighbours lost with it (their last two-camera update
      // within kFrameGapNs of its own; every marker at once after the cameras stalled), placed by
      // new tracks when they come back (reacquire_by_neighbours).
      then.clear();
      for (const Track& other : core.tracks)
        if (&other != &track && anchorable(other) && !anchor_neighbour(other, now_ns) &&
            std::abs(other.seen_ns - track.seen_ns) <= kFrameGapNs)
          then.push_back({other.id, other.seen_position_at(track.seen_ns), other.seen_velocity});
      const auto lost_with = make_anchor(track.seen_ns, track.seen_position, track.seen_velocity, then,
                                         kNeighbourRadiusM, kNeighbourHorizonS);
      for (int k = 0; k < lost_with.count && anchor.count < kAnchorNeighbours; ++k)
        anchor.neighbours[static_cast<std::size_t>(anchor.count++)] =
            lost_with.neighbours[static_cast<std::size_t>(k)];
    }
    track.anchored_seen_ns = track.seen_ns;
    if (anchor.count >= 3 || track.anchor.count < 3) track.anchor = anchor;
  }
}

std::vector<AnchorPoint> Tracker::Impl::neighbour_points(TimeNs now_ns) const {
  std::vector<AnchorPoint> now;
  for (const Track& track : core.tracks)
    if (anchor_neighbour(track, now_ns)) now.push_back({track.id, track.position_at(now_ns)});
  return now;
}

namespace {

// Where `anchor`'s neighbours found in `now` carried its marker by `now_ns`: a fit within
// kNeighbourMaxFitRmsM, of an anchor of three neighbours or more within kNeighbourMemoryNs.
std::optional<Eigen::Vector3d> carried_by(const NeighbourAnchor& anchor, std::span<const AnchorPoint> now,
                                          TimeNs now_ns) {
  if (anchor.count < 3 || now_ns - anchor.stamp_ns > kNeighbourMemoryNs) return std::nullopt;
  const auto position = carried_position(anchor, now, kNeighbourMaxFitRmsM);
  if (!position || position->fit_rms_m > kNeighbourMaxFitRmsM) return std::nullopt;
  return position->position;
}

}  // namespace

std::optional<Eigen::Vector3d> Tracker::Impl::carried_by_neighbours(const Track& track, TimeNs now_ns) const {
  return carried_by(track.anchor, neighbour_points(now_ns), now_ns);
}

void Tracker::Impl::reacquire_by_neighbours(
    std::vector<Track*>& pending, TimeNs now_ns, std::vector<std::int64_t>& claimed,
    std::vector<std::pair<std::int64_t, std::int64_t>>& renames) const {
  if (options.reacquire_neighbours_m <= 0 || pending.empty()) return;
  const std::vector<AnchorPoint> now = neighbour_points(now_ns);
  std::vector<AnchorPoint> carried;  // each candidate's id and where its neighbours carried it
  std::vector<char> by_stand_ins;    // ... whether new tracks stood in for some of them
  // Group returns: tracks that two cameras place but are not followed long enough to be anchors,
  // created after the anchor, may stand in for its neighbours lost with it (carried_with_stand_ins).
  std::vector<std::pair<TimeNs, Eigen::Vector3d>> newcomers;
  if (options.reacquire_group)
    for (const Track& track : core.tracks)
      if (!track.fast && !anchor_neighbour(track, now_ns) && track.seen_ns != 0 &&
          now_ns - track.seen_ns <= kFrameGapNs)
        newcomers.emplace_back(track.created_ns, track.position_at(now_ns));
  std::vector<Eigen::Vector3d> stand_ins;
  // `own`: the candidate's track (nullptr: a departed one, which only followed neighbours carry).
  const auto consider = [&](std::int64_t id, const NeighbourAnchor& anchor, const Track* own) {
    if (std::find(claimed.begin(), claimed.end(), id) != claimed.end()) return;
    if (const auto position = carried_by(anchor, now, now_ns)) {
      carried.push_back({id, *position});
      by_stand_ins.push_back(0);
      return;
    }
    if (own == nullptr || newcomers.empty() || anchor.count < 3 ||
        now_ns - anchor.stamp_ns > kNeighbourMemoryNs)
      return;
    stand_ins.clear();
    for (const auto& [created_ns, position] : newcomers)
      if (created_ns > anchor.stamp_ns) stand_ins.push_back(position);
    const auto group = carried_with_stand_ins(anchor, now, stand_ins, kStandInToleranceM, kStandInMaxFitRmsM,
                                              kStandInReachM);
    // Only where its own prediction allows: a foot's markers lie nearly in a plane, so the other
    // foot's new tracks fit its group turned over (a toe's id on the other toe 20 cm away, after a
    // 30 ms stall).
    const double since_s = ns_to_seconds(now_ns - own->last_update_ns);
    const double allowance = kStandInDriftM + 0.5 * kStandInAccelerationMps2 * since_s * since_s;
    if (group && (group->position - own->position_at(now_ns)).norm() <= allowance) {
      carried.push_back({id, group->position});
      by_stand_ins.push_back(1);
    }
  };
  for (const Track& track : core.tracks)
    if (!track.fast && track.anchor.stamp_ns != 0 && reacquire_candidate(track, now_ns, claimed, true))
      consider(track.id, track.anchor, &track);
  for (const Core::Departed& departed : core.departed) consider(departed.id, departed.anchor, nullptr);
  if (carried.empty()) return;
  std::vector<Eigen::Vector3d> at;  // the pending tracks' positions now, in `pending`'s order
  at.reserve(pending.size());
  for (const Track* track : pending) at.push_back(track->position_at(now_ns));
  std::vector<char> taken(pending.size(), 0);
  for (std::size_t i = 0; i < pending.size(); ++i) {
    const auto best = std::min_element(carried.begin(), carried.end(), [&](const auto& a, const auto& b) {
      return (at[i] - a.position).norm() < (at[i] - b.position).norm();
    });
    const double d = (at[i] - best->position).norm();
    const double clear = kNeighbourClearRatio * std::max(d, kNeighbourFloorM);
    const auto near = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double limit) {
      return (a - b).norm() < limit;
    };
    bool alone = std::none_of(carried.begin(), carried.end(), [&](const AnchorPoint& other) {
      return &other != &*best && near(at[i], other.position, clear);
    });
    for (std::size_t j = 0; j < pending.size() && alone; ++j)
      alone = j == i || !near(at[j], best->position, clear);
    const double crowd =
        options.reacquire_crowd_relative ? std::min(kNeighbourCrowdM, clear) : kNeighbourCrowdM;
    const bool crowded = std::any_of(now.begin(), now.end(), [&](const AnchorPoint& point) {
      return point.id != pending[i]->id && near(point.position, at[i], crowd);
    });
    const double reach = by_stand_ins[static_cast<std::size_t>(best - carried.begin())] != 0
                             ? std::min(kStandInReachM, options.reacquire_neighbours_m)
                             : options.reacquire_neighbours_m;
    if (d > reach || !alone || crowded ||
        std::find(claimed.begin(), claimed.end(), best->id) != claimed.end())
      continue;
    renames.emplace_back(pending[i]->id, best->id);
    claimed.push_back(best->id);
    taken[i] = 1;
  }
  std::size_t k = 0;
  std::erase_if(pending, [&](Track*) { return taken[k++] != 0; });
}

void Tracker::Impl::prune(TimeNs now_ns) {
  note_anchors(now_ns);
  reacquire_confirmed(now_ns);
  rejoin_confirmed(now_ns);
  std::erase_if(core.lost,
                [&](const Track& track) { return silence(track, now_ns) > options.delete_after_ns; });
  std::erase_if(core.departed, [&](const Core::Departed& departed) {
    return now_ns - departed.anchor.stamp_ns > kNeighbourMemoryNs;
  });
  // A deleted confirmed track with an anchor stays among the departed (reacquire_by_neighbours).
  const auto depart = [&](const Track& track) {
    if (track.confirmed && track.anchor.count >= 3 && options.reacquire_neighbours_m > 0)
      core.departed.push_back({track.id, track.anchor});
  };
  std::erase_if(core.tracks, [&](const Track& track) {
    const bool implausible =
        track.nis_updates >= 4 &&
        track.nis_average > (track.confirmed ? options.confirmed_max_nis : options.tentative_max_nis);
    // A runaway stays among the lost fast tracks: a club head that one view followed out of the
    // others rejoins its id (rejoin_fast_track).
    // It counts among the departed too: a walking marker's runaway (one camera dragged it along
    // its ray) comes back where its neighbours carried it (ceiling6/walk/c0.3/s3's heel).
    if (track.runaway) {
      core.lost.push_back(track);
      depart(track);
      ++core.runaway_tracks_deleted;
      ++core.tracks_deleted;
      return true;
    }
    if (one_view_ghost(track, now_ns)) {
      ++core.one_view_ghosts_deleted;
      ++core.tracks_deleted;
      return true;
    }
    if (implausible || (!track.confirmed && track.misses >= options.tentative_max_misses)) {
      if (track.confirmed) core.lost.push_back(track);
      ++core.ghosts_deleted;
      ++core.tracks_deleted;
      return true;
    }
    const TimeNs limit = track.confirmed ? options.delete_after_ns : options.tentative_delete_after_ns;
    if (silence(track, now_ns) > limit) {
      depart(track);
      ++core.tracks_deleted;
      return true;
    }
    return false;
  });

  // Duplicates of one marker (two initiations before either took the blobs): keep the track
  // with the longer history. Checked every few ms, with a sweep along x.
  if (core.last_merge_check_ns != std::numeric_limits<TimeNs>::min() &&
      now_ns - core.last_merge_check_ns < 5'000'000)
    return;
  core.last_merge_check_ns = now_ns;
  std::vector<std::pair<Eigen::Vector3d, std::size_t>> positions;
  positions.reserve(core.tracks.size());
  for (std::size_t i = 0; i < core.tracks.size(); ++i)
    positions.emplace_back(core.tracks[i].position_at(now_ns), i);
  std::sort(positions.begin(), positions.end(),
            [](const auto& a, const auto& b) { return a.first.x() < b.first.x(); });
  std::vector<char> remove(core.tracks.size(), 0);
  const double d = options.merge_distance_m;
  for (std::size_t a = 0; a < positions.size(); ++a) {
    for (std::size_t b = a + 1; b < positions.size() && positions[b].first.x() - positions[a].first.x() < d;
         ++b) {
      const std::size_t i = positions[a].second, j = positions[b].second;
      if (remove[i] || remove[j] || (positions[a].first - positions[b].first).norm() >= d) continue;
      const auto& ti = core.tracks[i];
      const auto& tj = core.tracks[j];
      // A track that came out of a coast within the deletion time onto a marker another track
      // followed all along is the one astray (its widened gate took a neighbour's blobs: a shank
      // marker hidden for 0.8 s, docs/estimator.md "Coasting tracks and their neighbours"), not the
      // duplicate to keep because it is older.
      const auto resumed = [&](const Track& t) {
        return t.resumed_ns != 0 && now_ns - t.resumed_ns <= options.delete_after_ns;
      };
      const bool keep_i = std::make_tuple(ti.confirmed, !resumed(ti), ti.updates, -ti.id) >=
                          std::make_tuple(tj.confirmed, !resumed(tj), tj.updates, -tj.id);
      remove[keep_i ? j : i] = 1;
      ++core.tracks_merged;
    }
  }
  std::size_t k = 0;
  std::erase_if(core.tracks, [&](const Track&) { return remove[k++] != 0; });
}

std::int64_t Tracker::Impl::id_for(const Eigen::Vector3d& position, TimeNs stamp, double& rejoined_peak_speed,
                                   std::int64_t& rejoin_id, bool& fresh) {
  // Where an undone track was when the replay creates a track again: its newest state moved back
  // by its velocity over at most the rewind horizon (0.5 s), a few millimetres for a walk.
  constexpr double kReuseIdGate = 0.015;
  auto nearest = undone.end();
  double best = kReuseIdGate;
  for (auto it = undone.begin(); it != undone.end(); ++it) {
    const double d = (it->position_at(stamp) - position).norm();
    if (d < best) {
      best = d;
      nearest = it;
    }
  }
  if (nearest == undone.end()) {
    // A rejoin waits for the new track's confirmation: a two-view ghost near the top of a swing,
    // born before the club head's own track, took the head's identity and left the head a new one
    // (corridor6/club, docs/estimator.md "Rejoin at confirmation").
    const auto rejoined = rejoin_fast_track(position, stamp);
    if (rejoined) {
      rejoin_id = rejoined->first;
      rejoined_peak_speed = rejoined->second;
    } else {
      fresh = true;
    }
    return next_track_id++;
  }
  const std::int64_t id = nearest->id;
  rejoin_id = nearest->rejoin_id;
  // A new id the rewind undid may still take a held-back track's id when the replay confirms it
  // again: the replay brings the late frames its first confirmation did not have.
  fresh = nearest->fresh;
  undone.erase(nearest);
  // A replay from before a reacquisition renamed the track: the held-back track of that id is
  // in the restored state again.
  std::erase_if(core.tracks, [id](const Track& track) { return track.id == id; });
  return id;
}

std::optional<std::pair<std::int64_t, double>> Tracker::Impl::rejoin_fast_track(
    const Eigen::Vector3d& position, TimeNs stamp) {
  if (!options.rejoin_fast_tracks || options.process_noise_max_scale <= 1.0) return std::nullopt;
  // A swung object that leaves every view (a club head above the cameras at the top of the swing)
  // comes back where its path turned, not where constant velocity puts it. Candidates: every
  // confirmed track that lost its marker, fast or not (a slower shaft marker lost beside the head
  // must not hand the head's id to the shaft), also those deleted as implausible. The nearest fast
  // one must be within its reach (the distance it could have covered at its peak speed, plus a
  // margin), every other at least twice as far and kClearMargin beyond, except young slow ones
  // (fewer than kSettledUpdates updates): near the top of a swing, where few cameras see the head
  // and the shaft, wrong pairings make short-lived tracks that are no other marker's identity.
  constexpr double kReachMargin = 0.05, kClearMargin = 0.05;
  const Track* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity(), other_d = best_d, followed_d = best_d;
  const auto consider = [&](const Track& track) {
    const TimeNs gap = stamp - track.last_update_ns;
    if (!track.confirmed || silence(track, stamp) > options.delete_after_ns) return;
    const double d = (position - track.last_seen_position()).norm();
    if (gap <= kFrameGapNs) {
      // Still followed: not a candidate, but a settled one nearer the new track than the lost
      // one is a sign that two markers went out of view together (head and shaft) and that this
      // one is astray.
      if (followed(track, stamp))
        followed_d = std::min(followed_d, (position - track.position_at(stamp)).norm());
      return;
    }
    if (track.fast && d < best_d) {
      if (best != nullptr) other_d = std::min(other_d, best_d);
      best_d = d;
      best = &track;
    } else if (track.fast || track.updates >= kSettledUpdates) {
      other_d = std::min(other_d, d);
    }
  };
  for (const Track& track : core.tracks) consider(track);
  for (const Track& track : core.lost) consider(track);
  if (best == nullptr || other_d < 2.0 * best_d + kClearMargin || followed_d < best_d) return std::nullopt;
  const double speed = std::max({best->peak_speed, best->state.velocity().norm(), kFastSpeed});
  const double reach = speed * ns_to_seconds(stamp - best->last_seen_ns()) + kReachMargin;
  if (best_d > reach) return std::nullopt;
  if (!keeps_partner_distance(*best, position, stamp)) return std::nullopt;
  return std::make_pair(best->id, std::max(best->peak_speed, kFastSpeed));
}

void Tracker::Impl::rejoin_confirmed(TimeNs now_ns) {
  std::vector<std::pair<std::int64_t, std::int64_t>> renames;  // (the new track's id, the lost one's)
  for (Track& track : core.tracks) {
    if (!track.confirmed || track.rejoin_id == 0) continue;
    // It waits until the track would be published: a two-view ghost confirmed near the top of a
    // swing never settles, and the marker's own track, born moments later under the same pending
    // id, takes it (docs/estimator.md, "Rejoin when determined").
    if (!determined(to_record(track, now_ns), false, track.fast)) continue;
    const std::int64_t id = std::exchange(track.rejoin_id, 0);
    const auto same = [id](const Track& other) { return other.id == id; };
    const auto held = std::find_if(core.tracks.begin(), core.tracks.end(), same);
    const bool lost = std::any_of(core.lost.begin(), core.lost.end(), same);
    const bool found_again = held != core.tracks.end() && now_ns - held->last_update_ns <= kFrameGapNs;
    const bool taken =
        std::any_of(renames.begin(), renames.end(), [id](const auto& r) { return r.second == id; });
    if ((held == core.tracks.end() && !lost) || found_again || taken) continue;
    renames.emplace_back(track.id, id);
  }
  if (renames.empty()) return;
  for (const auto& rename : renames) {
    const auto same = [id = rename.second](const Track& track) { return track.id == id; };
    std::erase_if(core.departed, [id = rename.second](const Core::Departed& d) { return d.id == id; });
    if (std::erase_if(core.lost, same) == 0) {
      std::erase_if(core.tracks, same);
      ++core.tracks_deleted;
    }
    ++core.fast_tracks_rejoined;
  }
  for (Track& track : core.tracks) {
    for (const auto& [from, to] : renames)
      if (track.id == from) track.id = to;
  }
  std::sort(core.tracks.begin(), core.tracks.end(),
            [](const Track& a, const Track& b) { return a.id < b.id; });
}

double Tracker::Impl::nearby_fast_speed(const Eigen::Vector3d& position, TimeNs stamp) const {
  if (options.process_noise_max_scale <= 1.0) return 0.0;
  constexpr double kMinGapS = 0.05, kMargin = 0.05;
  double speed = 0.0;
  const auto consider = [&](const Track& track) {
    const TimeNs gap = stamp - track.last_update_ns;
    if (!track.confirmed || !track.fast || track.fast_updates < kPriorFastUpdates || gap <= kFrameGapNs ||
        silence(track, stamp) > options.delete_after_ns)
      return;
    const double reach =
        track.peak_speed * std::max(ns_to_seconds(stamp - track.last_seen_ns()), kMinGapS) + kMargin;
    if ((position - track.last_seen_position()).norm() <= reach) speed = std::max(speed, track.peak_speed);
  };
  for (const Track& track : core.tracks) consider(track);
  for (const Track& track : core.lost) consider(track);
  return speed;
}

void Tracker::Impl::replay_with(std::vector<Entry> late) {
  // The tracks now, moved out (the rewind overwrites them); those the restored state lacks are
  // undone. Both lists are in id order.
  std::vector<Track> before = std::move(core.tracks);
  const std::size_t start = rewind_to(late.front().frame.stamp_ns) - history_base;
  undone.clear();
  auto kept = core.tracks.begin();
  for (auto& track : before) {
    while (kept != core.tracks.end() && kept->id < track.id) ++kept;
    if (kept == core.tracks.end() || kept->id != track.id) undone.push_back(std::move(track));
  }
  // Merge: a late frame goes after the history's frames of the same stamp.
  const auto by_stamp = [](const Entry& a, const Entry& b) { return a.frame.stamp_ns < b.frame.stamp_ns; };
  std::vector<Entry> tail;
  tail.reserve(history.size() - start + late.size());
  std::merge(std::make_move_iterator(history.begin() + static_cast<std::ptrdiff_t>(start)),
             std::make_move_iterator(history.end()), std::make_move_iterator(late.begin()),
             std::make_move_iterator(late.end()), std::back_inserter(tail), by_stamp);
  history.erase(history.begin() + static_cast<std::ptrdiff_t>(start), history.end());
  for (auto& entry : tail) history.push_back(std::move(entry));
  for (std::size_t i = start; i < history.size(); ++i) {
    maybe_checkpoint(history[i].frame.stamp_ns, history_base + i);
    apply(history[i], true);
  }
  undone.clear();  // what the replay did not create again has ended
  ++stats.replays;
  stats.replayed_frames += history.size() - start;
}

TrackRecord Tracker::Impl::to_record(const Track& track, TimeNs stamp_ns) const {
  const PointState state = predicted(track.state, stamp_ns, track.sigma2(options.process_noise));
  TrackRecord record;
  record.stamp_ns = stamp_ns;
  record.id = track.id;
  record.p = state.position();
  record.v = state.velocity();
  const auto& P = state.P.matrix();
  record.position_covariance = {P(0, 0), P(0, 1), P(0, 2), P(1, 1), P(1, 2), P(2, 2)};
  if (!track.confirmed) {
    record.status = TrackStatus::kTentative;
  } else if (stamp_ns - track.last_update_ns > options.coast_after_ns) {
    record.status = TrackStatus::kCoasting;
  } else {
    record.status = TrackStatus::kConfirmed;
  }
  record.cameras = static_cast<int>(std::count_if(
      track.camera_last_update.begin(), track.camera_last_update.end(),
      [&](TimeNs last) { return last != 0 && stamp_ns - last <= options.recent_camera_window_ns; }));
  return record;
}

// A published track stays published until its uncertainty is 2.5 times the limit: without it, one
// camera's frames processed alone while the others' were late (a loaded machine) grew every
// track's depth uncertainty past the limit for a frame, and TrackFrames blinked to zero tracks
// (issue 32 item 9). A track without depth still stops, within about 38 ms (σ 30 mm under the
// default process noise) instead of 21. 2.5 since the limit is 12 mm (stop 88): twice it (24 mm)
// blinked in the unit test's 30 ms of one camera alone, and 3.34 (40 mm, as before) gave back the
// running grid's gain (docs/estimator.md, "Publication limits for the edges").
constexpr double kKeepPublishedFactor = 2.5;
// A fast track's (fast_publish_max_sigma_m, 20 mm) keeps the former factor: with 2.5 × 20 mm the
// thrown ball's worst grid cell had 2.42 % false records instead of 0.47 %.
constexpr double kKeepPublishedFactorFast = 2.0;

bool Tracker::Impl::determined(const TrackRecord& record, bool published, bool fast) const {
  if (options.publish_max_sigma_m <= 0) return true;  // "0: always", fast tracks too
  const double base = fast && options.fast_publish_max_sigma_m > 0 ? options.fast_publish_max_sigma_m
                                                                   : options.publish_max_sigma_m;
  if (base <= 0) return true;
  const auto& c = record.position_covariance;
  Eigen::Matrix3d P;
  P << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
  const double limit = base * (published ? (fast ? kKeepPublishedFactorFast : kKeepPublishedFactor) : 1.0);
  return largest_eigenvalue_at_most(P, limit * limit);
}

// A track (not fast) that two or more cameras updated in the last 10 ms is published only while
// each of them finds its blobs, on a moving average (weight 0.3 per update), within
// publish_max_innovation_px of the predictions, or of four times the camera's typical innovation
// where that is larger (a noisy camera's centroids, or a measurement_noise_px set too small,
// must not withhold every track). A track made of two markers' blobs, one in some
// views and the other in the rest (two clavicles 5 cm apart, each camera seeing one), sits
// between them with an adaptive σ of a few millimetres and every view's blob several pixels off:
// 20-50 mm from either marker, false records that σ does not flag (docs/estimator.md, "Views
// that disagree").
constexpr double kInnovationLevels = 4.0;  // views_agree: a camera's limit is at least this × its level

double Tracker::Impl::innovation_limit(std::size_t camera) const {
  return std::max(options.publish_max_innovation_px,
                  kInnovationLevels * core.camera_innovation_level[camera]);
}

bool Tracker::Impl::views_agree(const Track& track) const {
  if (options.publish_max_innovation_px <= 0 || track.fast) return true;
  int recent = 0;
  bool far = false;
  for (std::size_t k = 0; k < track.camera_innovation_avg_px.size(); ++k) {
    const TimeNs last = track.camera_last_update[k];
    if (last == 0 || track.last_update_ns - last > kFrameGapNs) continue;
    ++recent;
    far = far || track.camera_innovation_avg_px[k] > innovation_limit(k);
  }
  return recent < 2 || !far;
}

// A fast track's σ carries fast_process_noise_scale's allowance for a manoeuvre (×100, ×300 when
// isolated): between two frames it passes the publication limit along the ray of the camera that
// updated it last, though the cameras find its blobs where it predicted them. A thrown ball seen
// by all eight cameras of a ring went unpublished at the first frame after each 6 ms gap in their
// frames (σ 40-50 mm, 0.2-2 mm off); one seen by two at a catch for 20-45 ms. It is published as
// well while the evidence says it is determined: its last update had a second camera's within
// kFrameGapNs (one camera alone lets it slide along its ray), every camera that updated it within
// kFrameGapNs before found its blob within fast_publish_innovation_px of the prediction (at a
// catch's reversal they do not), and the record is at most kFrameGapNs / 4 after that update. A
// track waiting to rejoin a lost fast track's id waits until determined (rejoin_confirmed).
// docs/estimator.md, "Fast tracks seen by few cameras".
bool Tracker::Impl::publishable(const Track& track, const TrackRecord& record, TimeNs stamp_ns) const {
  if (!views_agree(track)) return false;
  if (determined(record, track.published, track.fast)) return true;
  if (options.fast_publish_innovation_px <= 0 || !track.fast || track.rejoin_id != 0 ||
      track.seen_ns != track.last_update_ns || stamp_ns - track.last_update_ns > kFrameGapNs / 4)
    return false;
  for (std::size_t k = 0; k < track.camera_innovation_px.size(); ++k) {
    const TimeNs last = track.camera_last_update[k];
    if (last != 0 && track.last_update_ns - last <= kFrameGapNs &&
        track.camera_innovation_px[k] > options.fast_publish_innovation_px)
      return false;
  }
  return true;
}

Tracker::Tracker(const TrackerOptions& options) : impl_(std::make_unique<Impl>(options)) {}
Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

const TrackerOptions& Tracker::options() const {
  return impl_->options;
}

void Tracker::set_calibration(const SystemCalibration& calibration) {
  for (const auto& camera : calibration.cameras) set_camera(camera);
}

void Tracker::set_camera(const CameraCalibration& camera) {
  if (!camera.T_world_cam) return;
  auto& impl = *impl_;
  const auto found = impl.camera_index.find(camera.id);
  if (found != impl.camera_index.end()) {
    *impl.models[found->second] = camera.model();
  } else {
    impl.camera_index.emplace(camera.id, static_cast<int>(impl.models.size()));
    impl.camera_ids.push_back(camera.id);
    impl.models.push_back(std::make_unique<CameraModel>(camera.model()));
  }
  impl.cameras_changed();
}

void Tracker::replace_camera(const CameraCalibration& camera) {
  set_camera(camera);
  if (!camera.T_world_cam) return;
  auto& impl = *impl_;
  const auto index = static_cast<std::size_t>(impl.camera_index.at(camera.id));
  impl.monitor.restart(static_cast<int>(index));
  if (index < impl.resection_samples.size()) impl.resection_samples[index].clear();
  if (index < impl.refine_samples.size()) impl.refine_samples[index].clear();
  if (index < impl.refine_sampled_ns.size()) impl.refine_sampled_ns[index] = 0;
  if (index < impl.settle_since_ns.size()) impl.settle_since_ns[index] = 0;
  if (index < impl.resection_settle_until_ns.size()) impl.resection_settle_until_ns[index] = 0;
}

void Tracker::set_bodies(const std::vector<BodyDefinition>& bodies, const std::string& file_for_errors) {
  std::set<std::string> names;
  for (const auto& body : bodies) {
    validate_body(body, file_for_errors);
    if (!names.insert(body.name).second)
      throw ConfigError(file_for_errors, "body '" + body.name + "'", "duplicate body name");
  }
  // Rewinds must see the same definitions: checkpoints are updated alike.
  try {
    BodySet probe = impl_->core.bodies;
    probe.set_definitions(bodies, impl_->options.bodies);
  } catch (const std::invalid_argument& error) {  // a led7 layout that is not seed 004's
    throw ConfigError(file_for_errors, "bodies", error.what());
  }
  impl_->core.bodies.set_definitions(bodies, impl_->options.bodies);
  for (auto* tier : {&impl_->checkpoints, &impl_->recent}) {
    for (auto& checkpoint : *tier) checkpoint.core.bodies.set_definitions(bodies, impl_->options.bodies);
  }
}

std::vector<PoseRecord> Tracker::poses_at(TimeNs stamp_ns, TimeNs horizon_ns, bool smoothed) const {
  return impl_->core.bodies.poses_at(stamp_ns, horizon_ns, smoothed);
}

const BodyStats& Tracker::body_stats() const {
  return impl_->core.bodies.stats();
}
std::size_t Tracker::body_count() const {
  return impl_->core.bodies.size();
}

const std::vector<BodyDefinition>& Tracker::body_definitions() const {
  return impl_->core.bodies.definitions();
}

bool Tracker::has_camera(const std::string& camera_id) const {
  return impl_->camera_index.count(camera_id) != 0;
}

CameraCounters& Tracker::counters_for(const std::string& camera_id) {
  // Garbage camera ids must not grow this map without bound.
  constexpr std::size_t kMaxCameras = 1024;
  const auto found = camera_counters_.find(camera_id);
  if (found != camera_counters_.end()) return found->second;
  if (camera_counters_.size() >= kMaxCameras) return camera_counters_["<other>"];
  return camera_counters_[camera_id];
}

int Tracker::admit(const FeatureFrame& frame, FrameOutcome& outcome) {
  auto& stats = impl_->stats;
  ++stats.frames;
  CameraCounters& counters = counters_for(frame.camera_id);
  ++counters.frames;
  const auto found = impl_->camera_index.find(frame.camera_id);
  if (found == impl_->camera_index.end()) {
    ++stats.frames_unknown_camera;
    outcome = FrameOutcome::kUnknownCamera;
    return -1;
  }
  // Stamps this far from 1970 would overflow the time arithmetic (the node's screen rejects far
  // smaller errors); such a frame is counted as too late.
  constexpr TimeNs kStampLimit = TimeNs{1} << 62;
  if (frame.stamp_ns <= 0 || frame.stamp_ns > kStampLimit) {
    ++stats.frames_too_late;
    ++counters.too_late;
    outcome = FrameOutcome::kTooLate;
    return -1;
  }
  stats.blobs += frame.blobs.size();
  counters.blobs += frame.blobs.size();
  for (const auto& blob : frame.blobs) {
    if (!std::isfinite(blob.x) || !std::isfinite(blob.y)) ++stats.blobs_non_finite;
  }
  counters.last_stamp_ns = std::max(counters.last_stamp_ns, frame.stamp_ns);
  return found->second;
}

FrameOutcome Tracker::process(const FeatureFrame& frame) {
  return process_batch({&frame, 1}).front();
}

std::vector<FrameOutcome> Tracker::process_batch(std::span<const FeatureFrame> frames) {
  auto& impl = *impl_;
  std::vector<FrameOutcome> outcomes(frames.size(), FrameOutcome::kProcessed);
  std::vector<std::size_t> order(frames.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return frames[a].stamp_ns < frames[b].stamp_ns; });
  const TimeNs newest = impl.core.last_stamp_ns;
  const Checkpoint* oldest = impl.oldest_checkpoint();
  std::vector<Entry> late;
  std::vector<std::pair<std::size_t, int>> in_order;  // (frame, camera index)
  for (const std::size_t i : order) {
    const FeatureFrame& frame = frames[i];
    const int camera = admit(frame, outcomes[i]);
    if (camera < 0) continue;
    CameraCounters& counters = counters_for(frame.camera_id);
    if (frame.stamp_ns >= newest) {
      in_order.emplace_back(i, camera);
    } else if (oldest == nullptr || frame.stamp_ns < oldest->core.last_stamp_ns) {
      ++impl.stats.frames_too_late;
      ++counters.too_late;
      outcomes[i] = FrameOutcome::kTooLate;
    } else {
      late.push_back(Entry{camera, frame, {}, 0, false});
      ++impl.stats.frames_late;
      ++counters.late;
      ++counters.used;
      outcomes[i] = FrameOutcome::kLateReplayed;
    }
  }
  if (!late.empty()) {
    impl.replay_with(std::move(late));
    // A replay may change what every camera's blobs were used for.
    for (std::size_t c = 0; c < impl.camera_ids.size(); ++c) {
      const auto entry = camera_counters_.find(impl.camera_ids[c]);
      if (entry != camera_counters_.end()) entry->second.associated = impl.core.associated_per_camera[c];
    }
    impl.trim();
  }
  for (const auto& [i, camera] : in_order) {
    const FeatureFrame& frame = frames[i];
    impl.maybe_checkpoint(frame.stamp_ns, impl.history_base + impl.history.size());
    impl.history.push_back(Entry{camera, frame, {}, 0, false});
    impl.apply(impl.history.back(), false);
    CameraCounters& counters = counters_for(frame.camera_id);
    counters.associated = impl.core.associated_per_camera[camera];
    ++counters.used;
    impl.trim();
  }
  return outcomes;
}

std::vector<CameraCalibrationHealth> Tracker::calibration_health() const {
  if (impl_->calibration_mode == CalibrationMode::kOff) return {};
  return impl_->monitor.health();
}

std::vector<CalibrationCorrection> Tracker::take_calibration_corrections() {
  std::vector<CalibrationCorrection> out = std::move(impl_->corrections);
  impl_->corrections.clear();
  return out;
}

std::vector<CalibrationTransition> Tracker::take_calibration_transitions() {
  return impl_->monitor.take_transitions();
}

const CameraModel* Tracker::camera_model(const std::string& camera_id) const {
  const auto found = impl_->camera_index.find(camera_id);
  return found == impl_->camera_index.end() ? nullptr : impl_->models[found->second].get();
}

bool Tracker::camera_quarantined(const std::string& camera_id) const {
  const auto found = impl_->camera_index.find(camera_id);
  return impl_->calibration_mode != CalibrationMode::kOff && found != impl_->camera_index.end() &&
         impl_->monitor.quarantined(found->second);
}

const TrackerStats& Tracker::stats() const {
  auto& s = impl_->merged_stats;
  s = impl_->stats;
  const Core& core = impl_->core;
  s.blobs_associated = core.blobs_associated;
  s.tracks_created = core.tracks_created;
  s.tracks_confirmed = core.tracks_confirmed;
  s.tracks_deleted = core.tracks_deleted;
  s.tracks_merged = core.tracks_merged;
  s.manoeuvres_recovered = core.manoeuvres_recovered;
  s.fast_tracks_rejoined = core.fast_tracks_rejoined;
  s.runaway_tracks_deleted = core.runaway_tracks_deleted;
  s.return_velocities_capped = core.return_velocities_capped;
  s.ray_twin_waits = core.ray_twin_waits;
  s.owned_blobs_kept = core.owned_blobs_kept;
  s.returns_beyond_reach = core.returns_beyond_reach;
  s.returns_far_from_carried = core.returns_far_from_carried;
  s.returns_fresh_far = core.returns_fresh_far;
  s.fast_off_partner = core.fast_off_partner;
  s.one_view_depths_pinned = core.one_view_depths_pinned;
  s.views_disputed = core.views_disputed;
  s.tracks_reacquired = core.tracks_reacquired;
  s.tracks_reacquired_by_neighbours = core.tracks_reacquired_by_neighbours;
  s.tracks_reanchored = core.tracks_reanchored;
  s.input_pauses = core.input_pauses;
  s.ghosts_deleted = core.ghosts_deleted;
  s.one_view_ghosts_deleted = core.one_view_ghosts_deleted;
  s.blobs_not_initiated = core.blobs_not_initiated;
  return s;
}

TimeNs Tracker::last_stamp_ns() const {
  const TimeNs last = impl_->core.last_stamp_ns;
  return last == std::numeric_limits<TimeNs>::min() ? 0 : last;
}

std::size_t Tracker::live_track_count() const {
  return impl_->core.tracks.size();
}

std::size_t Tracker::expire(TimeNs stamp_ns) {
  Core& core = impl_->core;
  const std::size_t before = core.tracks.size();
  std::vector<Track> confirmed;
  for (const Track& track : core.tracks)
    if (track.confirmed) confirmed.push_back(track);
  impl_->prune(std::max(stamp_ns, last_stamp_ns()));
  for (Track& track : confirmed) {
    if (impl_->find_track(track.id) != nullptr) continue;
    if (core.suspended.empty()) core.suspended_at_ns = core.last_stamp_ns;
    core.suspended.push_back(std::move(track));
  }
  return before - core.tracks.size();
}

std::array<std::size_t, 3> Tracker::track_counts(TimeNs stamp_ns) const {
  std::array<std::size_t, 3> counts{};
  for (const auto& track : impl_->core.tracks) {
    const auto status = impl_->to_record(track, stamp_ns).status;
    ++counts[status == TrackStatus::kTentative ? 0 : status == TrackStatus::kConfirmed ? 1 : 2];
  }
  return counts;
}

std::vector<TrackRecord> Tracker::tracks_at(TimeNs stamp_ns) const {
  std::vector<TrackRecord> records;
  for (const auto& track : impl_->core.tracks) {
    if (!track.confirmed) continue;
    TrackRecord record = impl_->to_record(track, stamp_ns);
    track.published = impl_->publishable(track, record, stamp_ns);
    if (!track.published) continue;
    impl_->note_published(track.id);
    records.push_back(std::move(record));
  }
  std::sort(records.begin(), records.end(),
            [](const TrackRecord& a, const TrackRecord& b) { return a.id < b.id; });
  return records;
}

std::vector<PredictedWindow2D> Tracker::predicted_windows(const std::string& camera_id, TimeNs stamp_ns,
                                                          double margin_px) const {
  std::vector<PredictedWindow2D> windows;
  const auto found = impl_->camera_index.find(camera_id);
  if (found == impl_->camera_index.end()) return windows;
  const CameraModel& camera = *impl_->models[found->second];
  for (const auto& track : impl_->core.tracks) {
    const PointState state = predicted(track.state, stamp_ns, track.sigma2(impl_->options.process_noise));
    const auto projection = project_point(state, camera, impl_->options.measurement_noise_px);
    if (!projection) continue;
    const double hw = std::sqrt(impl_->options.gate_chi2 * projection->S(0, 0)) + margin_px;
    const double hh = std::sqrt(impl_->options.gate_chi2 * projection->S(1, 1)) + margin_px;
    if (!camera.in_image(projection->pixel, std::max(hw, hh))) continue;
    windows.push_back({track.id, projection->pixel.x(), projection->pixel.y(), hw, hh});
  }
  return windows;
}

}  // namespace panoptes::estimator
