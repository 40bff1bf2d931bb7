// SPDX-License-Identifier: Apache-2.0
#include <cstdio>
#include <optional>

#include <nlohmann/json.hpp>

#include "panoptes/jsonl.h"
#include "panoptes/process.h"
#include "panoptes/session/log.h"
#include "panoptes/surface_app/surface_mode.h"

namespace panoptes::surface_app {
namespace {

const char* phase_name(surface::StrokePhase phase) {
  switch (phase) {
    case surface::StrokePhase::kBegin:
      return "begin";
    case surface::StrokePhase::kEnd:
      return "end";
    case surface::StrokePhase::kContinue:
      break;
  }
  return "continue";
}

}  // namespace

std::string stroke_json_line(const surface::StrokeEvent& event, const std::string& camera_id) {
  const nlohmann::json line = {{"stamp_ns", event.stamp_ns},
                               {"phase", phase_name(event.phase)},
                               {"id", event.stroke_id},
                               {"p", {event.position.x(), event.position.y()}},
                               {"v", {event.velocity.x(), event.velocity.y()}},
                               {"a", {event.acceleration.x(), event.acceleration.y()}},
                               {"cameras", event.cameras},
                               {"camera", camera_id}};
  return line.dump();
}

std::map<std::string, std::uint64_t> surface_counters(const surface::SurfaceCounters& c) {
  return {{"surface_frames", c.frames},
          {"surface_spots", c.spots},
          {"surface_late_frames", c.late_frames},
          {"surface_unknown_camera", c.unknown_camera},
          {"surface_off_surface", c.off_surface},
          {"surface_unmappable", c.unmappable},
          {"surface_duplicate_spots", c.duplicate_spots},
          {"surface_unconfirmed_dropped", c.unconfirmed_dropped},
          {"surface_strokes_begun", c.strokes_begun},
          {"surface_strokes_ended", c.strokes_ended}};
}

std::vector<Eigen::Vector2d> spot_pixels(const FeatureFrame& frame) {
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(frame.blobs.size());
  for (const auto& blob : frame.blobs) pixels.emplace_back(blob.x, blob.y);
  return pixels;
}

int run_surface_offline(SurfaceSetup& setup, session::FeatureFiles input, const std::string& out_strokes,
                        bool quiet) {
  session::sort_by_stamp(input.frames);
  std::optional<JsonlWriter> writer;
  if (!out_strokes.empty()) writer.emplace(out_strokes);
  std::uint64_t unknown_cameras = 0;
  std::size_t events_written = 0;
  const auto write = [&](const std::vector<surface::StrokeEvent>& events) {
    if (!writer) return;
    for (const auto& event : events) {
      const std::string& id =
          event.camera >= 0 ? setup.camera_ids[static_cast<std::size_t>(event.camera)] : "";
      writer->write_line(stroke_json_line(event, id));
      ++events_written;
    }
  };
  TimeNs last_stamp = 0;
  for (const FeatureFrame& frame : input.frames) {
    const int camera = setup.camera_index(frame.camera_id);
    if (camera < 0) {
      ++unknown_cameras;
      continue;
    }
    const auto pixels = spot_pixels(frame);
    write(setup.tracker->add_frame(camera, frame.stamp_ns, pixels));
    last_stamp = frame.stamp_ns;
  }
  // Strokes still open at the end of the input end at its last frame plus the silence they wait for.
  write(setup.tracker->end_silent(last_stamp + 2 * setup.tracker->options().end_after_ns));
  if (writer) writer->flush();
  if (!quiet) {
    auto counters = surface_counters(setup.tracker->counters());
    counters["surface_unknown_camera"] += unknown_cameras;
    std::string line = "surface: " + std::to_string(events_written) + " stroke events written";
    for (const auto& [name, value] : counters) line += ", " + name + " " + std::to_string(value);
    session::log(line);
  }
  return kExitOk;
}

}  // namespace panoptes::surface_app
