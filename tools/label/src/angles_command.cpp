// SPDX-License-Identifier: Apache-2.0
#include "angles_command.h"

#include <cstdio>
#include <string>

#include "panoptes/process.h"

namespace panoptes::label_job {

namespace {

CLI::Validator lab_axis() {
  return CLI::Validator(
      [](std::string& text) {
        try {
          parse_axis(text, "");
        } catch (const std::exception& error) {
          return std::string(error.what());
        }
        return std::string();
      },
      "AXIS");
}

}  // namespace

CLI::App* add_angles_command(CLI::App& app, AnglesCommandOptions& options) {
  CLI::App* angles = app.add_subcommand(
      "angles", "segment poses and joint angles per frame from a labelled trial and a subject model");
  angles->add_option("--in", options.in, "labelled trial: a .trc or .c3d file with the model's marker names")
      ->required()
      ->check(CLI::ExistingFile);
  angles->add_option("--subjects", options.subjects, "subject model YAML (panoptes_label model)")
      ->required()
      ->check(CLI::ExistingFile);
  angles
      ->add_option("--out", options.out,
                   "joint angles CSV to write: per joint flexion, adduction, internal rotation in degrees")
      ->required();
  angles->add_option("--poses", options.poses,
                     "also write the segment poses CSV (anatomical frames: position, quaternion, fit RMS)");
  angles->add_option("--up", options.up, "the static trial's vertical axis (+x, -x, +y, -y, +z, -z)")
      ->capture_default_str()
      ->check(lab_axis());
  angles->add_option("--forward", options.forward, "the direction the subject faces in the static trial")
      ->capture_default_str()
      ->check(lab_axis());
  angles->add_flag(
      "--joint-centres", options.joint_centres,
      "fit each segment to its markers and its proximal joint centre placed by the parent's pose "
      "(default: its markers only; the joint centre only when two markers are seen)");
  angles
      ->add_option("--fill", options.fill,
                   "gaps filled first: pattern, relational, spline, linear or none (as run)")
      ->capture_default_str();
  angles->add_option("--max-gap-s", options.max_gap_s, "longest gap filled, seconds")->capture_default_str();
  angles
      ->add_option(
          "--lowpass-hz", options.lowpass_hz,
          "then the markers low-passed without lag (Butterworth, forwards and backwards); 0: unfiltered")
      ->capture_default_str();
  return angles;
}

int run_angles_command(const AnglesCommandOptions& options) {
  const auto result = run_angles(options);
  std::printf("%s", angles_report(result).c_str());
  const std::string poses = options.poses.empty() ? "" : " and " + options.poses;
  std::printf("wrote %s%s\n", options.out.c_str(), poses.c_str());
  return kExitOk;
}

}  // namespace panoptes::label_job
