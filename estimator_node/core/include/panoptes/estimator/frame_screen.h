// SPDX-License-Identifier: Apache-2.0
// FrameScreen: the gate every FeatureFrame passes before the Tracker (issue 4, "bad input"). A
// frame from a broken camera, a corrupt file or a hostile sender must cost a counter, never a
// crash or a poisoned filter. Bad blobs are removed from the frame; a frame that cannot be trusted
// as a whole is rejected. Each case is counted under a snake_case reason. Frames from cameras the
// tracker has no calibration for are not judged here: Tracker::process counts them
// (FrameOutcome::kUnknownCamera) and the node reports both.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::estimator {

struct FrameScreenOptions {
  // A real frame has at most a few hundred blobs; 4096 is far above any rig. It bounds memory and
  // this screen's work, not the tracker's: thousands of plausible random blobs in a calibrated
  // camera each start pairings, and a frame of 4096 cost the tracker up to 2 s (512: 10-40 ms) on
  // the development machine. A deployment that knows its marker count should set this near it.
  std::size_t max_blobs = 4096;
  // |stamp - reference| beyond this rejects the frame. Live clocks are synchronised to well under
  // a millisecond and the inbox waits tens of ms, so 10 s only catches broken clocks.
  TimeNs max_stamp_skew_ns = 10 * kNsPerSecond;
  // Live only (screen_live): how far a stamp may lie ahead of the wall clock. A frame is stamped
  // at mid-exposure, before it can arrive, so only clock-synchronisation error puts it ahead. This
  // bound matters more than the skew: the tracker treats frames older than its newest by more
  // than its rewind horizon (500 ms) as too late, so one accepted frame stamped seconds ahead
  // would make it drop every real frame until the wall clock caught up.
  TimeNs max_future_ns = 200 * kNsPerMillisecond;
  // A centroid this far outside any sensor (|x| or |y|, px) is garbage, not a marker.
  double max_abs_coordinate_px = 1e5;
  std::size_t max_camera_id_length = 256;
};

// Reason names (the keys of FrameScreen::counts()). Blob reasons count blobs; frame reasons count
// frames. A frame or blob is counted under the first reason that applies, in this order.
namespace screen_reason {
// Frames.
inline constexpr std::string_view kBadCameraId = "bad_camera_id";  // empty, too long, control characters
inline constexpr std::string_view kNonPositiveStamp = "non_positive_stamp";
inline constexpr std::string_view kStampOutOfRange = "stamp_out_of_range";  // farther than max_stamp_skew
inline constexpr std::string_view kStampInFuture = "stamp_in_future";       // screen_live: > max_future ahead
inline constexpr std::string_view kTooManyBlobs = "too_many_blobs";
// Blobs.
inline constexpr std::string_view kNonFiniteBlob = "non_finite_blob";  // NaN/inf in x, y, area, sum, moments
inline constexpr std::string_view kNegativeArea = "negative_area";
// |x| or |y| > max_abs_coordinate_px.
inline constexpr std::string_view kBlobOutOfRange = "blob_out_of_range";
}  // namespace screen_reason

struct FrameScreenStats {
  std::uint64_t frames = 0;           // frames screened
  std::uint64_t frames_rejected = 0;  // = sum of the frame reasons
  std::uint64_t blobs = 0;            // blobs in frames that were not rejected
  std::uint64_t blobs_dropped = 0;    // = sum of the blob reasons
};

class FrameScreen {
 public:
  explicit FrameScreen(FrameScreenOptions options = {});

  // Removes bad blobs from `frame` and returns true if the rest may go to the tracker; false if the
  // whole frame is rejected (its blobs are then left as they were and not counted). The stamp
  // must lie within max_stamp_skew of `reference_ns` (offline: from offline_reference_stamps());
  // a reference <= 0 skips that check.
  bool screen(FeatureFrame& frame, TimeNs reference_ns);
  // Live: as screen() with the wall clock at arrival (wall_now_ns()) as the reference, and the
  // stamp may be at most max_future_ns ahead of it.
  bool screen_live(FeatureFrame& frame, TimeNs wall_now_ns);

  // Counts per reason (only reasons that occurred appear). Merge with the tracker's
  // frames_unknown_camera to report every frame that was not used.
  const std::map<std::string, std::uint64_t>& counts() const { return counts_; }
  std::uint64_t count(std::string_view reason) const;
  const FrameScreenStats& stats() const { return stats_; }
  const FrameScreenOptions& options() const { return options_; }

 private:
  void note(std::string_view reason, std::uint64_t n = 1);
  bool screen(FeatureFrame& frame, TimeNs reference_ns, bool live);

  FrameScreenOptions options_;
  std::map<std::string, std::uint64_t> counts_;
  FrameScreenStats stats_;
};

// Offline there is no wall clock to trust, so each frame is compared with its neighbours: the
// reference of frame i is the median stamp of frames [i - half_window, i + half_window] of
// `frames_in_stamp_order` (truncated at the ends). Inside a recording that is the frame's own
// stamp (real frames are dense in time, and a gap in the recording is accepted). A stamp that is
// garbage sorts to one end of the recording, where the median of its window is a real frame's
// stamp — as long as fewer than half_window / 2 garbage frames share that end. The last accepted
// stamp would not do: one bad frame sorted first would become the reference and reject the
// whole recording. Stamps <= 0 are left out of the medians. At the ends the reference lags the
// frame by up to half_window / 2 frames, so the rig must produce that many frames (32 by default)
// within max_stamp_skew, which any real one does.
std::vector<TimeNs> offline_reference_stamps(std::span<const FeatureFrame> frames_in_stamp_order,
                                             std::size_t half_window = 64);

}  // namespace panoptes::estimator
