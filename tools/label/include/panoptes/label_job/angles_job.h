// SPDX-License-Identifier: Apache-2.0
// `panoptes_label angles` apart from its command line (docs/marker_sets.md, "Segment poses and
// joint angles"): reads a labelled trial and a subject model, writes the joint angles (and the
// segment poses) per frame as CSV.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/labelling/segment_kinematics.h"
#include "panoptes/labelling/subject_model.h"

namespace panoptes::label_job {

struct AnglesCommandOptions {
  std::string in;                // labelled trial: .trc or .c3d
  std::string subjects;          // subject model YAML (panoptes_label model)
  std::string out;               // joint angles CSV
  std::string poses;             // segment poses CSV (optional)
  std::string up = "+y";         // the static trial's vertical
  std::string forward = "+x";    // the direction the subject faces in the static trial
  bool joint_centres = false;    // fit segments with their proximal joint centres (KinematicsOptions)
  std::string fill = "pattern";  // gaps filled before the kinematics (as `run --fill`), or none
  double max_gap_s = 0.3;        // longer gaps stay open
  double lowpass_hz = 6.0;       // zero-lag Butterworth low-pass of the markers first; 0: none
};

// "+x", "-y", "z" … as a unit lab axis; throws InputError naming `option` (when not empty) otherwise.
Eigen::Vector3d parse_axis(const std::string& text, const std::string& option);

struct AnglesResult {
  labelling::SubjectModel model;
  labelling::SegmentKinematics kinematics;
  std::vector<labelling::KinematicsFrame> frames;
  double rate_hz = 0.0;
  std::size_t model_markers_in_trial = 0;
  std::size_t filled_samples = 0;  // marker samples filled before the kinematics
  double lowpass_hz = 0.0;         // the markers' low-pass cutoff, 0: unfiltered
};

// Reads, computes and writes. Throws ConfigError/InputError naming the file or option: a trial or
// model that cannot be read, bad axes, a trial with none of the model's markers, an output that
// cannot be written.
AnglesResult run_angles(const AnglesCommandOptions& options);

// CSV texts: angles wide (frame, time_s, then per joint flexion, adduction and internal rotation
// in degrees, empty without a pose), poses long (a row per frame and segment with a pose).
std::string angles_csv(const AnglesResult& result);
std::string poses_csv(const AnglesResult& result);

// A line per segment named right or left (R./R_/Right, L./L_/Left) that the static pose puts
// elsewhere: --forward or --up do not match the static trial.
std::vector<std::string> side_warnings(const labelling::SegmentKinematics& kinematics);

// Per segment the frames with a pose and the mean fit RMS, per joint the flexion range, the side
// warnings; then one JSON line.
std::string angles_report(const AnglesResult& result);

}  // namespace panoptes::label_job
