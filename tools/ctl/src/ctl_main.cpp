// SPDX-License-Identifier: Apache-2.0
// panoptes_ctl: talk to running camera nodes over DDS (docs/camera_node.md).
//   panoptes_ctl command <camera id | *> <command> [arguments...]
//   panoptes_ctl script <file>                                    commands and sleeps from a file
//   panoptes_ctl status [--camera <id>] [--count <n>]            one JSON line per CameraStatus
//   panoptes_ctl preview <camera id> --out <file.pgm> [--width <px>]
//   panoptes_ctl predict <camera id> --window <x> <y> <half w> <half h> [--duration <s>] [--rate <Hz>]
//   panoptes_ctl body create --name <n> --tracks <id,id,id...> | --near <x,y,z> [--radius <m>] --bodies
//   <file>
// The work is panoptes_ctl_actions's (panoptes/ctl_actions/ctl_actions.h); this is its command line.
#include <cstdint>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include "panoptes/cli.h"
#include "panoptes/ctl_actions/ctl_actions.h"
#include "panoptes/dds/domain_option.h"
#include "panoptes/dds/security_options.h"
#include "panoptes/process.h"

namespace {

using panoptes::ctl::CtlOptions;

// `body create`: --name, --tracks or --near/--radius, --pivot, --bodies, --frames.
void add_body_create_options(CLI::App& create, CtlOptions& options) {
  auto& request = options.body;
  create.add_option("--name", request.name, "the new body's name (unique in the bodies file)")->required();
  auto* tracks = create.add_option("--tracks", request.tracks, "track ids, at least 3 (e.g. 3,5,7)")
                     ->delimiter(',')
                     ->expected(1, -1);
  auto* near =
      create
          .add_option_function<std::vector<double>>(
              "--near",
              [&request](const std::vector<double>& p) { request.near = Eigen::Vector3d(p[0], p[1], p[2]); },
              "x,y,z (m, world z up): every confirmed track within --radius of this point")
          ->delimiter(',')
          ->expected(3);
  tracks->excludes(near);
  near->excludes(tracks);
  create.add_option("--radius", request.radius_m, "with --near: the radius, m")->check(CLI::PositiveNumber);
  create.add_option_function<std::int64_t>(
      "--pivot", [&request](std::int64_t id) { request.pivot = id; },
      "the body origin at this track (one of the body's); default: the markers' centroid");
  create.add_option("--bodies", request.bodies_file, "bodies file to append to (created when missing)")
      ->required();
  create.add_option("--frames", options.body_frames, "frames of positions to average")
      ->check(CLI::Range(1, 10000));
  create.final_callback([tracks, near] {
    if (tracks->count() == 0 && near->count() == 0)
      throw CLI::ValidationError("--tracks", "give --tracks or --near");
  });
}

int run(int argc, char** argv) {
  CtlOptions options;
  CLI::App app{"panoptes_ctl: send commands to camera nodes and watch their status (Panoptes)",
               "panoptes_ctl"};
  app.require_subcommand(1);
  app.fallthrough();                                // --timeout and --dds-profile may follow the subcommand
  app.option_defaults()->always_capture_default();  // --help shows every default
  panoptes::dds::add_domain_option(app);
  app.add_option("--dds-profile", options.dds_profile, "Fast DDS XML profile")
      ->default_str("$PANOPTES_DDS_PROFILE or deploy/dds/loopback.xml");
  panoptes::dds::add_security_options(app, options.security);
  app.add_option("--timeout", options.timeout_s, "seconds to wait for nodes and replies")
      ->check(CLI::PositiveNumber);

  auto* command = app.add_subcommand(
      "command",
      "send a command: " + std::string("set_threshold <T_a> [<T_r>] | set_exposure <us> | set_gain <dB> "
                                       "| set_frame_rate <Hz> | capture_background [<frames>] | "
                                       "clear_background | add_mask rect <x> <y> <w> <h> | add_mask poly "
                                       "<x1> <y1> ... | clear_masks | preview [<width>] | restart"));
  command->add_option("target", options.target, "camera id, or * for every camera")->required();
  command->add_option("command", options.command, "command name")->required();
  command->add_option("arguments", options.arguments, "command arguments");

  auto* script = app.add_subcommand("script",
                                    "send the commands of a file: lines '<target> <command> [args]' "
                                    "or 'sleep <s>'");
  script
      ->add_option("file", options.out,
                   "script file: '<target> <command> [args]', 'sleep <s>', 'wait_nodes <n> <s>'")
      ->required();

  auto* status = app.add_subcommand("status", "print CameraStatus messages as JSON lines");
  status->add_option("--camera", options.camera, "only this camera")->default_str("every camera");
  status->add_option("--count", options.count, "messages to print before exiting")
      ->check(CLI::PositiveNumber);

  auto* preview = app.add_subcommand("preview", "request a downscaled image and save it as PGM");
  preview->add_option("camera", options.camera, "camera id")->required();
  preview->add_option("--out", options.out, "output .pgm file")->required();
  preview->add_option("--width", options.width, "maximum preview width")->check(CLI::Range(16, 4096));

  auto* predict = app.add_subcommand("predict", "publish a predicted search window for a camera (testing)");
  predict->add_option("camera", options.camera, "camera id")->required();
  predict->add_option("--window", options.window, "x y half_width half_height (px)")->expected(4)->required();
  predict->add_option("--duration", options.duration_s, "seconds to publish")->check(CLI::PositiveNumber);
  predict->add_option("--rate", options.rate_hz, "messages per second")->check(CLI::PositiveNumber);

  auto* body = app.add_subcommand("body", "rigid bodies from markers in the volume (docs/bodies.md)");
  body->require_subcommand(1);
  auto* create = body->add_subcommand(
      "create",
      "make a body from live tracks (by id, or within a radius of a point) and append it to the "
      "bodies file; an estimator running with --bodies FILE reloads it");
  add_body_create_options(*create, options);

  if (const auto exit_code = panoptes::parse_command_line(app, argc, argv)) return *exit_code;
  panoptes::install_stop_handlers();
  using panoptes::ctl::Action;
  const Action action = *command   ? Action::kCommand
                        : *script  ? Action::kScript
                        : *status  ? Action::kStatus
                        : *preview ? Action::kPreview
                        : *body    ? Action::kBodyCreate
                                   : Action::kPredict;
  return panoptes::ctl::run_action(action, options);
}

}  // namespace

int main(int argc, char** argv) {
  return panoptes::run_program("panoptes_ctl", [&] { return run(argc, argv); });
}
