// SPDX-License-Identifier: Apache-2.0
// bench_estimator's inside-out case (issue 21): the cost of one inside-out frame, side by side with
// a rigid body of the same marker count tracked outside-in from the same pixels. The head camera of
// deploy/scenes/inside_out.yaml (20 landmarks) goes to an InsideOutTracker. For the body, the room
// turns round: camera "a" is fixed at the world origin and sees the 20 landmarks as one 20-marker
// body whose pose is the head camera's T_cam_world, so its frames carry exactly the head camera's
// pixels; a second camera "b" 0.5 m to its side (its own 0.1 px noise, frames 5 ms later) lets the
// point tracker triangulate and identify the body. Only camera a's frames are timed, with the
// body defined and without it (the difference is the body's cost).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "panoptes/estimator/inside_out.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/simulator.h"

namespace panoptes::bench {

struct InsideOutCase {
  int landmarks = 0;
  double blobs_per_frame = 0;
  std::size_t frames = 0;  // timed
  double cold_start_ms = 0;
  double inside_out_us = 0, inside_out_p50_us = 0, inside_out_p99_us = 0;  // per frame while tracking
  // Tracker::process of camera a's frames, body defined.
  double tracker_us = 0, tracker_p50_us = 0, tracker_p99_us = 0;
  std::uint64_t body_identifications = 0;  // identified plus re-identified during the timed frames
  double points_only_us = 0;               // the same without the body definition
  std::size_t body_frames = 0;             // timed frames after which the body had a pose
};

namespace inside_out_detail {

constexpr TimeNs kStampOffset = 1'700'000'000'000'000'000LL;  // absolute stamps, as cameras send

inline double mean_us(const std::vector<double>& seconds) {
  double sum = 0;
  for (double s : seconds) sum += s;
  return seconds.empty() ? 0 : 1e6 * sum / static_cast<double>(seconds.size());
}

inline double percentile_us(std::vector<double> seconds, double q) {
  if (seconds.empty()) return 0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(seconds.size() - 1));
  std::nth_element(seconds.begin(), seconds.begin() + static_cast<std::ptrdiff_t>(k), seconds.end());
  return 1e6 * seconds[k];
}

template <typename Action>
double timed_s(Action&& action) {
  const auto begin = std::chrono::steady_clock::now();
  action();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

// Camera a's frames (the head camera's pixels) and camera b's, in stamp order.
inline std::vector<FeatureFrame> room_as_body_frames(const Scene& scene,
                                                     const std::vector<FeatureFrame>& head,
                                                     const CameraModel& camera_b, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<FeatureFrame> frames;
  for (const FeatureFrame& frame : head) {
    frames.push_back(frame);
    frames.back().camera_id = "a";
    FeatureFrame b;
    b.camera_id = "b";
    b.frame = frame.frame;
    b.stamp_ns = frame.stamp_ns + 5'000'000;
    const RigidTransform T_a_world = scene.camera_pose_at(0, b.stamp_ns - kStampOffset).inverse();
    for (const auto& group : scene.landmarks())
      for (const auto& landmark : group.points)
        if (const auto pixel = camera_b.project(T_a_world.apply(landmark));
            pixel && camera_b.in_image(*pixel)) {
          Blob blob;
          blob.x = pixel->x() + noise(rng);
          blob.y = pixel->y() + noise(rng);
          blob.area = blob.sum = 10;
          b.blobs.push_back(blob);
        }
    frames.push_back(std::move(b));
  }
  return frames;
}

}  // namespace inside_out_detail

// `seconds` of the scene timed after `warmup_s` (the body's identification, the filters settling).
inline InsideOutCase run_inside_out_case(const std::string& scene_file, double warmup_s, double seconds,
                                         std::uint64_t seed) {
  namespace detail = inside_out_detail;
  namespace est = panoptes::estimator;
  const Scene scene = Scene::load(scene_file);
  const CameraSimulator head(scene, scene.cameras().front().calibration.id);
  std::vector<FeatureFrame> frames;
  for (std::int64_t k = 0; head.frame_time_ns(k) < seconds_to_ns(warmup_s + seconds); ++k) {
    frames.push_back(head.features(k));
    frames.back().stamp_ns += detail::kStampOffset;
  }
  const TimeNs timed_from = detail::kStampOffset + seconds_to_ns(warmup_s);

  InsideOutCase result;
  std::vector<est::Constellation> constellations;
  BodyDefinition room;
  room.name = "room";
  for (const auto& group : scene.landmarks()) {
    constellations.push_back({group.name, group.points, group.constellation});
    room.markers.insert(room.markers.end(), group.points.begin(), group.points.end());
  }
  result.landmarks = static_cast<int>(room.markers.size());
  const CameraCalibration& head_calibration = scene.cameras().front().calibration;
  est::InsideOutTracker inside_out(constellations,
                                   CameraModel(head_calibration.intrinsics, *head_calibration.T_world_cam));
  std::vector<double> inside_out_s;
  std::size_t blobs = 0;
  for (const FeatureFrame& frame : frames) {
    std::vector<Eigen::Vector2d> pixels;
    for (const Blob& blob : frame.blobs) pixels.emplace_back(blob.x, blob.y);
    const bool cold = !inside_out.tracking();
    const double spent = detail::timed_s([&] { inside_out.add_frame(frame.stamp_ns, pixels); });
    if (cold && result.cold_start_ms == 0) result.cold_start_ms = 1e3 * spent;
    if (frame.stamp_ns < timed_from) continue;
    inside_out_s.push_back(spent);
    blobs += frame.blobs.size();
  }
  result.frames = inside_out_s.size();
  result.blobs_per_frame =
      static_cast<double>(blobs) / static_cast<double>(std::max<std::size_t>(result.frames, 1));
  result.inside_out_us = detail::mean_us(inside_out_s);
  result.inside_out_p50_us = detail::percentile_us(inside_out_s, 0.5);
  result.inside_out_p99_us = detail::percentile_us(inside_out_s, 0.99);

  // The room as a body: camera a at the origin sees the landmarks where the head camera did.
  SystemCalibration calibration;
  for (const char* id : {"a", "b"}) {
    CameraCalibration camera;
    camera.id = id;
    camera.intrinsics = head_calibration.intrinsics;
    camera.T_world_cam = RigidTransform{};
    calibration.cameras.push_back(camera);
  }
  calibration.cameras[1].T_world_cam->t = Eigen::Vector3d(0.5, 0, 0);
  const auto room_frames = detail::room_as_body_frames(scene, frames, calibration.cameras[1].model(), seed);
  for (const bool with_body : {false, true}) {
    est::Tracker tracker;
    tracker.set_calibration(calibration);
    if (with_body) tracker.set_bodies({room});
    std::vector<double> timed;
    std::uint64_t identifications_before = 0;
    for (const FeatureFrame& frame : room_frames) {
      if (frame.stamp_ns < timed_from)
        identifications_before = tracker.body_stats().identified + tracker.body_stats().reidentified;
      const double spent = detail::timed_s([&] { tracker.process(frame); });
      if (frame.camera_id != "a" || frame.stamp_ns < timed_from) continue;
      timed.push_back(spent);
      if (with_body && !tracker.current_poses().empty()) ++result.body_frames;
    }
    (with_body ? result.tracker_us : result.points_only_us) = detail::mean_us(timed);
    if (!with_body) continue;
    result.tracker_p50_us = detail::percentile_us(timed, 0.5);
    result.tracker_p99_us = detail::percentile_us(timed, 0.99);
    result.body_identifications =
        tracker.body_stats().identified + tracker.body_stats().reidentified - identifications_before;
  }
  return result;
}

}  // namespace panoptes::bench
