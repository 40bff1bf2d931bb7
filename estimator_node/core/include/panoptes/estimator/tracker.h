// SPDX-License-Identifier: Apache-2.0
// Multi-point tracker: one-camera-at-a-time EKF over asynchronous cameras (seed 003 §2.2.3).
// Per camera frame: project the tracks, gate (verify region), assign globally, update; start
// tracks from what is left; coast, confirm, delete. Frames that arrive out of stamp order are
// used by rewinding to a checkpoint and replaying the history (seed 003 §2.2.4.2 asks for
// out-of-order packets not to starve a camera). Design and equations: docs/estimator.md.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/estimator/bodies.h"
#include "panoptes/estimator/calibration_health.h"
#include "panoptes/estimator/initiator.h"
#include "panoptes/estimator/point_ekf.h"
#include "panoptes/records.h"

namespace panoptes::estimator {

struct TrackerOptions {
  double process_noise = 50.0;  // σ² of white acceleration, m²/s³ (seed 003 A.48)
  // Adaptive process noise (issue 35 item 2, docs/estimator.md "Adaptive process noise"): each
  // track scales process_noise by its own factor in [1, max_scale], raised by its normalised
  // innovations (d² above nis_target, averaged) and decaying back to 1 with time constant
  // adapt_decay_ns. max_scale 1: off (one fixed σ² for every track). With init.link_radius_px 120,
  // init_velocity_relative_sigma 0.3, confirmed_max_nis 16, recover_manoeuvres and
  // rejoin_fast_tracks a swung club or a thrown ball keeps its identity (docs/estimator.md
  // "Manoeuvres"); the default since stop 55.
  double process_noise_max_scale = 40.0;
  double process_noise_nis_target = 6.0;
  TimeNs process_noise_adapt_decay_ns = 30'000'000;
  // With adaptive process noise: a confirmed track faster than 10 m/s that took no blob in a frame
  // that sees it, updated within 10 ms, takes the one blob left in its gate widened to the largest
  // σ², unless another such track claims it too (docs/estimator.md, "Manoeuvres").
  bool recover_manoeuvres = true;
  // With adaptive process noise: a new track, once confirmed, takes the id of a confirmed fast
  // track (once faster than 10 m/s) that lost its marker 10 ms to delete_after_ns before the new
  // one was born, when that track was within reach (its speed x the gap) and clearly the nearest
  // of every confirmed track that lost its marker: a club head that left every view at the top of
  // the swing (docs/estimator.md, "Manoeuvres", "Rejoin at confirmation").
  bool rejoin_fast_tracks = true;
  // ... and that new track (or a reacquisition of the fast track's id) is within this of the fast
  // track's distance from its rigid partner, the settled track whose distance from it held within
  // 3 cm for the last 100 ms it was seen, when that partner is still followed: a club head comes
  // back as far from the shaft's marker as it went, a clutter ghost within the head's reach does
  // not (docs/estimator.md, "Rigid partners"). 0: no such test.
  double rejoin_rigid_margin_m = 0.1;
  // A fast track that no two cameras placed within the last 10 ms, whose rigid partner two cameras
  // did, takes no blob whose update would put it further than this from its distance to the
  // partner: a club head's track, followed by one camera at the top of the swing with its depth
  // uncertain to decimetres, took a clutter blob in a second camera and jumped a metre off the club
  // (docs/estimator.md, "Rigid partners at every update"). A track already further off than this
  // (its prediction) may take a blob that puts it at most this much further off. 0: no such test.
  double partner_update_margin_m = 0.1;
  // A settled confirmed track that became fast (5 updates above 10 m/s) with fewer than 5 of those
  // updates made while a second camera updated it within 10 ms is a runaway: one camera alone
  // dragged it along its ray (a walking marker's track at 12-65 m/s). It is deleted like an
  // implausible track and stays among the lost fast tracks for rejoin_fast_tracks
  // (docs/estimator.md, "Runaway tracks").
  bool delete_runaway_tracks = true;
  // A track that one camera alone has updated for 30 ms (its depth along that camera's ray is its
  // prediction's) holds that camera's blob, which the initiator would otherwise pair with a second
  // camera's: its blobs are offered to the initiator as probes (Initiator::probe), and a point made
  // with one of them moves the track there under its id when that is within
  // reacquire_max_seen_distance_m of where two cameras last placed it, or within 0.1 m of where its
  // neighbours carried it since (a stray view may have made that last position wrong), and no other
  // track is within 0.1 m (docs/estimator.md, "One-view tracks"). Fast tracks are left to
  // rejoin_fast_tracks. Only while another camera's applied frame had the track in view and missed
  // it (within 10 ms): live, a frame that has not arrived yet is no evidence.
  bool reanchor_one_view_tracks = true;
  // A second camera's update more than 30 ms after the last update two cameras made together
  // (within 10 ms) changes the track's velocity by at most this, m/s, unless the track is fast or
  // was predicted faster than 10 m/s: one camera alone let it slide along its ray and the update
  // that pulls it back would turn the pull into velocity (docs/estimator.md, "Runaway tracks").
  // 3 m/s by default (0: no cap). Off from stop 71 to 96: live, test_live_labels then failed 3 of 5
  // loaded runs with it; on today's tracker it passes (docs/estimator.md, "Velocity at a return").
  double return_velocity_cap_mps = 3.0;
  // A track (not fast) that one camera alone has updated for more than 10 ms, while another
  // camera's frame, applied within 10 ms, had it in view and did not update it: its velocity along
  // the updating camera's ray, which no update of that camera observes, decays with this time
  // constant at each of its updates (0: off, constant velocity). A foot that lands while one camera
  // sees it stops; constant velocity carried its depth on at the speed it had when the second view
  // was lost (ring4/walk/c0/s1: ankle and heel 30 mm off along one ray in 30 ms, lost, then
  // swapped). On by default since stop 89, when "another camera" became one whose frame was applied
  // and missed the track (live, a frame not yet arrived is no evidence): walk 39 -> 41 ID switches
  // (swaps 9 -> 11), run 229 -> 194 (61 -> 40), dance, club and ball unchanged; test_live_labels
  // passed 5 of 5 loaded runs (2 of 5 failed with the former rule) (docs/estimator.md, "One-view
  // velocity").
  TimeNs one_view_velocity_time_constant_ns = 120'000'000;
  // A confirmed track that one camera alone has updated for 10 ms slides along that camera's ray
  // (its pixels cannot tell depth): where its neighbours carried it (trusted_carried_position: a
  // rigid fit of followed tracks near it, docs/estimator.md "Reacquisition by neighbours") measures
  // its depth along the ray, with this σ, at each such update, when the carried point lies within
  // 3 cm of the ray (docs/estimator.md, "Depth from the neighbours"). 0: off, the default: with
  // 0.05 m the 12 s walk and run grids have 180 -> 126 and 599 -> 410 ID switches, but the 2.5 s
  // walk grid 0 -> 6 (an ankle and a heel swap in ring4/walk/s2), not understood yet.
  double one_view_carried_sigma_m = 0;
  // Two confirmed tracks that one camera alone has updated for 30 ms and that it sees within 6 px of
  // each other (ray twins: an ankle and a heel on one ray, their blobs merged) are each other's rival
  // for a blob both gate. In their own camera, the one that did not get the blob is not counted as
  // unseen (held_back would soon hold it back, and the other would take the next view's blob alone).
  // In another camera, the blob is left to neither for up to this long: the next frame of that view
  // usually shows both markers, and the assignment then takes them together (0: off, the nearest d²
  // decides at once). Walk grid 41 -> 35 ID switches (swaps 11 -> 5), run 194 -> 178 (40 -> 25);
  // dance, club and ball unchanged (docs/estimator.md, "Ray twins").
  TimeNs ray_twin_wait_ns = 20'000'000;
  // Blob owners: a track that one camera alone has updated for 30 ms, and whose depth along that
  // camera's ray is uncertain (its position's covariance trace above 3 reacquire_sigma_m²), takes
  // no blob in another camera that continues (nearest, within this many pixels) a blob another
  // track took in that camera's previous frame, or that track's blob left untaken since (for up to
  // 100 ms): it is that marker's. Two markers each seen by one camera made two-view ghosts 18 cm
  // from both (ceiling4/walk/c1/s1: two hip markers at the turnaround, 0.70 % false records). The
  // other track, updated within 10 ms and gating this blob and another, competes for it in the
  // assignment instead (a blob that splits off a merged one). 0: off. Walk grid: worst cell's false
  // records 0.70 -> 0.45 %, ID switches 35 -> 33 (swaps 5 -> 1); run 178 -> 179 (swaps 25 -> 34)
  // (docs/estimator.md, "Blob owners"). Needs reacquire_sigma_m (0: no track is uncertain).
  double blob_owner_px = 6.0;
  // Second views within reach: such a track (one camera alone for 30 ms, depth uncertain) takes a
  // blob of another camera only if the update puts it within this of where two cameras last placed
  // it, or of where its velocity then carries it, plus 3 m/s (or the track's top speed, if higher)
  // for every second since (metres; 0: off; fast tracks exempt). A clutter blob 378 px off passed a
  // foot's one-view gate, 0.25 s long along its camera's ray, and took the track 1.9 m away, below
  // the floor (ceiling6/walk/c0.3/s3); the foot came back under a new id. Off by default: at 0.4 it
  // also kept a one-view ghost alive in the planner's 4-camera walk layout, which then held a
  // marker's blob, and two markers lost 16-20 % of their coverage (docs/estimator.md, "Second
  // views within reach").
  double return_max_seen_distance_m = 0.0;
  // Second views near where the neighbours carried it: such a track (the same two conditions) takes
  // no blob of another camera whose update would put it more than this from where its neighbours
  // carried it since its last two-camera update (the rigid motion of up to six neighbours; metres;
  // 0: off; fast tracks exempt). Only where that point says where its marker is: the anchor taken
  // at least 0.5 s after the track's birth, and no other track updated within 10 ms is within 5 cm
  // of the point. A heel's one-view track gated other markers' blobs (L.SH3's) in two other cameras;
  // it took one, and the ankle then took the heel's id (ceiling6/walk/c1/s1). Walk
  // grid 2 (1) -> 0 switches (swaps), 12 s 287 (72) -> 263 (52), run 111 (29) -> 107 (25)
  // (docs/estimator.md, "Second views near the carried point"). Needs reacquire_neighbours_m (the
  // anchors) and reacquire_sigma_m (no track is uncertain without it).
  double return_max_carried_distance_m = 0.3;
  // Fresh second views: such a track (the same two conditions, and its anchor taken at least 0.5 s
  // after its birth) takes a blob of another camera that continues no blob of that camera's
  // previous frame (none within 20 px: a marker moves a few px a frame, a false blob lasts one)
  // only if the update moves it at most this far, or puts it within 0.15 m of where its neighbours
  // carried it (metres; 0: off; fast tracks exempt). At the walk's turnarounds on the four-camera
  // ceiling a knee's track, one camera's alone for 0.2 s (its covariance trace 0.17 m²), took a
  // clutter blob in a second camera and jumped 1.26 m, below the floor (ceiling4/walk/c1/s2, 12 s).
  // Walk grid 0 (0) switches (swaps) either way, 12 s 263 (52) -> 245 (45), run 107 (25) -> 105 (23)
  // (docs/estimator.md, "Fresh second views"). Needs reacquire_sigma_m and reacquire_neighbours_m.
  double return_fresh_max_jump_m = 0.5;
  // A fast track (confirmed, five updates above 10 m/s: a swung or thrown object; walking, running
  // and dancing markers stay below) keeps process_noise × fast_process_noise_scale until
  // fast_hold_ns after its last update above 10 m/s, whatever its innovations (0: the adaptive
  // factor, as for any track). On the accuracy grid's club and ball (docs/estimator.md, "Fast
  // tracks"): 100 and 200 ms against the adaptive factor alone, club 41 -> 15 ID switches and
  // RMSE 3.20 -> 1.65 mm, ball 55 -> 0 switches.
  double fast_process_noise_scale = 100.0;
  TimeNs fast_hold_ns = 200'000'000;
  // ... or × fast_isolated_process_noise_scale once fast by 20 updates of its own while no other
  // confirmed track is within fast_isolation_m: a thrown ball's catch needs the wider gate and has
  // no neighbour whose blob the gate could take (a club's markers, 0.4 m apart, keep the smaller
  // factor). Ball on the full grid: worst coverage 95.39 -> 99.42 %, still 0 switches; club, walk,
  // run and dance unchanged (docs/estimator.md, "Isolated fast tracks"). 0: off. 20 since stop 77:
  // with the acceleration input the lone ball is best with a factor smaller than the club's (ball
  // worst coverage 72.4 -> 87.7 % on the grid; docs/estimator.md, "Acceleration input").
  double fast_isolated_process_noise_scale = 20.0;
  double fast_isolation_m = 1.0;
  // An isolated fast track's prediction (as above: a lone thrown ball, not a club's markers) carries
  // its acceleration as a known input (PointState::acceleration): the rate of change of its velocity
  // from update to update, low-passed with this time constant (0: off, constant velocity). A ball's
  // catch (785 m/s² for 0.1 s) is then predicted, not only allowed for by a wide σ²: ball worst
  // coverage 72.4 -> 87.7 %, 99 % or more on every rig but the four-camera ceiling
  // (docs/estimator.md, "Acceleration input").
  TimeNs fast_acceleration_time_constant_ns = 6'000'000;
  double measurement_noise_px = 0.5;  // σ of a centroid, px (seed 003 A.30)
  double gate_chi2 = 18.42;           // χ²₂ at p = 0.9999: the verify region (seed 003 §2.2.3.2)
  InitiatorOptions init;              // pairing of unmatched blobs into new points
  double init_position_sigma_m = 0.01;
  double init_velocity_sigma_mps = 2.0;           // velocity unknown at initiation
  double init_measured_velocity_sigma_mps = 0.5;  // velocity from the tracklets' pixel velocities ...
  double init_velocity_relative_sigma = 0.3;      // ... at least this fraction of its magnitude (0: off)
  int confirm_cameras = 3;                        // distinct cameras that confirm a track ...
  int confirm_updates = 12;                       // ... or this many updates from at least two cameras
  int tentative_max_misses = 4;                   // a tentative track absent where it should be seen: ghost
  double tentative_max_nis = 4.0;                 // moving average of d² above this: fed by clutter, deleted
  double confirmed_max_nis = 16.0;                // through a manoeuvre the average passes 8 ("Manoeuvres")
  TimeNs coast_after_ns = 50'000'000;             // no update for this long: coasting
  TimeNs delete_after_ns = 300'000'000;
  TimeNs tentative_delete_after_ns = 100'000'000;
  // One-view ghosts: a track never published (not fast) that no two cameras have updated together
  // for this long, while another camera's frame, applied within 10 ms, had it in view and did not
  // update it, is deleted as a ghost (0: off). A two-view ghost born 8 m away along camera 0's ray,
  // below the floor, was then updated by camera 0 alone for 1.1 s and held a marker's blob there, so
  // that marker had no track and its neighbour's track took its place (corridor4/walk/s2). Walk grid
  // 4 -> 2 ID switches, run and the fast motions unchanged (docs/estimator.md, "One-view ghosts").
  TimeNs one_view_ghost_ns = 150'000'000;
  // A confirmed track is published only while its predicted position is known this well (1σ
  // along its least determined direction, m; 0: always). A marker that only one camera sees has
  // no depth, and one no camera sees is only predicted: either kind is kept (same id when seen
  // again) but not reported once the filter's own uncertainty passes this. 12 mm since stop 88
  // (20 before): the walk grid's four-camera cells reported markers 20-50 mm off with σ 12-20 mm
  // (docs/estimator.md, "Publication limits for the edges").
  double publish_max_sigma_m = 0.012;
  // The same limit for a fast track (above 10 m/s: a club head, a ball), whose σ carries its
  // manoeuvre allowance between frames; 0: publish_max_sigma_m.
  double fast_publish_max_sigma_m = 0.02;
  // ... or, a fast track (its σ carries fast_process_noise_scale's allowance for a manoeuvre),
  // while the cameras confirm its predictions: its last update had a second camera's within 10 ms,
  // every camera that updated it within 10 ms before found its blob within this of the
  // prediction (px), and the record is at most 2.5 ms after that update (docs/estimator.md, "Fast
  // tracks seen by few cameras"). 0: off.
  double fast_publish_innovation_px = 1.5;
  // A track (not fast) that two or more cameras updated in the last 10 ms is published only while
  // each of them finds its blobs within this of its predictions, px, on a moving average (weight
  // 0.3 per update), or within four times the camera's typical innovation where that is larger:
  // views that disagree are two markers' blobs fused into a point between them (docs/estimator.md,
  // "Views that disagree"). 0: off. On the accuracy grid's walk: false records 10639 -> 6567
  // (worst cell 2.04 -> 1.14 %), switches 56 -> 39, for 0.24 point of mean coverage (3 px, stop
  // 85); 2 px with the 12 mm publish_max_sigma_m since stop 88 ("Publication limits for the edges").
  double publish_max_innovation_px = 2.0;
  // A confirmed track (not fast) whose views disagree as above, whose other views' last blobs
  // agree on a point that one camera's blob misses by more than that camera's limit, gives that
  // camera up for 100 ms when its blob there pairs with another camera's unmatched blob into a point
  // no track explains: that blob is a neighbour's, which the track took where the neighbour hides
  // its own marker from that camera (a sacrum and a PSIS marker 5 cm apart, 1-5 px apart in that
  // camera), and the neighbour could not be initiated while the track held it (docs/estimator.md,
  // "Odd views"). On the accuracy grid's walk: 13 -> 10 switches.
  bool dispute_odd_views = true;
  double merge_distance_m = 0.005;  // two tracks closer than this are one marker
  // A confirmed track not updated for 10 ms and four applied frames (a marker out of sight, not a
  // pause of the input) whose predicted position is less certain than this (1σ per axis, m) takes
  // no blob of its own: its gate would take a neighbour's, or pair a ghost of two markers' blobs. It waits,
  // held back, until delete_after_ns; a new track that initiation makes from ≥ 2 views and that is confirmed
  // near it takes its id then, when that track's prediction gates it (χ²₃, 0.999) and no other held-back
  // track's does nearly as well (docs/estimator.md, "Reacquisition"). 0: off (coasting tracks take blobs in
  // their gates).
  double reacquire_sigma_m = 0.05;
  // ... and only when the next held-back track's prediction is this many times farther (metres; 1: no
  // test). A track that coasted through a pause of the input (every camera stalled: no frame for
  // 25 ms and 8 usual intervals) is held back from σ² one third of reacquire_sigma_m's.
  double reacquire_distance_ratio = 3.0;
  // ... and only when it lies within this of where two cameras last placed the held-back marker, or
  // of where its velocity then carries it (metres; 0: no test). A track that one camera alone kept
  // updating slides along that camera's ray and its velocity runs away (walking markers' held-back
  // tracks predicted 1-9 m off at 8-65 m/s): its prediction gates markers it never was. A swung or
  // thrown object's track (fast) reaches farther and is exempt (docs/estimator.md, "Reacquisition").
  double reacquire_max_seen_distance_m = 0.2;
  // Before those tests: a new track within this of one held-back track's way (the segment from where
  // two cameras last placed it to where its velocity then would have carried it: a marker that went
  // on, slowed down or stopped) takes its id when every other held-back track in the gate is at
  // least twice as far from its own way (metres; 0: off). A foot that lands while one camera sees it
  // comes back short of its velocity's reach and beyond 0.2 m of its last two-camera position
  // (docs/estimator.md, "Reacquisition along the way").
  double reacquire_way_m = 0.06;
  // After those tests, and for confirmed tracks deleted up to 2 s before: a new track within this of
  // where a lost track's neighbours carried it takes its id, when every other lost track's is at
  // least twice as far and no followed track is within 6 cm of the new one (metres; 0: off). The
  // neighbours are the up to six tracks nearest it at its last two-camera update (by distance and
  // velocity); their rigid motion since, fitted to at least three still followed, carries that
  // position (neighbour_anchor.h). A foot or a sacrum out of every view for 0.3-1.5 s
  // comes back 0.2-0.9 m from where it was lost (docs/estimator.md, "Reacquisition by neighbours").
  double reacquire_neighbours_m = 0.08;
  // ... where "no followed track within 6 cm" means within twice the new track's distance from the
  // carried position (at least 1 cm), at most 6 cm: a sacrum marker back 9 mm from where its
  // neighbours carried it is not crowded out by the two PSIS markers 5 cm away (docs/estimator.md,
  // "Crowded returns"). false: within 6 cm.
  bool reacquire_crowd_relative = true;
  // ... and where its neighbours lost with it came back as new tracks (a foot's markers out of every
  // view together), those new tracks stand in for them, placed by their distances (neighbour_anchor.h,
  // carried_with_stand_ins; docs/estimator.md, "Group returns"). false: only followed neighbours.
  bool reacquire_group = true;
  TimeNs recent_camera_window_ns = 500'000'000;   // for TrackRecord::cameras
  TimeNs rewind_horizon_ns = 500'000'000;         // late frames up to this much older are replayed
  TimeNs checkpoint_interval_ns = 10'000'000;     // state snapshots for rewinding ...
  TimeNs dense_checkpoint_window_ns = 5'000'000;  // ... and one before every frame this recent (0: none)
  bool reuse_replay_associations = true;          // a replayed frame keeps its association while it gates
  double grid_cell_px = 32.0;                     // spatial index of a frame's blobs
  std::size_t max_unmatched_per_frame = 256;      // unmatched blobs of one frame offered to initiation
  BodyTrackerOptions bodies;                      // rigid bodies (set_bodies)
  // Per-camera calibration health and quarantine of a bumped camera (docs/continuous_calibration.md).
  CalibrationHealthOptions calibration;

