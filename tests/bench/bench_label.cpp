// SPDX-License-Identifier: Apache-2.0
// bench_label: live labelling cost per subject-frame (issue 33, "Benchmark"; docs/marker_sets.md).
// The Gait2392 subject01 model from its static trial; walk1 (60 Hz) interpolated to --rate-hz and
// played by 1, 2 and 4 subjects at once (each 1.5 m beside the last, along the walk's narrowest axis,
// and 0.7 s later in the walk),
// every marker a track with a stable id, hidden markers left out. Labeller::update runs on every
// instant with the instant's time, as the estimator's labelling stage does; its time is divided by
// the subjects. Also reported: the share of marker-instants named right, names that crossed to
// another subject (must be 0), and the cost of the segment poses the estimator publishes after the
// names (session::SegmentStage::append on the instant's named markers, docs/marker_sets.md "Segment
// poses live"), per subject-frame. Goal: <= 50 us per subject-frame on one core.
//   bench_label [--json] [--subjects 1,2,4] [--rate-hz 240] [--seconds 4]
// With --json the last line of output is one JSON object (docs/benchmarks.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling/subject_model.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"
#include "panoptes/process.h"
#include "panoptes/session/segment_stage.h"

namespace {

namespace lab = panoptes::labelling;
namespace fs = std::filesystem;

struct Cell {
  int subjects = 0;
  double mean_us = 0, p99_us = 0;                    // per subject-frame
  double segments_mean_us = 0, segments_p99_us = 0;  // segment poses, per subject-frame
  double right_percent = 0;
  long crossed = 0;  // a person's marker named by another subject than the one naming that person
  long instants = 0;
};

// The walk at `t` seconds (looped), linearly interpolated; false where the marker is hidden.
bool walk_at(const lab::MarkerSamples& walk, double t, std::size_t m, Eigen::Vector3d& out) {
  const double frames = static_cast<double>(walk.frame_count());
  double f = std::fmod(t * walk.rate_hz, frames - 1.0);
  if (f < 0) f += frames - 1.0;
  const auto a = static_cast<std::size_t>(f);
  const std::size_t b = std::min(a + 1, walk.frame_count() - 1);
  if (!walk.is_valid(a, m) || !walk.is_valid(b, m)) return false;
  const double w = f - static_cast<double>(a);
  out = (1.0 - w) * walk.position(a, m) + w * walk.position(b, m);
  return out.allFinite();
}

// The axis along which the walk's markers spread least (the walk's side, whatever its up axis): the
// subjects stand side by side along it.
int side_axis(const lab::MarkerSamples& walk) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(1e9), high = Eigen::Vector3d::Constant(-1e9);
  for (std::size_t f = 0; f < walk.frame_count(); ++f)
    for (std::size_t m = 0; m < walk.point_count(); ++m)
      if (walk.is_valid(f, m) && walk.position(f, m).allFinite()) {
        low = low.cwiseMin(walk.position(f, m));
        high = high.cwiseMax(walk.position(f, m));
      }
  int axis = 0;
  (high - low).minCoeff(&axis);
  return axis;
}

Cell run_cell(const lab::SubjectModel& model, const lab::MarkerSamples& walk, int subjects, double rate_hz,
              double seconds) {
  std::vector<lab::SubjectModel> models;
  for (int s = 0; s < subjects; ++s) {
    models.push_back(model);
    models.back().subject = "s" + std::to_string(s + 1);
  }
  lab::LabellerOptions options;
  options.soft_segments = {"Torso"};
  lab::Labeller labeller(models, options);
  const panoptes::session::SegmentStage segments(models, lab::KinematicsOptions{});
  std::map<std::string, int> segment_ids;
  for (const auto& description : segments.descriptions())
    segment_ids.emplace(description.name, static_cast<int>(segment_ids.size()) + 1);
  panoptes::session::FrameOutput frame;
  std::vector<double> per_subject_us;
  std::vector<double> segments_us;
  double visible = 0, right = 0;
  Cell cell;
  cell.subjects = subjects;
  const int side = side_axis(walk);
  const auto instants = static_cast<long>(seconds * rate_hz);
  std::vector<lab::TrackPoint> points;
  struct Named {
    std::size_t person, subject;
    bool right;
  };
  std::vector<Named> named;
  for (long k = 0; k < instants; ++k) {
    const double t = static_cast<double>(k) / rate_hz;
    points.clear();
    for (int s = 0; s < subjects; ++s) {
      for (std::size_t m = 0; m < walk.point_count(); ++m) {
        Eigen::Vector3d p;
        if (!walk_at(walk, t + 0.7 * s, m, p)) continue;
        p[side] += 1.5 * s;
        points.push_back({(1000 * static_cast<std::uint64_t>(s + 1)) + m, p});
      }
    }
    const auto start = std::chrono::steady_clock::now();
    labeller.update(points, t);
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    per_subject_us.push_back(us / subjects);
    frame.bodies.clear();
    frame.markers.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto& point = points[i];
      const std::size_t person = point.track / 1000 - 1, m = point.track % 1000;
      const auto label = labeller.label_of(point.track);
      visible += 1;
      frame.markers[i].track.p = point.position_m;
      frame.markers[i].subject = label ? models[label->subject].subject : "";
      frame.markers[i].name = label ? label->marker : "";
      if (!label) continue;
      named.push_back({person, label->subject, label->marker == walk.names[m]});
    }
    const auto segments_start = std::chrono::steady_clock::now();
    segments.append(frame, segment_ids);
    segments_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - segments_start).count() /
        subjects);
  }
  // The subjects share one model, so which subject takes which person is the labeller's choice:
  // each person is the subject that names most of its markers, a different subject per person; a
  // name from another subject crossed subjects.
  std::vector<std::vector<long>> votes(static_cast<std::size_t>(subjects),
                                       std::vector<long>(static_cast<std::size_t>(subjects), 0));
  for (const Named& n : named) ++votes[n.person][n.subject];
  std::vector<std::size_t> subject_of(votes.size());
  std::vector<char> taken(votes.size(), 0);
  for (std::size_t person = 0; person < votes.size(); ++person) {
    const auto best = std::max_element(votes[person].begin(), votes[person].end()) - votes[person].begin();
    subject_of[person] = static_cast<std::size_t>(best);
    if (taken[subject_of[person]] != 0) subject_of[person] = votes.size();  // two persons, one subject
    taken[static_cast<std::size_t>(best)] = 1;
  }
  for (const Named& n : named) {
    if (n.subject != subject_of[n.person]) {
      ++cell.crossed;
    } else {
      right += n.right ? 1 : 0;
    }
  }
  cell.instants = instants;
  std::sort(per_subject_us.begin(), per_subject_us.end());
  double sum = 0;
  for (double us : per_subject_us) sum += us;
  cell.mean_us = per_subject_us.empty() ? 0 : sum / static_cast<double>(per_subject_us.size());
  cell.p99_us = per_subject_us.empty() ? 0 : per_subject_us[per_subject_us.size() * 99 / 100];
  cell.right_percent = visible > 0 ? 100.0 * right / visible : 0.0;
  std::sort(segments_us.begin(), segments_us.end());
  double segments_sum = 0;
  for (double us : segments_us) segments_sum += us;
  cell.segments_mean_us = segments_us.empty() ? 0 : segments_sum / static_cast<double>(segments_us.size());
  cell.segments_p99_us = segments_us.empty() ? 0 : segments_us[segments_us.size() * 99 / 100];
  return cell;
}

