// SPDX-License-Identifier: Apache-2.0
// panoptes_label_replay: estimator_node --out-labels JSON Lines (every confirmed track per instant)
// played through the live labeller again, offline and deterministic: what a live run's labeller
// did, reproduced from its own input (docs/marker_sets.md, "When a live run names wrongly"), with the
// labeller's default options but --soft-segments. The labeller runs at the records whose stamp is
// --period-s after its last run (0: every record). Writes the same format with its names, for
// tests/integration/score_labels.py.
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling_files/subject_model_file.h"

namespace {

using panoptes::labelling::Labeller;
using panoptes::labelling::LabellerOptions;
using panoptes::labelling::TrackPoint;

int run(int argc, char** argv) {
  std::string in_file;
  std::string out_file;
  std::vector<std::string> subject_files;
  std::vector<std::string> soft_segments{"Torso"};
  double period_s = 0.0;
  CLI::App app{"panoptes_label_replay: an --out-labels record played through the live labeller again",
               "panoptes_label_replay"};
  app.option_defaults()->always_capture_default();
  app.add_option("--labels", in_file, "estimator_node --out-labels JSON Lines")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--subjects", subject_files, "subject model YAML, one per subject")->required();
  app.add_option("--soft-segments", soft_segments, "segments whose markers move against each other");
  app.add_option("--period-s", period_s, "the labeller runs at most this often (0: every record)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--out", out_file, "the records again with the replayed names")->required();
  CLI11_PARSE(app, argc, argv);

  std::vector<panoptes::labelling::SubjectModel> models;
  for (const auto& path : subject_files) models.push_back(panoptes::labelling::load_subject_model(path));
  std::vector<std::string> subjects;
  for (const auto& model : models) subjects.push_back(model.subject);
  LabellerOptions options;
  options.soft_segments = soft_segments;
  Labeller labeller(std::move(models), options);

  std::ifstream in(in_file);
  std::ofstream out(out_file);
  if (!out) {
    std::fprintf(stderr, "panoptes_label_replay: cannot write '%s'\n", out_file.c_str());
    return 1;
  }
  std::string line;
  std::optional<std::int64_t> last_run;
  std::size_t records = 0;
  std::size_t runs = 0;
  while (std::getline(in, line)) {
    nlohmann::json record;
    try {
      record = nlohmann::json::parse(line);
    } catch (const nlohmann::json::exception& e) {
      std::fprintf(stderr, "panoptes_label_replay: %s line %zu: %s\n", in_file.c_str(), records + 1,
                   e.what());
      return 1;
    }
    const std::int64_t stamp = record.at("stamp_ns").get<std::int64_t>();
    std::vector<TrackPoint> points;
    for (const auto& entry : record.at("tracks")) {
      const auto& p = entry.at("p");
      points.push_back({entry.at("track").get<std::uint64_t>(),
                        {p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>()}});
    }
    ++records;
    if (!last_run || static_cast<double>(stamp - *last_run) * 1e-9 >= period_s) {
      labeller.update(points, static_cast<double>(stamp) * 1e-9);
      last_run = stamp;
      ++runs;
    }
    for (auto& entry : record["tracks"]) {
      entry.erase("subject");
      entry.erase("marker");
      if (const auto label = labeller.label_of(entry.at("track").get<std::uint64_t>())) {
        entry["subject"] = subjects.at(label->subject);
        entry["marker"] = label->marker;
      }
    }
    out << record.dump() << '\n';
  }
  std::printf(
      "panoptes_label_replay: %zu records, %zu labeller runs, %llu pairs untangled, %llu names released\n",
      records, runs, static_cast<unsigned long long>(labeller.untangled()),
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
