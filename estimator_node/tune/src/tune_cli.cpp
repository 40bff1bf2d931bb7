// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/tune_cli.h"

#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <CLI/CLI.hpp>

#include "panoptes/calibration_file.h"
#include "panoptes/cli.h"
#include "panoptes/errors.h"
#include "panoptes/process.h"
#include "panoptes/session/log.h"
#include "panoptes/simulator.h"
#include "panoptes/tune/criteria.h"
#include "panoptes/tune/search.h"
#include "panoptes/tune/tune_parameters.h"
#include "panoptes/tune/tune_plot.h"

namespace panoptes::tune {

namespace {

struct TuneArgs {
  std::string calibration_file;
  std::vector<std::string> in_features;
  std::string in_recording;
  std::string criterion = "heldout";
  std::string scene_file;
  long long epoch_ns = 1'700'000'000'000'000'000LL;
  std::string config_file;
  std::string params = "measurement_noise_px,process_noise,gate_chi2";
  SearchOptions search;
  HeldOutCriterionOptions held_out;
  TruthCriterionOptions truth;
  std::string out_config;
  std::string out_curve;
  std::string plot;
  bool quiet = false;
};

void add_options(CLI::App& app, TuneArgs& a) {
  app.option_defaults()->always_capture_default();
  app.add_option("--calibration", a.calibration_file, "calibration YAML (cameras with T_world_cam)")
      ->required();
  auto* features = app.add_option("--in-features", a.in_features,
                                  "FeatureFrame JSONL files (one per camera), as the offline mode")
                       ->expected(1, -1);
  auto* recording = app.add_option("--in-recording", a.in_recording,
                                   "an MCAP recording (panoptes_record), instead of --in-features");
  features->excludes(recording);
  app.add_option(
         "--criterion", a.criterion,
         "heldout: leave-one-camera-out prediction error (or NLL) + NIS consistency (no ground truth); "
         "truth: RMSE + ID-switch and coverage penalties against --scene")
      ->check(CLI::IsMember({"heldout", "truth"}));
  app.add_option("--scene", a.scene_file,
                 "simulator scene that produced the features: needed by --criterion truth; with heldout, "
                 "every sample's ground-truth RMSE is also reported (curve file and plot)");
  app.add_option("--epoch-ns", a.epoch_ns, "absolute stamp of scene time 0 (panoptes_sim's default)");
  app.add_option("--config", a.config_file, "start settings YAML (docs/estimator.md); default: the defaults");
  app.add_option("--params", a.params,
                 "comma-separated settings to search (tracker.<key>): process_noise, "
                 "measurement_noise_px, gate_chi2, init.epipolar_px, init.reprojection_px, "
                 "init.link_radius_px");
  app.add_option("--span", a.search.span, "first sweep searches start value / span .. × span (log space)")
      ->check(CLI::Range(1.01, 1e6));
  app.add_option("--grid", a.search.grid_points, "log-spaced grid points per line search")
      ->check(CLI::Range(2, 100));
  app.add_option("--golden", a.search.golden_iterations, "golden-section steps after the grid")
      ->check(CLI::Range(0, 100));
  app.add_option("--sweeps", a.search.sweeps, "coordinate-descent sweeps (each searches √ of the last span)")
      ->check(CLI::Range(1, 20));
  app.add_option("--heldout-score", a.held_out.score,
                 "heldout: residual (capped squared prediction error) or nll (negative log-likelihood)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, HeldOutCriterionOptions::Score>{
              {"residual", HeldOutCriterionOptions::Score::kResidual},
              {"nll", HeldOutCriterionOptions::Score::kNll}},
          CLI::ignore_case))
      ->default_str("residual");
  app.add_option("--residual-cap-px", a.held_out.residual_cap_px,
                 "heldout: squared residuals are capped at this² (a blob no track explains costs the cap)")
      ->check(CLI::PositiveNumber);
  app.add_option("--nis-weight", a.held_out.nis_weight, "heldout: weight of ln(mean NIS / expected)²")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--clutter-weight", a.held_out.clutter_weight,
                 "heldout: ε, share of blobs no track explains")
      ->check(CLI::Range(1e-6, 0.5));
  app.add_option("--switch-penalty-mm", a.truth.id_switch_penalty_mm, "truth: mm added per ID switch")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--coverage-penalty-mm", a.truth.lost_coverage_penalty_mm,
                 "truth: mm added × (1 − coverage of trackable marker-time)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--out-config", a.out_config, "write the tuned settings here (loadable by --config)")
      ->required();
  app.add_option("--out-curve", a.out_curve, "write every evaluation as CSV (default: <out-config>.csv)");
  app.add_option("--plot", a.plot, "write a PNG of the criterion against each parameter (/usr/bin/python3)");
  app.add_flag("--quiet", a.quiet, "no progress output");
}

std::vector<std::string> split_params(const std::string& text) {
  std::vector<std::string> names;
  std::stringstream in(text);
  for (std::string name; std::getline(in, name, ',');)
    if (!name.empty()) names.push_back(name);
  for (const auto& name : names) parameter_info(name);  // throws for an unknown name
  return names;
}

std::string sample_line(const SearchSample& sample, const std::vector<std::string>& params) {
  std::ostringstream line;
  line << "tune: [" << sample.index << "] sweep " << sample.sweep + 1 << ' ' << sample.varied << ':';
  for (std::size_t p = 0; p < params.size(); ++p) line << ' ' << params[p] << '=' << sample.values[p];
  line << " cost=" << sample.cost;
  return line.str();
}

struct Criterion {
  CostFunction cost;
  std::vector<std::string> extra_names;
  std::string label;
};

