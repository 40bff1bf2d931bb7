// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/frame_screen.h"

#include <algorithm>
#include <cmath>

namespace panoptes::estimator {

namespace {

bool valid_camera_id(const std::string& id, std::size_t max_length) {
  if (id.empty() || id.size() > max_length) return false;
  // Ids end up in logs, file names and map keys; control characters (a NUL, a newline from a
  // corrupt line) are never part of a real one. Bytes >= 0x80 (UTF-8) are allowed.
  return std::none_of(id.begin(), id.end(), [](char c) {
    const auto byte = static_cast<unsigned char>(c);
    return byte < 0x20 || byte == 0x7f;
  });
}

bool finite_blob(const Blob& blob) {
  return std::isfinite(blob.x) && std::isfinite(blob.y) && std::isfinite(blob.area) &&
         std::isfinite(blob.sum) && std::isfinite(blob.m20) && std::isfinite(blob.m11) &&
         std::isfinite(blob.m02);
}

// |a - b| > limit without overflowing for any int64 pair.
bool farther_than(TimeNs a, TimeNs b, TimeNs limit) {
  const TimeNs high = std::max(a, b);
  const TimeNs low = std::min(a, b);
  // high - low may exceed int64 range; compare through unsigned arithmetic, where it cannot.
  const auto difference = static_cast<std::uint64_t>(high) - static_cast<std::uint64_t>(low);
  return difference > static_cast<std::uint64_t>(std::max<TimeNs>(limit, 0));
}

}  // namespace

FrameScreen::FrameScreen(FrameScreenOptions options) : options_(options) {}

std::uint64_t FrameScreen::count(std::string_view reason) const {
  const auto it = counts_.find(std::string(reason));
  return it == counts_.end() ? 0 : it->second;
}

void FrameScreen::note(std::string_view reason, std::uint64_t n) {
  counts_[std::string(reason)] += n;
}

bool FrameScreen::screen(FeatureFrame& frame, TimeNs reference_ns) {
  return screen(frame, reference_ns, false);
}

bool FrameScreen::screen_live(FeatureFrame& frame, TimeNs wall_now_ns) {
  return screen(frame, wall_now_ns, true);
}

bool FrameScreen::screen(FeatureFrame& frame, TimeNs reference_ns, bool live) {
  ++stats_.frames;
  std::string_view rejected;
  if (!valid_camera_id(frame.camera_id, options_.max_camera_id_length)) {
    rejected = screen_reason::kBadCameraId;
  } else if (frame.stamp_ns <= 0) {
    rejected = screen_reason::kNonPositiveStamp;
  } else if (reference_ns > 0 && farther_than(frame.stamp_ns, reference_ns, options_.max_stamp_skew_ns)) {
    rejected = screen_reason::kStampOutOfRange;
  } else if (live && reference_ns > 0 && frame.stamp_ns > reference_ns &&
             farther_than(frame.stamp_ns, reference_ns, options_.max_future_ns)) {
    rejected = screen_reason::kStampInFuture;
  } else if (frame.blobs.size() > options_.max_blobs) {
    // Checked before looking at any blob, so a frame of a million blobs costs nothing more.
    rejected = screen_reason::kTooManyBlobs;
  }
  if (!rejected.empty()) {
    ++stats_.frames_rejected;
    note(rejected);
    return false;
  }

  stats_.blobs += frame.blobs.size();
  std::uint64_t non_finite = 0, negative_area = 0, out_of_range = 0;
  const double limit = options_.max_abs_coordinate_px;
  std::erase_if(frame.blobs, [&](const Blob& blob) {
    std::uint64_t* reason = nullptr;
    if (!finite_blob(blob)) {
      reason = &non_finite;
    } else if (blob.area < 0) {
      reason = &negative_area;
    } else if (std::abs(blob.x) > limit || std::abs(blob.y) > limit) {
      reason = &out_of_range;
    }
    if (reason != nullptr) ++*reason;
    return reason != nullptr;
  });
  if (non_finite > 0) note(screen_reason::kNonFiniteBlob, non_finite);
  if (negative_area > 0) note(screen_reason::kNegativeArea, negative_area);
  if (out_of_range > 0) note(screen_reason::kBlobOutOfRange, out_of_range);
  stats_.blobs_dropped += non_finite + negative_area + out_of_range;
  return true;
}

std::vector<TimeNs> offline_reference_stamps(std::span<const FeatureFrame> frames_in_stamp_order,
                                             std::size_t half_window) {
  const std::size_t n = frames_in_stamp_order.size();
  std::vector<TimeNs> references(n, 0);
  std::vector<TimeNs> window;
  window.reserve(2 * half_window + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t begin = i > half_window ? i - half_window : 0;
    const std::size_t end = std::min(n, i + half_window + 1);
    window.clear();
    for (std::size_t j = begin; j < end; ++j) {
      const TimeNs stamp = frames_in_stamp_order[j].stamp_ns;
      if (stamp > 0) window.push_back(stamp);
    }
    if (window.empty()) continue;
    // The frames are sorted, but sorting the window keeps the result right if a caller's are not.
    const auto middle = window.begin() + static_cast<std::ptrdiff_t>(window.size() / 2);
    std::nth_element(window.begin(), middle, window.end());
    references[i] = *middle;
  }
  return references;
}

}  // namespace panoptes::estimator
