// SPDX-License-Identifier: Apache-2.0
#include "panoptes/label_job/angles_job.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "panoptes/errors.h"
#include "panoptes/label_job/label_job.h"
#include "panoptes/labelling/gap_fill.h"
#include "panoptes/labelling/lowpass.h"
#include "panoptes/labelling_files/static_trial.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace panoptes::label_job {

namespace {

void append_field(std::string& text, const std::string& value) {
  text += ',';
  text += value;
}

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::out | std::ios::trunc);
  if (!out) throw ConfigError(path, "", "cannot open file for writing");
  out << text;
  out.flush();
  if (!out) throw ConfigError(path, "", "write failed");
}

std::size_t model_markers_in(const labelling::SubjectModel& model, const labelling::MarkerSamples& samples) {
  std::size_t found = 0;
  for (const auto& segment : model.segments) {
    for (const auto& marker : segment.markers) {
      if (!marker.calibration_only &&
          std::find(samples.names.begin(), samples.names.end(), marker.name) != samples.names.end())
        ++found;
    }
  }
  return found;
}

// A right segment reported on the left means --forward or --up is wrong for the static trial.
const char* side_name(int side) {
  if (side == 0) return "midline";
  return side > 0 ? "right side" : "left side";
}

// The side a segment's name says (a prefix "R." / "R_" / "Right", "L." / "L_" / "Left"), or 0.
int named_side(const std::string& name) {
  const auto starts = [&](const char* prefix) { return name.rfind(prefix, 0) == 0; };
  if (starts("R.") || starts("R_") || starts("Right")) return 1;
  if (starts("L.") || starts("L_") || starts("Left")) return -1;
  return 0;
}

// Gap filling, then the low-pass filter, as --fill and --lowpass-hz ask.
void prepare_markers(const AnglesCommandOptions& options, AnglesResult& result,
                     labelling::MarkerSamples& samples) {
  const auto method = parse_fill_method(options.fill);
  if (!method)
    throw InputError("--fill: expected pattern, relational, spline, linear or none, got '" + options.fill +
                     "'");
  if (!(options.max_gap_s >= 0.0)) throw InputError("--max-gap-s: must be 0 or more");
  labelling::FillOptions fill;
  fill.method = *method;
  fill.max_gap_frames = static_cast<std::size_t>(std::floor(options.max_gap_s * samples.rate_hz + 1e-9));
  std::vector<std::uint8_t> filled;
  labelling::fill_gaps(result.model, samples, filled, fill);
  for (const auto flag : filled) result.filled_samples += flag;
  if (options.lowpass_hz == 0.0) return;
  try {
    labelling::lowpass_filter(samples, options.lowpass_hz);
  } catch (const std::invalid_argument& error) {
    throw InputError(std::string("--lowpass-hz: ") + error.what());
  }
  result.lowpass_hz = options.lowpass_hz;
}

}  // namespace

std::vector<std::string> side_warnings(const labelling::SegmentKinematics& kinematics) {
  std::vector<std::string> warnings;
  for (const auto& segment : kinematics.segments) {
    const int named = named_side(segment.name);
    if (named == 0 || named == segment.side) continue;
    warnings.push_back("warning: " + segment.name + " lies on the " + side_name(segment.side) +
                       " of the static pose: check --forward and --up (angles are meaningless otherwise)");
  }
  return warnings;
}

Eigen::Vector3d parse_axis(const std::string& text, const std::string& option) {
  if (const auto axis = labelling::axis_from_name(text)) return *axis;
  throw InputError((option.empty() ? "" : option + ": ") + "'" + text +
                   "' is not an axis (+x, -x, +y, -y, +z or -z)");
}

AnglesResult run_angles(const AnglesCommandOptions& options) {
  labelling::KinematicsOptions kinematics_options;
  kinematics_options.up = parse_axis(options.up, "--up");
  kinematics_options.forward = parse_axis(options.forward, "--forward");
  if (std::abs(kinematics_options.up.dot(kinematics_options.forward)) > 0.5)
    throw InputError("--up " + options.up + " and --forward " + options.forward + " must be different axes");
  kinematics_options.joint_centres_in_fit = options.joint_centres;
  AnglesResult result;
  result.model = labelling::load_subject_model(options.subjects);
  labelling::MarkerSamples samples = labelling::load_marker_samples(options.in);
  result.rate_hz = samples.rate_hz;
  result.model_markers_in_trial = model_markers_in(result.model, samples);
  if (result.model_markers_in_trial == 0)
    throw InputError(options.in + ": none of the markers of subject model " + options.subjects +
                     " (subject " + result.model.subject + ") is in the trial");
  prepare_markers(options, result, samples);
  try {
    result.kinematics = labelling::build_segment_kinematics(result.model, kinematics_options);
  } catch (const InputError& error) {
    throw ConfigError(options.subjects, "segments", error.what());
  }
  for (std::size_t f = 0; f < samples.frame_count(); ++f) {
    result.frames.push_back(labelling::compute_kinematics(
        result.kinematics, result.model,
        labelling::segment_points(result.kinematics, result.model, samples, f)));
  }
  write_file(options.out, angles_csv(result));
  if (!options.poses.empty()) write_file(options.poses, poses_csv(result));
  return result;
}