// The criteria refer to `args`, `input` and `scene`, which must outlive them.
Criterion make_criterion(const TuneArgs& args, const TuneInput& input, const Scene* scene) {
  const auto truth_extras = [&args, &input, scene](const session::EstimatorConfig& config,
                                                   std::vector<double>& extras) {
    const TruthScore score = truth_score(config, input, *scene, args.truth);
    extras.insert(extras.end(), {score.rmse_mm, static_cast<double>(score.id_switches), score.coverage});
    return score.cost;
  };
  const std::vector<std::string> truth_names = {"rmse_mm", "id_switches", "coverage"};
  if (args.criterion == "truth") {
    return {[truth_extras](const session::EstimatorConfig& config) {
              CostResult result;
              result.cost = truth_extras(config, result.extras);
              return result;
            },
            truth_names, "RMSE + penalties, mm"};
  }
  Criterion criterion{
      [&args, &input, scene, truth_extras](const session::EstimatorConfig& config) {
        const HeldOutScore score = held_out_score(config, input, args.held_out);
        CostResult result{score.cost, {score.rms_residual_px, score.nll_per_blob, score.mean_nis}};
        if (scene) truth_extras(config, result.extras);
        return result;
      },
      {"rms_residual_px", "nll_per_blob", "mean_nis"},
      args.held_out.score == HeldOutCriterionOptions::Score::kResidual
          ? "held-out ln(mean r² / px²) + NIS term"
          : "held-out NLL + NIS term"};
  if (scene)
    criterion.extra_names.insert(criterion.extra_names.end(), truth_names.begin(), truth_names.end());
  return criterion;
}

int tune(const TuneArgs& args, const RecordingReader& read_recording) {
  session::EstimatorConfig start = args.config_file.empty()
                                       ? session::EstimatorConfig{}
                                       : session::load_estimator_config(args.config_file);
  SearchOptions search = args.search;
  search.parameters = split_params(args.params);
  std::optional<Scene> scene;
  if (!args.scene_file.empty()) scene.emplace(Scene::load(args.scene_file));
  if (args.criterion == "truth" && !scene) throw ConfigError("--criterion", "truth", "needs --scene");
  TruthCriterionOptions truth = args.truth;
  truth.evaluation.epoch_ns = args.epoch_ns;
  TuneArgs effective = args;
  effective.truth = truth;

  TuneInput input;
  if (!args.in_recording.empty()) {
    if (!read_recording)
      throw ConfigError(args.in_recording, "--in-recording", "recordings are not readable here");
    try {
      input.calibration = load_calibration(args.calibration_file);
      session::FeatureFiles files = read_recording(args.in_recording);
      input.frames = std::move(files.frames);
      input.bad_lines = files.bad_lines;
      session::sort_by_stamp(input.frames);
    } catch (const std::runtime_error& error) {
      throw ConfigError(args.in_recording, "--in-recording", error.what());
    }
  } else {
    try {
      input = load_feature_input(args.calibration_file, args.in_features);
    } catch (const std::runtime_error& error) {  // an unreadable file: bad input, not a failure
      throw ConfigError(args.in_features.front(), "--in-features", error.what());
    }
  }
  if (cameras_with_frames(input).size() < 3 && args.criterion == "heldout")
    throw ConfigError(args.calibration_file, "cameras", "heldout needs frames of at least 3 posed cameras");
  if (!args.quiet) {
    session::log("tune: " + std::to_string(input.frames.size()) + " frames of " +
                 std::to_string(cameras_with_frames(input).size()) + " cameras (" +
                 std::to_string(input.bad_lines) + " malformed lines skipped), criterion " + args.criterion);
  }
  const Criterion criterion = make_criterion(effective, input, scene ? &*scene : nullptr);
  const SearchResult result = coordinate_search(
      start, search, criterion.cost, [&](const SearchSample& sample, const SearchSample& best) {
        if (!args.quiet)
          std::fprintf(stderr, "%s (best %.6g)\n", sample_line(sample, search.parameters).c_str(), best.cost);
      });

  std::ofstream out(args.out_config);
  if (!out) throw std::runtime_error(args.out_config + ": cannot write");
  out << "# estimator_node tune --criterion " << args.criterion << ": cost " << result.best_sample.cost
      << " after " << result.samples.size() << " evaluations\n"
      << session::estimator_config_to_yaml(result.best);
  if (!out.flush()) throw std::runtime_error(args.out_config + ": write failed");
  const std::string curve = args.out_curve.empty() ? args.out_config + ".csv" : args.out_curve;
  write_curve_csv(curve, result, search.parameters, criterion.extra_names);
  if (!args.plot.empty()) {
    write_curve_png(curve, args.plot, "estimator_node tune --criterion " + args.criterion, criterion.label,
                    scene && args.criterion == "heldout" ? "rmse_mm" : "");
  }
  session::log(sample_line(result.best_sample, search.parameters) + ": wrote " + args.out_config + ", " +
               curve + (args.plot.empty() ? "" : ", " + args.plot));
  return kExitOk;
}

}  // namespace

int run_tune(int argc, char** argv, const RecordingReader& read_recording) {
  CLI::App app{
      "estimator_node tune: searches process noise, measurement noise and gates over a recording "
      "(seed 003 A.3.2; docs/recording.md)",
      "estimator_node tune"};
  TuneArgs args;
  add_options(app, args);
  if (const auto exit_code = parse_command_line(app, argc, argv, [&] {
        if (args.in_features.empty() && args.in_recording.empty())
          throw CLI::ValidationError("--in-features", "give --in-features files or --in-recording");
      }))
    return *exit_code;
  try {
    return tune(args, read_recording);
  } catch (const ConfigError& error) {
    session::log(error.what());
    return kExitBadInput;
  } catch (const std::exception& error) {
    session::log(error.what());
    return kExitFailure;
  }
}

}  // namespace panoptes::tune
