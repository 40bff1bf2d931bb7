// SPDX-License-Identifier: Apache-2.0
// `panoptes_label angles`'s library (tools/label/src/angles_job.cpp): the real Gait2392 walk with
// the model from its static trial gives angles and poses CSV files of the right shape, and bad
// input is refused naming the option or file.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "../scratch_dir.h"
#include "../shared_data.h"
#include "panoptes/errors.h"
#include "panoptes/label_job/angles_job.h"
#include "panoptes/label_job/label_job.h"

namespace panoptes::label_job {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return panoptes::testing::process_scratch_dir("panoptes_label_angles") / name;
}

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The subject model of a static trial of ../shared/data/static with a set of deploy/markersets.
std::string subject_model(const std::string& static_trial, const std::string& set) {
  ModelCommandOptions model;
  model.static_trial = test::shared_data("static/" + static_trial).string();
  model.marker_set = (fs::path(PANOPTES_SOURCE_DIR) / "deploy" / "markersets" / (set + ".yaml")).string();
  model.out = scratch(set + ".yaml").string();
  run_model(model);
  return model.out;
}

AnglesCommandOptions gait2392_walk() {
  AnglesCommandOptions options;
  options.in = test::shared_data("static/gait2392_subject01_walk1.trc").string();
  options.subjects = subject_model("gait2392_subject01_static.trc", "gait2392");
  options.out = scratch("angles.csv").string();
  options.poses = scratch("poses.csv").string();
  return options;
}

std::size_t lines(const std::string& text) {
  std::size_t count = 0;
  for (const char c : text) count += c == '\n' ? 1 : 0;
  return count;
}

TEST(LabelAngles, WritesAnglesAndPosesOfTheWalk) {
  const AnglesCommandOptions options = gait2392_walk();
  const AnglesResult result = run_angles(options);
  EXPECT_EQ(result.frames.size(), 151U);
  EXPECT_EQ(result.model_markers_in_trial, 41U);
  const std::string angles = read(options.out);
  EXPECT_EQ(lines(angles), 152U);
  EXPECT_EQ(angles.rfind("frame,time_s,Pelvis-R.Thigh.flexion_deg,", 0), 0U);
  EXPECT_NE(angles.find(",R.Knee.flexion_deg,R.Knee.adduction_deg,R.Knee.internal_rotation_deg,"),
            std::string::npos);
  const std::string poses = read(options.poses);
  EXPECT_EQ(poses.rfind("frame,time_s,segment,x_m,y_m,z_m,qw,qx,qy,qz,rms_mm,markers_used,joint_centre\n", 0),
            0U);
  EXPECT_EQ(lines(poses), 1U + 151U * 9U);  // 9 segments with a pose (the arms have two markers, no joint)
  const std::string report = angles_report(result);
  EXPECT_NE(report.find("segment R.UpperArm: pose in 0/151 frames"), std::string::npos) << report;
  EXPECT_NE(report.find("\"posed_segments\":9"), std::string::npos) << report;
  // The defaults: gaps filled by pattern (walk1 has none), markers low-passed at 6 Hz.
  EXPECT_NE(report.find("markers: 0 samples gap-filled, low-pass 6.000 Hz (zero lag)"), std::string::npos)
      << report;
  EXPECT_NE(report.find("\"filled_samples\":0,\"lowpass_hz\":6.000}"), std::string::npos) << report;
}

TEST(LabelAngles, RefusesAFillMethodOrACutoffItCannotUse) {
  AnglesCommandOptions options = gait2392_walk();
  const auto error_of = [&] {
    try {
      run_angles(options);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  options.fill = "cubic";
  EXPECT_NE(error_of().find("--fill: expected pattern, relational, spline, linear or none, got 'cubic'"),
            std::string::npos);
  options.fill = "none";
  options.lowpass_hz = 30.0;  // walk1 is 60 Hz: the cutoff must be below 30
  EXPECT_NE(error_of().find("--lowpass-hz: low-pass cutoff 30"), std::string::npos) << error_of();
  options.lowpass_hz = 0.0;
  EXPECT_EQ(angles_report(run_angles(options)).find("low-pass"), std::string::npos);
}

TEST(LabelAngles, WarnsWhenTheAxesPutARightSegmentElsewhere) {
  AnglesCommandOptions options;
  options.in = (fs::path(PANOPTES_SOURCE_DIR) / "tests" / "data" / "walk_41markers_100hz.trc").string();
  options.subjects = subject_model("rajagopal_static_walk_1.trc", "rajagopal");
  options.out = scratch("rajagopal_angles.csv").string();
  // The Rajagopal static trial faces +z: the default +x puts the thighs on the midline.
  const std::string wrong = angles_report(run_angles(options));
  EXPECT_NE(wrong.find("warning: R.Thigh lies on the midline"), std::string::npos) << wrong;
  options.forward = "+z";
  const std::string right = angles_report(run_angles(options));
  EXPECT_EQ(right.find("warning"), std::string::npos) << right;
  EXPECT_NE(right.find("segment L.Shank: pose in 238/238 frames"), std::string::npos) << right;
}

TEST(LabelAngles, RefusesBadAxesATrialWithoutTheModelsMarkersAndAnUnwritableOutput) {
  AnglesCommandOptions options = gait2392_walk();
  EXPECT_THROW(parse_axis("+w", "--up"), InputError);
  EXPECT_EQ(parse_axis("-z", "--up"), -Eigen::Vector3d::UnitZ());
  options.forward = "-y";
  try {
    run_angles(options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("--up +y and --forward -y"), std::string::npos) << error.what();
  }
  options.forward = "+x";
  const fs::path other = scratch("other.trc");
  std::ofstream(other)
      << "PathFileType\t4\t(X/Y/Z)\tother.trc\n"
         "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
         "\n"
         "60\t60\t1\t1\tmm\t60\t1\t1\nFrame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n\n1\t0\t1\t2\t3\n";
  const AnglesCommandOptions good = options;
  options.in = other.string();
  try {
    run_angles(options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(other.string() + ": none of the markers"), std::string::npos)
        << error.what();
  }
  options = good;
  options.out = (scratch("no_such_dir") / "x" / "angles.csv").string();
  try {
    run_angles(options);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.file(), options.out);
  }
}

}  // namespace
}  // namespace panoptes::label_job
