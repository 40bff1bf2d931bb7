// SPDX-License-Identifier: Apache-2.0
// `estimator_node calibrate history|revert|accept` (docs/calibration.md, "Versions"): the versions
// of a calibration file stored beside it (panoptes/calibration_history.h).
#include <cmath>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "calibrate_history_cli.h"
#include "panoptes/calibration_history.h"
#include "panoptes/cli.h"
#include "panoptes/process.h"

namespace panoptes::calib {

namespace {

std::string residuals(const CalibrationChange& change) {
  if (!std::isfinite(change.residual_before_px) && !std::isfinite(change.residual_after_px)) return "";
  char text[96];
  std::snprintf(text, sizeof text, ", residual %.3g -> %.3g px", change.residual_before_px,
                change.residual_after_px);
  return text;
}

std::string cameras(const CalibrationChange& change) {
  if (change.cameras.empty()) return "";
  std::string text = ", cameras";
  for (const auto& camera : change.cameras) text += " " + camera;
  return text;
}

void print_versions(const CalibrationHistory& history, bool json) {
  const auto versions = history.versions();
  if (json) {
    for (const auto& v : versions) {
      nlohmann::json j = {{"version", v.version},        {"time_utc", v.time_utc},
                          {"reason", v.change.reason},   {"cameras", v.change.cameras},
                          {"state", to_string(v.state)}, {"file", (history.directory() / v.file).string()}};
      std::printf("%s\n", j.dump().c_str());
    }
    return;
  }
  if (versions.empty()) {
    std::printf("%s: no versions yet (the history begins with the first change)\n",
                history.calibration_file().string().c_str());
    return;
  }
  for (const auto& v : versions) {
    std::printf("v%d  %s  %-8s  %s%s%s%s\n", v.version, v.time_utc.c_str(), to_string(v.state),
                v.change.reason.c_str(), cameras(v.change).c_str(), residuals(v.change).c_str(),
                &v == &versions.back() ? "  (current)" : "");
  }
}

}  // namespace

int run_calibrate_history(int argc, char** argv) {
  const std::string sub = argv[0];
  std::string file;
  int version = 0;
  bool json = false;
  bool start = false;
  CLI::App app{"calibrate " + sub + ": the versions of a calibration file, kept beside it in <file>.history/",
               "estimator_node calibrate " + sub};
  app.add_option("--calibration", file, "the calibration file")->required()->check(CLI::ExistingFile);
  if (sub == "history") {
    app.add_flag("--json", json, "one JSON object per version");
    app.add_flag("--start", start,
                 "start the history: the file as it is becomes version 1, and `calibrate solve|world --out` "
                 "this file then add versions");
  } else {
    app.add_option("--version", version, sub == "revert" ? "the version to restore" : "the version to accept")
        ->required();
  }
  if (auto exit = parse_command_line(app, argc, argv)) return *exit;
  CalibrationHistory history(file);
  if (start) history.start();
  if (sub == "revert") {
    const auto before = history.versions().size();
    const auto v = history.revert(version);
    if (history.versions().size() == before)
      std::printf("version %d is the current file already (v%d): nothing to restore\n", version, v.version);
    else
      std::printf("restored version %d as v%d%s\n", version, v.version, cameras(v.change).c_str());
  } else if (sub == "accept") {
    history.accept(version);
    std::printf("accepted v%d\n", version);
  }
  print_versions(history, json);
  return kExitOk;
}

}  // namespace panoptes::calib
