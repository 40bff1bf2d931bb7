// SPDX-License-Identifier: Apache-2.0
// FrameOutput: everything an application learns from one processed camera frame (docs/clients.md):
// frame number, capture and stage stamps, every defined body (tracked or not) with its pose and
// mean marker error, and every published point track with its label. Built once per processed
// frame by FrameOutputBuilder; the DDS adapters (rt/panoptes/frames, the ROS 2 topics) only
// convert it, so they all carry the same numbers.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/records.h"

namespace panoptes::session {

// Stamps of the stages a frame went through (MocapFrame.stages); 0: unknown.
struct FrameStages {
  TimeNs camera_arrival_ns = 0;
  TimeNs camera_processing_ns = 0;  // a duration
  TimeNs feature_publish_ns = 0;
  TimeNs received_ns = 0;
  TimeNs dequeued_ns = 0;
  TimeNs updated_ns = 0;
};

struct BodyOutput {
  std::string name;
  int id = 0;                   // 1-based position in the bodies file
  bool tracking_valid = false;  // false: `pose` holds only the name
  PoseRecord pose;              // as published on rt/panoptes/bodies (predicted by the horizon)
  double mean_marker_error_m = 0.0;
  int labelled_markers = 0;
  // A subject's segment (SegmentStage, docs/marker_sets.md "Segment poses live"), named
  // "<subject>/<segment>": its parent segment's body name ("" for the subject's root), for ROS 2's
  // tf tree. Not a body of the bodies file: no pose and twist topics of its own.
  bool segment = false;
  std::string parent;
};

struct MarkerOutput {
  TrackRecord track;
  std::string body;      // "": unlabelled
  int body_marker = -1;  // index in the body's layout
  std::string subject;   // --subjects: the subject and marker-set name its track carries ("": none)
  std::string name;
};

struct FrameOutput {
  std::uint64_t frame_number = 0;  // from 1 in each run; fixed rate: + 1 per period (docs/frames.md)
  TimeNs stamp_ns = 0;             // mid-exposure capture time of the source frame; fixed rate: the instant
  std::string source_camera;       // fixed rate: "" (every camera)
  std::int64_t source_frame = 0;   // fixed rate: -1
  FrameStages stages;
  std::vector<BodyOutput> bodies;  // every defined body, in the bodies file's order
  std::vector<MarkerOutput> markers;
};

class FrameOutputBuilder {
 public:
  // Tracks within `label_distance_m` of a tracked body's predicted marker carry its label.
  explicit FrameOutputBuilder(double label_distance_m = 0.01) : label_distance_m_(label_distance_m) {}

  // The output of `frame`, just processed by `tracker`. `poses` are the poses published for it
  // (possibly predicted ahead) and `tracks` its published tracks; labels use the poses at the
  // frame's stamp.
  FrameOutput build(const estimator::Tracker& tracker, const FeatureFrame& frame, const FrameStages& stages,
                    const std::vector<PoseRecord>& poses, const std::vector<TrackRecord>& tracks);

  // A fixed-rate frame (docs/frames.md): every track and body at `tick.instant_ns`. `poses` and
  // `tracks` are predicted to that instant; labels use the bodies' filter poses there.
  FrameOutput build_at(const estimator::Tracker& tracker, std::uint64_t frame_number, TimeNs instant_ns,
                       const FrameStages& stages, const std::vector<PoseRecord>& poses,
                       const std::vector<TrackRecord>& tracks) const;

  std::uint64_t frames_built() const { return frame_number_; }

 private:
  // Bodies and labelled markers of `out`, labels from the bodies' poses at `label_stamp_ns`.
  void fill(FrameOutput& out, const estimator::Tracker& tracker, TimeNs label_stamp_ns,
            const std::vector<PoseRecord>& poses, const std::vector<TrackRecord>& tracks) const;

  double label_distance_m_;
  std::uint64_t frame_number_ = 0;
};

}  // namespace panoptes::session
