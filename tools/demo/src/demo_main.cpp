// SPDX-License-Identifier: Apache-2.0
// panoptes_demo: the main job. Starts one camera_node per simulated camera and one estimator_node
// over Fast DDS (loopback profile), watches the tracks as an application would, and ends with the
// accuracy against ground truth. The work is panoptes_demo_run's (panoptes/demo_run/demo_run.h);
// this is its command line.
#include <filesystem>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>

#include "panoptes/cli.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/demo_run/demo_run.h"
#include "panoptes/process.h"

namespace {

namespace fs = std::filesystem;

fs::path executable_dir() {
  std::error_code error;
  return fs::read_symlink("/proc/self/exe", error).parent_path();
}

int run(int argc, char** argv) {
  panoptes::demo_run::DemoOptions options;
  options.bin_dir = executable_dir();
  options.scene_file = (options.bin_dir / "../../deploy/scenes/demo.yaml").lexically_normal().string();
  if (!fs::exists(options.scene_file))
    options.scene_file = std::string(PANOPTES_SOURCE_DIR) + "/deploy/scenes/demo.yaml";
  CLI::App app{"panoptes_demo: simulated multi-camera tracking over DDS, with accuracy against ground truth",
               "panoptes_demo"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  panoptes::dds::add_domain_option(app);
  app.add_option("--scene", options.scene_file, "simulator scene");
  app.add_option("--duration", options.duration_s, "seconds of tracking")->check(CLI::Range(2.0, 3600.0));
  app.add_option("--summary-json", options.summary_json, "write the accuracy summary as JSON to this file");
  app.add_option("--dds-profile", options.dds_profile, "Fast DDS XML profile")
      ->default_str("deploy/dds/loopback.xml");
  app.add_option("--log-dir", options.log_dir, "keep process logs and recorded tracks here")
      ->default_str("a temporary folder");
  app.add_option(
         "--frames", options.frames,
         "the estimator's rt/panoptes/frames: auto (fixed-rate live), per-camera or fixed (docs/frames.md)")
      ->check(CLI::IsMember({"auto", "per-camera", "fixed"}));
  app.add_flag(
      "--check", options.check,
      "exit 1 unless every marker meets the demo's targets (RMSE < 2 mm, >= 95% tracked, 0 ID switches)");
  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  // A bad $PANOPTES_DOMAIN or DDS profile is a usage error (exit 2) here, not an early exit of
  // every child.
  panoptes::dds::resolve_domain();
  panoptes::dds::resolve_profile_file(options.dds_profile);
  panoptes::install_stop_handlers();
  return panoptes::demo_run::run_demo(options);
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_demo", [&] { return run(argc, argv); });
}
