// SPDX-License-Identifier: Apache-2.0
// panoptes_label_replay: estimator_node --out-labels JSON Lines (every confirmed track per instant)
// played through the live labeller again, offline and deterministic: what a live run's labeller
// did, reproduced from its own input (docs/marker_sets.md, "When a live run names wrongly"), with the
// labeller's default options but --soft-segments. The labeller runs at the records whose stamp is
// --period-s after its last run (0: every record), or, with --as-recorded, at the records whose stamp
// a record names as its "labelled_ns" (the live run's own schedule), each record then carrying the
// names of the run it names: the live names again, unless the labeller's logic differs from the
// run's (its lag behind the frames is the record's). Writes the same format with its names, for
// tests/integration/score_labels.py.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace {

using panoptes::labelling::Labeller;
using panoptes::labelling::LabellerOptions;
using panoptes::labelling::TrackPoint;

using Names = std::vector<std::pair<std::uint64_t, panoptes::labelling::MarkerLabel>>;

// Every record of the file (throws naming the line).
std::vector<nlohmann::json> read_records(const std::string& path) {
  std::ifstream in(path);
  std::vector<nlohmann::json> records;
  std::string line;
  while (std::getline(in, line)) {
    try {
      records.push_back(nlohmann::json::parse(line));
    } catch (const nlohmann::json::exception& e) {
      throw std::runtime_error(path + " line " + std::to_string(records.size() + 1) + ": " + e.what());
    }
  }
  return records;
}

std::vector<TrackPoint> points_of(const nlohmann::json& record) {
  std::vector<TrackPoint> points;
  for (const auto& entry : record.at("tracks")) {
    const auto& p = entry.at("p");
    points.push_back({entry.at("track").get<std::uint64_t>(),
                      {p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>()}});
  }
  return points;
}

// The record's tracks named from `names` (sorted by track), the recorded names dropped.
void rename(nlohmann::json& record, const Names& names, const std::vector<std::string>& subjects) {
  for (auto& entry : record["tracks"]) {
    entry.erase("subject");
    entry.erase("marker");
    const auto track = entry.at("track").get<std::uint64_t>();
    const auto found = std::lower_bound(names.begin(), names.end(), track,
                                        [](const auto& named, std::uint64_t id) { return named.first < id; });
    if (found == names.end() || found->first != track) continue;
    entry["subject"] = subjects.at(found->second.subject);
    entry["marker"] = found->second.marker;
  }
}

int run(int argc, char** argv) {
  std::string in_file;
  std::string out_file;
  std::vector<std::string> subject_files;
  std::vector<std::string> soft_segments{"Torso"};
  double period_s = 0.0;
  bool as_recorded = false;
  CLI::App app{"panoptes_label_replay: an --out-labels record played through the live labeller again",
               "panoptes_label_replay"};
  app.option_defaults()->always_capture_default();
  app.add_option("--labels", in_file, "estimator_node --out-labels JSON Lines")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--subjects", subject_files, "subject model YAML, one per subject")->required();
  app.add_option("--soft-segments", soft_segments, "segments whose markers move against each other");
  auto* period =
      app.add_option("--period-s", period_s, "the labeller runs at most this often (0: every record)")
          ->check(CLI::NonNegativeNumber);
  app.add_flag("--as-recorded", as_recorded,
               "the labeller runs at the records the live runs named (\"labelled_ns\") and each record "
               "carries the names of its own run")
      ->excludes(period);
  app.add_option("--out", out_file, "the records again with the replayed names")->required();
  CLI11_PARSE(app, argc, argv);

  std::vector<panoptes::labelling::SubjectModel> models;
  for (const auto& path : subject_files) models.push_back(panoptes::labelling::load_subject_model(path));
  std::vector<std::string> subjects;
  for (const auto& model : models) subjects.push_back(model.subject);
  LabellerOptions options;
  options.soft_segments = soft_segments;
  Labeller labeller(std::move(models), options);

  std::vector<nlohmann::json> records = read_records(in_file);
  std::ofstream out(out_file);
  if (!out) {
    std::fprintf(stderr, "panoptes_label_replay: cannot write '%s'\n", out_file.c_str());
    return 1;
  }
  std::set<std::int64_t> recorded_runs;
  if (as_recorded) {
    for (const auto& record : records) recorded_runs.insert(record.value("labelled_ns", std::int64_t{0}));
    recorded_runs.erase(0);
    if (recorded_runs.empty())
      throw std::runtime_error(in_file + ": no record has \"labelled_ns\" (an older file?)");
  }
  std::map<std::int64_t, Names> names_at;  // --as-recorded: each run's names
  std::optional<std::int64_t> last_run;
  std::size_t runs = 0;
  for (auto& record : records) {
    const auto stamp = record.at("stamp_ns").get<std::int64_t>();
    const bool due = as_recorded ? recorded_runs.count(stamp) != 0
                                 : !last_run || static_cast<double>(stamp - *last_run) * 1e-9 >= period_s;
    if (due) {
      labeller.update(points_of(record), static_cast<double>(stamp) * 1e-9);
      last_run = stamp;
      ++runs;
      if (as_recorded) names_at[stamp] = labeller.labels();
    }
    if (as_recorded) {
      const auto found = names_at.find(record.value("labelled_ns", std::int64_t{0}));
      rename(record, found == names_at.end() ? Names{} : found->second, subjects);
    } else {
      rename(record, labeller.labels(), subjects);
    }
    out << record.dump() << '\n';
  }
  std::printf(
      "panoptes_label_replay: %zu records, %zu labeller runs, %llu pairs untangled, %llu names released\n",
      records.size(), runs, static_cast<unsigned long long>(labeller.untangled()),
      static_cast<unsigned long long>(labeller.released()));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "panoptes_label_replay: %s\n", e.what());
    return 1;
  }
}
