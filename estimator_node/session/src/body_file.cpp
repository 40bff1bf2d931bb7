// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/body_file.h"

#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/session/log.h"

namespace panoptes::session {

void BodyFile::load(estimator::Tracker& tracker) {
  stamp_ = modified();
  const auto bodies = load_bodies(path_);
  tracker.set_bodies(bodies, path_);
  ++generation_;
  std::size_t led = 0;
  for (const auto& body : bodies) led += body.kind == BodyKind::kLed7 ? 1 : 0;
  log("tracking " + std::to_string(bodies.size()) + " rigid bod" + (bodies.size() == 1 ? "y" : "ies") +
      (led ? " (" + std::to_string(led) + " monocular 7-LED)" : "") + " from " + path_);
  for (const auto& warning :
       estimator::distinguishability_warnings(bodies, tracker.options().bodies.identification))
    log(path_ + ": warning: " + warning);
}

void BodyFile::reload_if_changed(estimator::Tracker& tracker) {
  if (!enabled()) return;
  const auto now = modified();
  if (!now || now == stamp_) return;
  try {
    load(tracker);
  } catch (const std::exception& error) {
    stamp_ = now;  // report a bad version once
    log(std::string(error.what()) + " (keeping the previous body definitions)");
  }
}

std::optional<std::filesystem::file_time_type> BodyFile::modified() const {
  std::error_code error;
  const auto time = std::filesystem::last_write_time(path_, error);
  if (error) return std::nullopt;
  return time;
}

}  // namespace panoptes::session