int run(int argc, char** argv) {
  CLI::App app{"bench_label: live labelling cost per subject-frame (1, 2, 4 subjects), one thread",
               "bench_label"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  const fs::path data = fs::path(PANOPTES_SOURCE_DIR) / ".." / "shared" / "data" / "static";
  std::string static_trial = (data / "gait2392_subject01_static.trc").string();
  std::string walk_file = (data / "gait2392_subject01_walk1.trc").string();
  std::string marker_set =
      (fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "markersets" / "gait2392.yaml").string();
  std::vector<int> subject_counts = {1, 2, 4};
  double rate_hz = 240, seconds = 4;
  bool json = false;
  app.add_option("--static", static_trial, "static trial the model is built from");
  app.add_option("--walk", walk_file, "walk played by every subject");
  app.add_option("--markerset", marker_set, "marker set");
  app.add_option("--subjects", subject_counts, "subject counts to time")
      ->delimiter(',')
      ->check(CLI::Range(1, 16));
  app.add_option("--rate-hz", rate_hz, "labelling instants per second")->check(CLI::Range(1.0, 2000.0));
  app.add_option("--seconds", seconds, "seconds of walk per cell")->check(CLI::Range(0.1, 600.0));
  app.add_flag("--json", json, "print one JSON object on the last line");
  if (auto code = panoptes::parse_command_line(app, argc, argv)) return *code;

  const lab::MarkerSet set = lab::load_marker_set(marker_set);
  const lab::SubjectModel model = lab::build_subject_model(set, lab::load_marker_samples(static_trial), "s1");
  const lab::MarkerSamples walk = lab::load_marker_samples(walk_file);
  std::vector<Cell> cells;
  for (const int n : subject_counts) {
    cells.push_back(run_cell(model, walk, n, rate_hz, seconds));
    const Cell& c = cells.back();
    std::printf(
        "%d subject%s at %.0f Hz: %.1f us per subject-frame (mean), p99 %.1f us; %.2f %% of marker-instants "
        "named right, %ld named by another subject than their person's, %ld instants; segment poses %.1f us "
        "per "
        "subject-frame (mean), p99 %.1f us\n",
        c.subjects, c.subjects == 1 ? "" : "s", rate_hz, c.mean_us, c.p99_us, c.right_percent, c.crossed,
        c.instants, c.segments_mean_us, c.segments_p99_us);
  }
  std::printf("goal: <= 50 us per subject-frame on one core (issue 33)\n");
  if (json) {
    std::string text = "{\"rate_hz\": " + std::to_string(rate_hz) + ", \"cells\": [";
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const Cell& c = cells[i];
      char entry[320];
      std::snprintf(entry, sizeof entry,
                    "%s{\"subjects\": %d, \"mean_us\": %.2f, \"p99_us\": %.2f, \"right_percent\": %.3f, "
                    "\"crossed\": %ld, \"segments_mean_us\": %.2f, \"segments_p99_us\": %.2f}",
                    i == 0 ? "" : ", ", c.subjects, c.mean_us, c.p99_us, c.right_percent, c.crossed,
                    c.segments_mean_us, c.segments_p99_us);
      text += entry;
    }
    std::printf("%s]}\n", text.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("bench_label", [&] { return run(argc, argv); });
}
