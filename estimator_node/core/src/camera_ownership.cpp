// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/camera_ownership.h"

#include <algorithm>

namespace panoptes::estimator {

CameraOwnership::Decision CameraOwnership::claim(const std::string& camera_id, const std::string& writer,
                                                 TimeNs now_ns) {
  if (writer.empty()) return {};
  std::lock_guard<std::mutex> lock(mutex_);
  auto found = claims_.find(camera_id);
  if (found == claims_.end()) {
    if (claims_.size() >= kMaxCameras) return {};  // beyond the table: unchecked, as before
    found = claims_.emplace(camera_id, Claim{writer, now_ns, {}}).first;
    return {Verdict::kOwner, false, writer};
  }
  Claim& claim = found->second;
  if (claim.owner == writer) {
    claim.last_ns = std::max(claim.last_ns, now_ns);
    return {Verdict::kOwner, false, writer};
  }
  if (now_ns - claim.last_ns > handover_after_ns_) {
    claim.owner = writer;
    claim.last_ns = now_ns;
    claim.refused.erase(writer);
    return {Verdict::kHandedOver, false, writer};
  }
  ++refused_frames_;
  bool first = false;
  if (!claim.refused.contains(writer) && claim.refused.size() < kMaxRefusedPerCamera) {
    claim.refused.emplace(writer, now_ns);
    first = true;
  }
  return {Verdict::kRefused, first, claim.owner};
}

std::string CameraOwnership::owner(const std::string& camera_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto found = claims_.find(camera_id);
  return found == claims_.end() ? std::string() : found->second.owner;
}

std::uint64_t CameraOwnership::refused_frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return refused_frames_;
}

const char* to_string(CameraOwnership::Verdict verdict) {
  switch (verdict) {
    case CameraOwnership::Verdict::kOwner:
      return "owner";
    case CameraOwnership::Verdict::kHandedOver:
      return "handed over";
    case CameraOwnership::Verdict::kRefused:
      return "refused";
  }
  return "?";
}

}  // namespace panoptes::estimator