  void print(std::ostream& out) const;
};

struct TrackerStats {
  std::uint64_t frames = 0;
  std::uint64_t frames_unknown_camera = 0;  // no calibration for the camera: ignored
  std::uint64_t frames_late = 0;            // older than the newest processed frame: replayed
  std::uint64_t frames_too_late = 0;        // older than the rewind horizon: dropped
  std::uint64_t replays = 0;                // rewinds
  std::uint64_t replayed_frames = 0;        // frames applied again by rewinds
  std::uint64_t replayed_reassociated = 0;  // of those, kept their association (re-gated only)
  std::uint64_t blobs = 0;
  std::uint64_t blobs_non_finite = 0;  // NaN/inf coordinates: ignored
  std::uint64_t blobs_associated = 0;
  std::uint64_t tracks_created = 0;
  std::uint64_t tracks_confirmed = 0;
  std::uint64_t tracks_deleted = 0;
  std::uint64_t tracks_merged = 0;
  std::uint64_t manoeuvres_recovered = 0;      // blobs a fast track took in its manoeuvre gate
  std::uint64_t fast_tracks_rejoined = 0;      // new tracks that took a lost fast track's id
  std::uint64_t fast_off_partner = 0;          // blobs refused off a rigid partner (partner_update_margin_m)
  std::uint64_t one_view_depths_pinned = 0;    // depths from the neighbours (one_view_carried_sigma_m)
  std::uint64_t runaway_tracks_deleted = 0;    // fast by one camera's updates (delete_runaway_tracks)
  std::uint64_t return_velocities_capped = 0;  // at a return to two views (return_velocity_cap_mps)
  std::uint64_t ray_twin_waits = 0;            // blobs left to neither of two ray twins (ray_twin_wait_ns)
  std::uint64_t owned_blobs_kept = 0;          // blobs kept from uncertain one-view tracks (blob_owner_px)
  std::uint64_t returns_beyond_reach = 0;  // ... and second views out of reach (return_max_seen_distance_m)
  // ... or far from where the neighbours carried the track (return_max_carried_distance_m)
  std::uint64_t returns_far_from_carried = 0;
  std::uint64_t returns_fresh_far = 0;  // ... or on a fresh blob, too far (return_fresh_max_jump_m)
  std::uint64_t views_disputed = 0;     // odd views given up for a neighbour's blob (dispute_odd_views)
  std::uint64_t tracks_reacquired = 0;  // confirmed new tracks that took a held-back track's id
  std::uint64_t tracks_reacquired_by_neighbours =
      0;                                      // ... of which by reacquire_neighbours_m (or a deleted one's)
  std::uint64_t tracks_reanchored = 0;        // one-view tracks moved where two views put their blob
  std::uint64_t input_pauses = 0;             // no frame of any camera for 25 ms and 8 usual intervals
  std::uint64_t ghosts_deleted = 0;           // tentative tracks that cameras did not see
  std::uint64_t one_view_ghosts_deleted = 0;  // ... and never-published one-view tracks (one_view_ghost_ns)
  std::uint64_t blobs_not_initiated = 0;      // unmatched blobs beyond max_unmatched_per_frame
};

// What became of each camera's frames (a camera's utilisation is used / frames).
struct CameraCounters {
  std::uint64_t frames = 0;
  std::uint64_t used = 0;      // applied in order or by rewind and replay
  std::uint64_t late = 0;      // of those, by rewind and replay
  std::uint64_t too_late = 0;  // dropped: older than the rewind horizon
  std::uint64_t blobs = 0;
  std::uint64_t associated = 0;  // blobs that updated a track (final, after replays)
  TimeNs last_stamp_ns = 0;
};

// A region of one camera's image where a track's blob is expected.
struct PredictedWindow2D {
  std::int64_t track_id = 0;
  double x = 0, y = 0;  // predicted centre, px
  double half_width = 0, half_height = 0;
};

enum class FrameOutcome { kProcessed, kLateReplayed, kTooLate, kUnknownCamera };

// A camera's pose corrected from the tracks (--continuous-calibration correct,
// docs/continuous_calibration.md): the tracker applied it; the session records and publishes it.
struct CalibrationCorrection {
  // kBump: a quarantined camera's pose found again; kDrift: a healthy camera's pose refined;
  // kSettle: a bump's correction refined once more over a long window (settle_refine_ns).
  enum class Kind : std::uint8_t { kBump, kDrift, kSettle };
  Kind kind = Kind::kBump;
  std::string camera_id;
  TimeNs stamp_ns = 0;    // the monitored frame that completed the evidence
  RigidTransform before;  // T_world_cam
  RigidTransform after;
  ResectionResult result;
};

class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options = {});
  ~Tracker();
  Tracker(Tracker&&) noexcept;
  Tracker& operator=(Tracker&&) noexcept;

  // Cameras without T_world_cam are ignored (their frames count as unknown). Changing a camera
  // clears the rewind history.
  void set_calibration(const SystemCalibration& calibration);
  void set_camera(const CameraCalibration& camera);
  // A camera changed by an operator (a calibration file reverted or written while tracking,
  // docs/continuous_calibration.md "A changed file"): set_camera, and its calibration monitoring
  // starts again from the new model (residual window, resection and refinement samples, settling);
  // a quarantine stays until the new window is calm.
  void replace_camera(const CameraCalibration& camera);
  bool has_camera(const std::string& camera_id) const;

  // Rigid bodies to identify and track (docs/bodies.md). Throws ConfigError naming the body (and
  // `file_for_errors`) for an unusable definition, keeping the previous definitions. Bodies whose
  // definition is unchanged keep their state.
  void set_bodies(const std::vector<BodyDefinition>& bodies, const std::string& file_for_errors = "bodies");
  // Poses of the tracked bodies at `stamp_ns`, predicted `horizon_ns` further (seed 000 Ch. 5).
  // `smoothed` false: the filter's poses at `stamp_ns` even when bodies.smoothing_ns > 0.
  std::vector<PoseRecord> poses_at(TimeNs stamp_ns, TimeNs horizon_ns = 0, bool smoothed = true) const;
  std::vector<PoseRecord> current_poses(TimeNs horizon_ns = 0) const {
    return poses_at(last_stamp_ns(), horizon_ns);
  }
  const BodyStats& body_stats() const;
  std::size_t body_count() const;
  // The bodies in the order given to set_bodies.
  const std::vector<BodyDefinition>& body_definitions() const;

  // Processes one camera frame. Frames normally come in stamp order; an older frame within the
  // rewind horizon is inserted into the history and the state replayed from before it.
  FrameOutcome process(const FeatureFrame& frame);
  // Processes frames that arrived together, in any order: those older than the newest processed
  // frame are inserted into the history with one rewind and replay (a burst of late frames costs
  // one replay), then the others in stamp order. The outcomes are in the order of `frames`.
  std::vector<FrameOutcome> process_batch(std::span<const FeatureFrame> frames);

  // Published tracks (confirmed or coasting), predicted to `stamp_ns`.
  std::vector<TrackRecord> tracks_at(TimeNs stamp_ns) const;
  // Published tracks at the newest processed frame's stamp.
  std::vector<TrackRecord> current_tracks() const { return tracks_at(last_stamp_ns()); }
  TimeNs last_stamp_ns() const;
  std::size_t live_track_count() const;
  // Deletes the tracks that no frame has updated for their delete_after (tentative ones: their
  // tentative_delete_after) at `stamp_ns`, a time after the newest frame's. When frames stop
  // arriving, the live estimator calls it with the newest stamp plus the time since the last frame,
  // so that tracks do not outlive their cameras (issue 32). The rewind history is kept: a late frame
  // still replays from it. The confirmed ones deleted are kept aside: if frames come back within
  // 3 s of the newest stamp, they return as tracks that coasted through a pause of the input, and
  // new tracks of their markers take their ids when unambiguous (a stall, not cameras stopped).
  // Returns the number deleted.
  std::size_t expire(TimeNs stamp_ns);
  // Live tracks by status at `stamp_ns`: {tentative, confirmed, coasting}.
  std::array<std::size_t, 3> track_counts(TimeNs stamp_ns) const;

  // Where the live tracks should appear in `camera_id`'s frame at `stamp_ns` (for the
  // prediction-guided detector): the gate's extent plus `margin_px`.
  std::vector<PredictedWindow2D> predicted_windows(const std::string& camera_id, TimeNs stamp_ns,
                                                   double margin_px = 3.0) const;

  const TrackerStats& stats() const;
  // Each calibrated camera's calibration health, in calibration order (empty with mode off).
  std::vector<CameraCalibrationHealth> calibration_health() const;
  // Whether `camera_id`'s blobs are currently withheld from fusion (quarantined).
  bool camera_quarantined(const std::string& camera_id) const;
  // The corrections applied since the last call (mode correct), oldest first.
  std::vector<CalibrationCorrection> take_calibration_corrections();
  // The quarantines begun and ended since the last call (CalibrationMonitor::take_transitions).
  std::vector<CalibrationTransition> take_calibration_transitions();
  // The camera's model as the tracker uses it now (a correction changes it); nullptr if unknown.
  const CameraModel* camera_model(const std::string& camera_id) const;
  const std::map<std::string, CameraCounters>& camera_counters() const { return camera_counters_; }
  const TrackerOptions& options() const;

 private:
  struct Impl;
  CameraCounters& counters_for(const std::string& camera_id);
  // Counts a frame; its camera's index, or -1 (and `outcome`) when it cannot be used.
  int admit(const FeatureFrame& frame, FrameOutcome& outcome);

  std::unique_ptr<Impl> impl_;
  std::map<std::string, CameraCounters> camera_counters_;
};

}  // namespace panoptes::estimator