std::string angles_csv(const AnglesResult& result) {
  std::string text = "frame,time_s";
  for (const auto& joint : result.kinematics.joints)
    text += "," + joint.name + ".flexion_deg," + joint.name + ".adduction_deg," + joint.name +
            ".internal_rotation_deg";
  text += "\n";
  for (std::size_t f = 0; f < result.frames.size(); ++f) {
    text += std::to_string(f) + "," + fixed(result.rate_hz > 0 ? f / result.rate_hz : 0.0, 6);
    for (const auto& angles : result.frames[f].angles) {
      if (!angles.valid) {
        text += ",,,";
        continue;
      }
      for (const double v : {angles.flexion_deg, angles.adduction_deg, angles.internal_rotation_deg})
        append_field(text, fixed(v, 4));
    }
    text += "\n";
  }
  return text;
}

std::string poses_csv(const AnglesResult& result) {
  std::string text = "frame,time_s,segment,x_m,y_m,z_m,qw,qx,qy,qz,rms_mm,markers_used,joint_centre\n";
  for (std::size_t f = 0; f < result.frames.size(); ++f) {
    const std::string time = fixed(result.rate_hz > 0 ? f / result.rate_hz : 0.0, 6);
    for (std::size_t s = 0; s < result.frames[f].poses.size(); ++s) {
      const auto& pose = result.frames[f].poses[s];
      if (!pose.valid) continue;
      const auto& T = pose.T_world_anatomical;
      text += std::to_string(f) + "," + time + "," + result.kinematics.segments[s].name;
      for (const double v : {T.t.x(), T.t.y(), T.t.z()}) append_field(text, fixed(v, 6));
      for (const double v : {T.q.w(), T.q.x(), T.q.y(), T.q.z()}) append_field(text, fixed(v, 7));
      append_field(text, fixed(pose.rms_m * 1e3, 3));
      append_field(text, std::to_string(pose.markers_used));
      append_field(text, pose.used_joint_centre ? "1" : "0");
      text += '\n';
    }
  }
  return text;
}

std::string angles_report(const AnglesResult& result) {
  const auto& kinematics = result.kinematics;
  std::string text;
  std::size_t posed_segments = 0;
  for (std::size_t s = 0; s < kinematics.segments.size(); ++s) {
    std::size_t posed = 0;
    double rms = 0.0;
    for (const auto& frame : result.frames) {
      if (!frame.poses[s].valid) continue;
      ++posed;
      rms += frame.poses[s].rms_m;
    }
    posed_segments += posed > 0 ? 1 : 0;
    text += "segment " + kinematics.segments[s].name + ": pose in " + std::to_string(posed) + "/" +
            std::to_string(result.frames.size()) + " frames" +
            (posed > 0 ? ", mean fit RMS " + fixed(rms / posed * 1e3, 2) + " mm" : "") + ", Y axis " +
            kinematics.segments[s].long_axis + ", " + side_name(kinematics.segments[s].side) + "\n";
  }
  for (std::size_t j = 0; j < kinematics.joints.size(); ++j) {
    double low = std::numeric_limits<double>::infinity();
    double high = -low;
    for (const auto& frame : result.frames) {
      if (!frame.angles[j].valid) continue;
      low = std::min(low, frame.angles[j].flexion_deg);
      high = std::max(high, frame.angles[j].flexion_deg);
    }
    text += "joint " + kinematics.joints[j].name + ": flexion " +
            (high >= low ? fixed(low, 1) + " .. " + fixed(high, 1) + " deg" : "never posed") + "\n";
  }
  for (const auto& warning : side_warnings(kinematics)) text += warning + "\n";
  text += "markers: " + std::to_string(result.filled_samples) + " samples gap-filled, " +
          (result.lowpass_hz > 0.0 ? "low-pass " + fixed(result.lowpass_hz, 3) + " Hz (zero lag)"
                                   : "unfiltered") +
          "\n";
  text += "{\"subject\":\"" + result.model.subject + "\",\"frames\":" + std::to_string(result.frames.size()) +
          ",\"segments\":" + std::to_string(kinematics.segments.size()) +
          ",\"posed_segments\":" + std::to_string(posed_segments) +
          ",\"joints\":" + std::to_string(kinematics.joints.size()) +
          ",\"model_markers_in_trial\":" + std::to_string(result.model_markers_in_trial) +
          ",\"filled_samples\":" + std::to_string(result.filled_samples) +
          ",\"lowpass_hz\":" + fixed(result.lowpass_hz, 3) + "}\n";
  return text;
}

}  // namespace panoptes::label_job
