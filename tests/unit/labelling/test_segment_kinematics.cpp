// SPDX-License-Identifier: Apache-2.0
// Segment poses and joint angles (docs/marker_sets.md, "Segment poses and joint angles") on the
// real Gait2392 walk: the computation on noisy markers with some hidden against the same
// computation on the file's markers, the knee's range and sign over the walk, and bad input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "labelling_test_support.h"
#include "panoptes/errors.h"
#include "panoptes/labelling/gap_fill.h"
#include "panoptes/labelling/lowpass.h"
#include "panoptes/labelling/segment_kinematics.h"
#include "panoptes/labelling_files/marker_set_file.h"
#include "panoptes/labelling_files/static_trial.h"

namespace panoptes::labelling {
namespace {

SubjectModel gait2392_model() {
  return build_subject_model(load_marker_set(test::marker_set_path("gait2392")),
                             load_marker_samples(test::gait2392_static()), "subject01");
}

std::size_t segment_index(const SegmentKinematics& kinematics, const std::string& name) {
  for (std::size_t s = 0; s < kinematics.segments.size(); ++s) {
    if (kinematics.segments[s].name == name) return s;
  }
  ADD_FAILURE() << "no segment " << name;
  return 0;
}

std::size_t joint_index(const SegmentKinematics& kinematics, const std::string& name) {
  for (std::size_t j = 0; j < kinematics.joints.size(); ++j) {
    if (kinematics.joints[j].name == name) return j;
  }
  ADD_FAILURE() << "no joint " << name;
  return 0;
}

std::vector<KinematicsFrame> trial_kinematics(const SegmentKinematics& kinematics, const SubjectModel& model,
                                              const MarkerSamples& samples) {
  std::vector<KinematicsFrame> frames;
  for (std::size_t f = 0; f < samples.frame_count(); ++f)
    frames.push_back(compute_kinematics(kinematics, model, segment_points(kinematics, model, samples, f)));
  return frames;
}

// The walk with Gaussian noise (sigma per axis) and each marker-frame hidden with probability `hide`.
MarkerSamples noisy(const MarkerSamples& truth, double sigma_m, double hide, unsigned seed) {
  MarkerSamples out = truth;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t i = 0; i < out.positions.size(); ++i) {
    out.positions[i] += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    if (uniform(rng) < hide) out.valid[i] = 0;
  }
  return out;
}

struct Rms {
  double squares = 0.0;
  std::size_t count = 0;
  void add(double value) {
    squares += value * value;
    ++count;
  }
  double value() const { return count == 0 ? 0.0 : std::sqrt(squares / static_cast<double>(count)); }
};

struct Comparison {
  Rms orientation;
  Rms knee;
  std::vector<Rms> per_segment;
  std::size_t joint_centre_poses = 0;
  std::size_t lost = 0;
};

// The walk's kinematics from noisy markers with some hidden, 5 seeds, against the file's markers.
// The pipeline before the kinematics: none (the defaults), or `panoptes_label angles`'s (gaps
// filled by pattern up to 0.3 s, then a zero-lag low-pass), applied alike to the noisy and, unless
// filter_reference is false, to the true markers ("the same computation on the true markers").
struct Preparation {
  bool fill = false;
  double lowpass_hz = 0.0;
  bool filter_reference = true;
};

Comparison compare_noisy(const SegmentKinematics& kinematics, const SubjectModel& model,
                         const MarkerSamples& truth, double sigma_m, double hide,
                         const Preparation& prepare = {}) {
  const auto prepared = [&](MarkerSamples samples) {
    if (prepare.fill) {
      std::vector<std::uint8_t> filled;
      fill_gaps(model, samples, filled, FillOptions{.method = FillMethod::kPattern, .max_gap_frames = 18});
    }
    if (prepare.lowpass_hz > 0.0) lowpass_filter(samples, prepare.lowpass_hz);
    return samples;
  };
  const auto reference =
      trial_kinematics(kinematics, model, prepare.filter_reference ? prepared(truth) : truth);
  Comparison out;
  out.per_segment.resize(kinematics.segments.size());
  for (const unsigned seed : {1U, 2U, 3U, 4U, 5U}) {
    const auto measured = trial_kinematics(kinematics, model, prepared(noisy(truth, sigma_m, hide, seed)));
    for (std::size_t f = 0; f < reference.size(); ++f) {
      for (std::size_t s = 0; s < kinematics.segments.size(); ++s) {
        const SegmentPose& a = reference[f].poses[s];
        const SegmentPose& b = measured[f].poses[s];
        if (a.valid && !b.valid) ++out.lost;
        if (!a.valid || !b.valid) continue;
        const double angle = rotation_angle_deg(a.T_world_anatomical.q, b.T_world_anatomical.q);
        out.orientation.add(angle);
        out.per_segment[s].add(angle);
        out.joint_centre_poses += b.used_joint_centre ? 1 : 0;
      }
      for (const char* name : {"R.Knee", "L.Knee"}) {
        const JointAngles& a = reference[f].angles[joint_index(kinematics, name)];
        const JointAngles& b = measured[f].angles[joint_index(kinematics, name)];
        if (a.valid && b.valid) out.knee.add(b.flexion_deg - a.flexion_deg);
      }
    }
  }
  std::printf(
      "%slow-pass %.0f Hz%s, noise %.2f mm per axis (%.2f mm 3-D RMS), %.0f %% of marker-frames hidden, 5 "
      "seeds: orientation "
      "RMS %.3f deg over %zu segment-frames (%zu posed from 2 markers + the joint centre, %zu lost), knee "
      "flexion RMS %.3f deg over %zu\n  per segment:",
      prepare.fill ? "pattern fill, " : "", prepare.lowpass_hz,
      prepare.filter_reference ? "" : " (reference unfiltered)", sigma_m * 1e3,
      sigma_m * 1e3 * std::sqrt(3.0), hide * 100, out.orientation.value(), out.orientation.count,
      out.joint_centre_poses, out.lost, out.knee.value(), out.knee.count);
  for (std::size_t s = 0; s < kinematics.segments.size(); ++s) {
    if (out.per_segment[s].count > 0)
      std::printf(" %s %.2f", kinematics.segments[s].name.c_str(), out.per_segment[s].value());
  }
  std::printf("\n");
  return out;
}

TEST(SegmentKinematics, NoisyWalkMatchesTheSameComputationOnTheTrueMarkers) {
  const SubjectModel model = gait2392_model();
  const SegmentKinematics kinematics = build_segment_kinematics(model);
  const MarkerSamples truth = load_marker_samples(test::gait2392_walk());
  KinematicsOptions with_centres;
  with_centres.joint_centres_in_fit = true;
  const SegmentKinematics constrained = build_segment_kinematics(model, with_centres);
  for (const double sigma : {0.001, 0.0005, 0.0003}) {
    for (const double hide : {0.02, 0.0}) {
      std::printf("with joint centres: ");
      compare_noisy(constrained, model, truth, sigma, hide);
    }
  }
  for (const double sigma : {0.001, 0.0005, 0.0003}) {
    std::printf("markers only, none hidden: ");
    compare_noisy(kinematics, model, truth, sigma, 0.0);
  }
  // The default (markers only), 1 mm 3-D RMS noise, 2 % of marker-frames hidden: regression bounds
  // at the measured 0.94 deg and 1.06 deg. The 0.5 deg and 1 deg are not met at this noise
  // (three markers 6-12 cm apart on the shanks; a segment fitted without one of its markers, which
  // are not rigid while walking).
  const Comparison c = compare_noisy(kinematics, model, truth, 0.001 / std::sqrt(3.0), 0.02);
  EXPECT_LE(c.orientation.value(), 1.0);
  EXPECT_LE(c.knee.value(), 1.15);
  EXPECT_GT(c.knee.count, 1300U);
  EXPECT_GT(c.joint_centre_poses, 0U);  // two markers and the joint centre when one is hidden
  // 0.3 mm per axis (0.52 mm 3-D RMS), none hidden: both met (measured 0.32 deg, 0.35 deg).
  const Comparison fine = compare_noisy(kinematics, model, truth, 0.0003, 0.0);
  EXPECT_LE(fine.orientation.value(), 0.5);
  EXPECT_LE(fine.knee.value(), 1.0);
}

// panoptes_label angles's pipeline (gaps filled by pattern, markers low-passed at 6 Hz without lag)
// at 1 mm 3-D RMS noise with 2 % of marker-frames hidden, against the same pipeline on the true
// markers: the 0.5 deg and 1 deg are met (measured 0.267 deg and 0.295 deg; the fill alone
// 0.619 deg and 0.674 deg; the 6 Hz filter alone 0.775 deg and 0.915 deg). Against the unfiltered
// true markers the filter's own smoothing of the walk shows (measured 0.684 deg, 0.786 deg).
TEST(SegmentKinematics, FilledAndLowPassedMarkersMeetTheAcceptanceAtOneMillimetre) {
  const SubjectModel model = gait2392_model();
  const SegmentKinematics kinematics = build_segment_kinematics(model);
  const MarkerSamples truth = load_marker_samples(test::gait2392_walk());
  const double sigma = 0.001 / std::sqrt(3.0);
  const Comparison c =
      compare_noisy(kinematics, model, truth, sigma, 0.02, {.fill = true, .lowpass_hz = 6.0});
  EXPECT_LE(c.orientation.value(), 0.5);
  EXPECT_LE(c.knee.value(), 1.0);
  EXPECT_GT(c.knee.count, 1450U);  // the filled markers pose the segments the hidden ones left
  const Comparison raw_reference = compare_noisy(
      kinematics, model, truth, sigma, 0.02, {.fill = true, .lowpass_hz = 6.0, .filter_reference = false});
  EXPECT_LE(raw_reference.orientation.value(), 0.8);
  const Comparison fill_only = compare_noisy(kinematics, model, truth, sigma, 0.02, {.fill = true});
  EXPECT_LT(c.orientation.value(), 0.6 * fill_only.orientation.value());
}

TEST(SegmentKinematics, KneeFlexesPositiveWithinThePhysiologicalRangeOfAWalk) {
  const SubjectModel model = gait2392_model();
  const SegmentKinematics kinematics = build_segment_kinematics(model);
  const auto frames = trial_kinematics(kinematics, model, load_marker_samples(test::gait2392_walk()));
  for (const char* name : {"R.Knee", "L.Knee", "R.Ankle", "L.Ankle"}) {
    const std::size_t j = joint_index(kinematics, name);
    double low = 1e9;
    double high = -1e9;
    std::size_t valid = 0;
    for (const auto& frame : frames) {
      if (!frame.angles[j].valid) continue;
      low = std::min(low, frame.angles[j].flexion_deg);
      high = std::max(high, frame.angles[j].flexion_deg);
      ++valid;
    }
    std::printf("%s flexion over the walk: %.1f .. %.1f deg (%zu frames)\n", name, low, high, valid);
    EXPECT_EQ(valid, frames.size()) << name;
    if (std::string(name).find("Knee") == std::string::npos) continue;
    EXPECT_TRUE(kinematics.joints[j].knee);
    EXPECT_GE(low, -8.0) << name;  // standing is ~4 deg (Y of the thigh is the vertical): no hyperextension
    EXPECT_LE(high, 75.0) << name;
    EXPECT_GE(high, 40.0) << name;  // swing flexes the knee 55-65 deg: the sign is right
  }
}

TEST(SegmentKinematics, TheStaticPoseIsNearTheNeutralPose) {
  const SubjectModel model = gait2392_model();
  const SegmentKinematics kinematics = build_segment_kinematics(model);
  const MarkerSamples samples = load_marker_samples(test::gait2392_static());
  const auto frame = compute_kinematics(kinematics, model, segment_points(kinematics, model, samples, 150));
  for (std::size_t j = 0; j < kinematics.joints.size(); ++j) {
    if (!frame.angles[j].valid) continue;
    const JointAngles& a = frame.angles[j];
    std::printf("static %s: flexion %.1f adduction %.1f internal rotation %.1f deg\n",
                kinematics.joints[j].name.c_str(), a.flexion_deg, a.adduction_deg, a.internal_rotation_deg);
    EXPECT_LT(std::abs(a.adduction_deg), 15.0) << kinematics.joints[j].name;
  }
  EXPECT_EQ(kinematics.segments[segment_index(kinematics, "R.Thigh")].side, 1);
  EXPECT_EQ(kinematics.segments[segment_index(kinematics, "L.Shank")].side, -1);
  EXPECT_EQ(kinematics.segments[segment_index(kinematics, "Pelvis")].side, 0);
}

TEST(SegmentKinematics, TooFewMarkersGiveNoPoseRatherThanAWrongOne) {
  const SubjectModel model = gait2392_model();
  const SegmentKinematics kinematics = build_segment_kinematics(model);
  const MarkerSamples walk = load_marker_samples(test::gait2392_walk());
  SegmentPoints points = segment_points(kinematics, model, walk, 40);
  const std::size_t thigh = segment_index(kinematics, "R.Thigh");
  const std::size_t shank = segment_index(kinematics, "R.Shank");
  // The thigh with two of three markers: Gait2392 has no hip centre, so no pose and no knee angle.
  for (std::size_t m = 0; m < points[thigh].size(); ++m) {
    if (model.segments[kinematics.segments[thigh].model_segment].markers[m].name == "R.Thigh.Front")
      points[thigh][m].reset();
  }
  // The shank with two markers has its knee centre from the thigh's pose: none now either.
  for (std::size_t m = 0; m < points[shank].size(); ++m) {
    if (model.segments[kinematics.segments[shank].model_segment].markers[m].name == "R.Shank.Rear")
      points[shank][m].reset();
  }
  auto frame = compute_kinematics(kinematics, model, points);
  EXPECT_FALSE(frame.poses[thigh].valid);
  EXPECT_FALSE(frame.poses[shank].valid);
  EXPECT_FALSE(frame.angles[joint_index(kinematics, "R.Knee")].valid);
  EXPECT_TRUE(frame.poses[segment_index(kinematics, "L.Thigh")].valid);
  // Collinear markers: no pose.
  const std::size_t pelvis = segment_index(kinematics, "Pelvis");
  for (std::size_t m = 0; m < points[pelvis].size(); ++m)
    points[pelvis][m] = Eigen::Vector3d(0.1 * m, 0.0, 0.0);
  frame = compute_kinematics(kinematics, model, points);
  EXPECT_FALSE(frame.poses[pelvis].valid);
}

TEST(SegmentKinematics, ACycleOrAnUnknownParentIsRefused) {
  SubjectModel model = gait2392_model();
  SubjectModel unknown = model;
  unknown.segments[1].parent = "Nowhere";
  EXPECT_NE(
      test::error_of<InputError>([&] { build_segment_kinematics(unknown); }).find("unknown parent Nowhere"),
      std::string::npos);
  SubjectModel cycle = model;
  cycle.segments[0].parent = cycle.segments.back().name;
  EXPECT_NE(test::error_of<InputError>([&] { build_segment_kinematics(cycle); }).find("do not form a tree"),
            std::string::npos);
  KinematicsOptions skew;
  skew.forward = Eigen::Vector3d(1.0, 1.0, 0.0);
  EXPECT_NE(test::error_of<InputError>([&] { build_segment_kinematics(model, skew); }).find("orthogonal"),
            std::string::npos);
}

TEST(SegmentKinematics, CardanZxyInvertsItsRotation) {
  for (const Eigen::Vector3d& angles : {Eigen::Vector3d(0.3, -0.2, 0.7), Eigen::Vector3d(-1.2, 0.9, -2.5)}) {
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(angles.x(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(angles.y(), Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(angles.z(), Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    EXPECT_LT((cardan_zxy(R) - angles).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace panoptes::labelling
