// SPDX-License-Identifier: Apache-2.0
#include "panoptes/label_job/label_job.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace panoptes::label_job {

namespace {

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string subject_name(const ModelCommandOptions& options) {
  if (!options.subject.empty()) return options.subject;
  return std::filesystem::path(trial_file(options)).stem().string();
}

const std::string& trial_file(const ModelCommandOptions& options) {
  return options.labelled.empty() ? options.static_trial : options.labelled;
}

std::pair<std::size_t, std::size_t> frame_range(const std::string& frames) {
  std::pair<std::size_t, std::size_t> range{0, std::numeric_limits<std::size_t>::max()};
  if (frames.empty()) return range;
  const auto colon = frames.find(':');
  if (colon == std::string::npos)
    throw std::invalid_argument("--frames: expected FIRST:LAST, got '" + frames + "'");
  const auto number = [&](const std::string& text, std::size_t fallback) {
    if (text.empty()) return fallback;
    std::size_t used = 0;
    const unsigned long long value = std::stoull(text, &used);
    if (used != text.size())
      throw std::invalid_argument("--frames: expected a frame number, got '" + text + "'");
    return static_cast<std::size_t>(value);
  };
  try {
    range = {number(frames.substr(0, colon), range.first), number(frames.substr(colon + 1), range.second)};
  } catch (const std::logic_error&) {
    throw std::invalid_argument("--frames: expected FIRST:LAST with frame numbers, got '" + frames + "'");
  }
  if (range.first >= range.second)
    throw std::invalid_argument("--frames: FIRST must be below LAST, got '" + frames + "'");
  return range;
}

std::optional<std::string> find_problem(const ModelCommandOptions& options) {
  if (options.static_trial.empty() == options.labelled.empty())
    return "give exactly one of --static (a static trial) and --labelled (a labelled dynamic trial)";
  try {
    frame_range(options.frames);
  } catch (const std::invalid_argument& error) {
    return std::string(error.what());
  }
  return std::nullopt;
}

labelling::SubjectModel run_model(const ModelCommandOptions& options) {
  const labelling::MarkerSet set = labelling::load_marker_set(options.marker_set);
  const auto [first, last] = frame_range(options.frames);
  const labelling::MarkerSamples trial =
      labelling::slice_frames(labelling::load_marker_samples(trial_file(options)), first, last);
  labelling::ModelOptions model_options;
  model_options.dynamic = !options.labelled.empty();
  model_options.sigmas = options.sigmas;
  model_options.min_tolerance_m = options.min_tolerance_mm / 1000.0;
  model_options.still_m = options.still_mm / 1000.0;
  labelling::SubjectModel model =
      labelling::build_subject_model(set, trial, subject_name(options), model_options);
  labelling::save_subject_model(model, options.out);
  return model;
}

std::string model_report(const labelling::SubjectModel& model) {
  std::string text = "subject '" + model.subject + "', marker set '" + model.marker_set + "', " +
                     std::to_string(model.frames) + " frames of " + model.trial_file + "\n";
  for (const auto& segment : model.segments) {
    const std::size_t tracked = segment.tracked_marker_names().size();
    text += "  " + segment.name + (segment.parent.empty() ? "" : " (parent " + segment.parent + ")") + ": " +
            std::to_string(tracked) + " tracked markers";
    if (segment.markers.size() > tracked)
      text += " + " + std::to_string(segment.markers.size() - tracked) + " calibration-only";
    text +=
        segment.has_pose ? ", static fit RMS " : ", no pose (fewer than 3 tracked markers), static fit RMS ";
    text += format("%.2f mm", segment.static_fit_rms_m * 1000.0) + "\n";
  }
  for (const auto& joint : model.joints)
    text += "  joint " + joint.name + ": " + joint.parent + " -> " + joint.child + "\n";
  for (const auto& flag : model.flags) text += "  flagged " + flag.marker + ": " + flag.reason + "\n";
  const std::size_t moved =
      static_cast<std::size_t>(std::count_if(model.flags.begin(), model.flags.end(), [](const auto& flag) {
        return flag.kind == labelling::MarkerFlag::Kind::kMoved;
      }));
  if (2 * moved > model.marker_count())
    text += "  the subject did not stand still: " + std::to_string(moved) + " of " +
            std::to_string(model.marker_count()) +
            " markers moved; the layouts follow the motion (fit RMS above)\n";
  if (!model.ignored_points.empty()) {
    text +=
        "  ignored " + std::to_string(model.ignored_points.size()) + " points of the trial not in the set:";
    for (const auto& name : model.ignored_points) text += " " + name;
    text += "\n";
  }
  return text;
}

std::string model_summary_line(const labelling::SubjectModel& model) {
  double worst_rms = 0.0;
  for (const auto& segment : model.segments) worst_rms = std::max(worst_rms, segment.static_fit_rms_m);
  return "{\"subject\":" + quoted(model.subject) + ",\"segments\":" + std::to_string(model.segments.size()) +
         ",\"markers\":" + std::to_string(model.marker_count()) +
         ",\"joints\":" + std::to_string(model.joints.size()) +
         ",\"flagged\":" + std::to_string(model.flags.size()) +
         ",\"ignored_points\":" + std::to_string(model.ignored_points.size()) +
         ",\"worst_fit_rms_mm\":" + format("%.3f", worst_rms * 1000.0) + "}";
}

}  // namespace panoptes::label_job
