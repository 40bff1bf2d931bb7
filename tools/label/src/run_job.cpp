// SPDX-License-Identifier: Apache-2.0
// panoptes_label run (docs/marker_sets.md, "Offline labelling"): tracks in, labelled and gap-filled
// trajectories out through the project's C3D, TRC and CSV writers.
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "panoptes/errors.h"
#include "panoptes/export_job/recording_source.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/csv.h"
#include "panoptes/formats/record_source.h"
#include "panoptes/formats/resample.h"
#include "panoptes/formats/trc.h"
#include "panoptes/label_job/label_job.h"
#include "panoptes/labelling_files/static_trial.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace fs = std::filesystem;

namespace panoptes::label_job {

namespace {

// Measured samples carry a nominal residual so that the C3D writer does not mark them computed.
constexpr float kMeasuredResidualM = 0.001F;

std::string extension_of(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

labelling::MarkerSamples to_samples(MarkerTrajectories data, const std::string& source) {
  labelling::MarkerSamples samples;
  samples.source = source;
  samples.rate_hz = data.data_rate_hz;
  samples.names = std::move(data.marker_names);
  samples.positions = std::move(data.positions);
  samples.valid = std::move(data.valid);
  return samples;
}

// The input as anonymous columns: a labelled file's markers, or the estimator's tracks resampled to
// options.rate_hz (a track updated less often than every two samples has a gap there).
labelling::MarkerSamples read_tracks(const RunCommandOptions& options, RunSummary& summary) {
  const std::string& input = input_of(options);
  const std::string extension = extension_of(input);
  if (options.in_recording.empty() && (extension == ".c3d" || extension == ".trc")) {
    summary.input_format = extension.substr(1);
    return labelling::load_marker_samples(input);
  }
  ExportRecords records;
  if (!options.in_recording.empty()) {
    summary.input_format = "recording";
    records = export_job::RecordingRecordSource(fs::path(options.in_recording)).read();
  } else {
    summary.input_format = "tracks";
    records = JsonlRecordSource(fs::path(options.tracks), std::nullopt).read();
  }
  for (const std::string& error : records.skipped) std::fprintf(stderr, "skipped %s\n", error.c_str());
  summary.skipped_records = records.skipped.size();
  if (records.tracks.empty()) throw ConfigError(input, "", "no track records to label");
  ResampleOptions resample;
  resample.rate_hz = options.rate_hz;
  resample.max_gap_ns = static_cast<TimeNs>(2.0e9 / options.rate_hz);
  const SampleGrid grid = make_grid(records.tracks, {}, resample);
  return to_samples(resample_tracks(records.tracks, grid, resample), input);
}

// The subjects' labelled, filled trajectories side by side; names "subject:marker" for several.
MarkerTrajectories output_of(const std::vector<labelling::SubjectModel>& models,
                             const std::vector<labelling::MarkerSamples>& labelled,
                             const std::vector<std::vector<std::uint8_t>>& filled, std::size_t frames,
                             double rate_hz) {
  MarkerTrajectories out;
  out.data_rate_hz = rate_hz;
  out.units = "mm";
  for (std::size_t s = 0; s < models.size(); ++s) {
    for (const auto& name : labelled[s].names)
      out.marker_names.push_back(models.size() > 1 ? models[s].subject + ":" + name : name);
  }
  const std::size_t markers = out.marker_names.size();
  for (std::size_t f = 0; f < frames; ++f) out.times_s.push_back(static_cast<double>(f) / rate_hz);
  out.positions.assign(frames * markers, Eigen::Vector3d::Zero());
  out.valid.assign(frames * markers, 0);
  out.residuals_m.assign(frames * markers, 0.0F);
  for (std::size_t f = 0; f < frames; ++f) {
    std::size_t column = 0;
    for (std::size_t s = 0; s < models.size(); ++s) {
      for (std::size_t m = 0; m < labelled[s].point_count(); ++m, ++column) {
        const std::size_t in = f * labelled[s].point_count() + m;
        out.positions[f * markers + column] = labelled[s].positions[in];
        out.valid[f * markers + column] = labelled[s].valid[in];
        out.residuals_m[f * markers + column] = filled[s][in] != 0 ? 0.0F : kMeasuredResidualM;
      }
    }
  }
  return out;
}

void write_output(const std::string& path, const MarkerTrajectories& data) {
  const std::string extension = extension_of(path);
  if (extension == ".c3d") {
    C3dWriteOptions c3d;
    c3d.software = "panoptes_label";
    write_c3d(path, data, c3d);
  } else if (extension == ".trc") {
    write_trc(path, data);
  } else {
    write_markers_csv(path, data);
  }
}

}  // namespace

const std::string& input_of(const RunCommandOptions& options) {
  return options.in_recording.empty() ? options.tracks : options.in_recording;
}

std::optional<std::string> find_problem(const RunCommandOptions& options) {
  if (options.tracks.empty() == options.in_recording.empty())
    return "input: give --tracks or --in-recording (one of them)";
  if (!parse_fill_method(options.fill))
    return "--fill: expected pattern, relational, spline, linear or none, got '" + options.fill + "'";
  if (!(options.max_gap_s >= 0.0) || !std::isfinite(options.max_gap_s))
    return "--max-gap-s: expected a number of seconds >= 0";
  const std::string out = extension_of(options.out);
  if (out != ".c3d" && out != ".trc" && out != ".csv")
    return "--out: expected a .c3d, .trc or .csv file, got '" + options.out + "'";
  if (options.subjects.empty()) return "--subjects: give at least one subject model";
  return std::nullopt;
}

RunSummary run_labelling(const RunCommandOptions& options) {
  RunSummary summary;
  std::vector<labelling::SubjectModel> models;
  for (const auto& path : options.subjects) models.push_back(labelling::load_subject_model(path));
  const labelling::MarkerSamples tracks = read_tracks(options, summary);
  if (tracks.frame_count() == 0 || !(tracks.rate_hz > 0.0))
    throw ConfigError(input_of(options), "", "no frames at a known rate to label");
  summary.tracks = tracks.point_count();
  labelling::LabellerOptions labeller;
  labeller.soft_segments = options.soft_segments;
  summary.labelling = labelling::label_offline(models, tracks, labeller);
  labelling::FillOptions fill;
  fill.method = *parse_fill_method(options.fill);
  fill.max_gap_frames = static_cast<std::size_t>(std::floor(options.max_gap_s * tracks.rate_hz + 1e-9));
  std::vector<labelling::MarkerSamples> labelled;
  std::vector<std::vector<std::uint8_t>> filled(models.size());
  for (std::size_t s = 0; s < models.size(); ++s) {
    labelled.push_back(labelling::labelled_trajectories(models[s], s, tracks, summary.labelling));
    SubjectFill report{models[s].subject, {}, 0};
    for (auto valid : labelled.back().valid) report.marker_frames += valid;
    report.fill = labelling::fill_gaps(models[s], labelled.back(), filled[s], fill);
    summary.subjects.push_back(report);
  }
  summary.output = output_of(models, labelled, filled, tracks.frame_count(), tracks.rate_hz);
  write_output(options.out, summary.output);
  if (!options.report.empty()) {
    std::ofstream file(options.report);
    file << run_report_json(options, summary) << "\n";
    if (!file) throw ConfigError(options.report, "", "cannot write the report");
  }
  return summary;
}

namespace {

nlohmann::json count_json(const labelling::FillCount& count) {
  return {{"gaps", count.gaps}, {"frames", count.frames}};
}

}  // namespace

std::optional<labelling::FillMethod> parse_fill_method(const std::string& name) {
  if (name == "none") return labelling::FillMethod::kNone;
  if (name == "linear") return labelling::FillMethod::kLinear;
  if (name == "spline") return labelling::FillMethod::kSpline;
  if (name == "relational") return labelling::FillMethod::kRelational;
  if (name == "pattern") return labelling::FillMethod::kPattern;
  return std::nullopt;
}

std::string run_report_json(const RunCommandOptions& options, const RunSummary& summary) {
  const auto& l = summary.labelling;
  nlohmann::json subjects = nlohmann::json::array();
  for (const auto& s : summary.subjects) {
    subjects.push_back(
        {{"subject", s.subject},
         {"labelled_marker_frames", s.marker_frames},
         {"filled",
          {{"linear", count_json(s.fill.linear)},
           {"spline", count_json(s.fill.spline)},
           {"relational", count_json(s.fill.relational)},
           {"pattern", count_json(s.fill.pattern)}}},
         {"left_open",
          {{"too_long", count_json(s.fill.too_long)}, {"at_ends", count_json(s.fill.open_end)}}}});
  }
  std::size_t runs_labelled = 0;
  for (const auto& run : l.runs) runs_labelled += run.label ? 1 : 0;
  const nlohmann::json report = {{"input", input_of(options)},
                                 {"format", summary.input_format},
                                 {"out", options.out},
                                 {"frames", l.frames},
                                 {"rate_hz", summary.output.data_rate_hz},
                                 {"tracks", summary.tracks},
                                 {"runs", l.runs.size()},
                                 {"runs_labelled", runs_labelled},
                                 {"track_frames", l.run_frames},
                                 {"track_frames_labelled", l.labelled_frames},
                                 {"runs_where_passes_disagreed", l.disagreements},
                                 {"fill", options.fill},
                                 {"max_gap_s", options.max_gap_s},
                                 {"skipped_records", summary.skipped_records},
                                 {"subjects", subjects}};
  return report.dump();
}

std::string run_report(const RunCommandOptions& options, const RunSummary& summary) {
  const auto& l = summary.labelling;
  char line[512];
  std::snprintf(line, sizeof line,
                "%s (%s): %zu frames at %.6g Hz, %zu tracks in %zu runs; %zu of %zu track-frames labelled "
                "(%.2f %%), the passes disagreed on %zu runs\n",
                input_of(options).c_str(), summary.input_format.c_str(), l.frames,
                summary.output.data_rate_hz, summary.tracks, l.runs.size(), l.labelled_frames, l.run_frames,
                l.run_frames == 0
                    ? 0.0
                    : 100.0 * static_cast<double>(l.labelled_frames) / static_cast<double>(l.run_frames),
                l.disagreements);
  std::string text = line;
  for (const auto& s : summary.subjects) {
    std::snprintf(
        line, sizeof line,
        "  %s: %zu labelled marker-frames; filled (--fill %s, max %.3g s): linear %zu gaps / %zu "
        "frames, spline %zu / %zu, relational %zu / %zu, pattern %zu / %zu; left open: %zu gaps longer, "
        "%zu at the "
        "ends\n",
        s.subject.c_str(), s.marker_frames, options.fill.c_str(), options.max_gap_s, s.fill.linear.gaps,
        s.fill.linear.frames, s.fill.spline.gaps, s.fill.spline.frames, s.fill.relational.gaps,
        s.fill.relational.frames, s.fill.pattern.gaps, s.fill.pattern.frames, s.fill.too_long.gaps,
        s.fill.open_end.gaps);
    text += line;
  }
  return text;
}

}  // namespace panoptes::label_job
