// SPDX-License-Identifier: Apache-2.0
// Monocular 7-LED markers (seed 004; docs/monocular_markers.md): identification, pose with the
// pointer LED against OpenCV's IPPE on the coplanar LEDs (§4.4), accuracy, several markers,
// rejection of partial / false patterns, bad input and self-calibration (§3). Seeded.
#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "led_marker_fixtures.h"
#include "panoptes/calibration.h"
#include "panoptes/calibration_file.h"
#include "panoptes/estimator/led_marker.h"
#include "panoptes/jsonl.h"
#include "panoptes/records.h"

namespace panoptes::estimator {
int run_calibrate_marker(int argc, char** argv);  // estimator_node/calib_cli/src/calibrate_marker_cli.h
}

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using panoptes::RigidTransform;
namespace est = panoptes::estimator;

using panoptes::led_marker_fixtures::kFocal;
using panoptes::led_marker_fixtures::paper_leds;
constexpr double kHalfWidth = 1024.0;
constexpr double kDeg = M_PI / 180.0;

double rotation_error_deg(const RigidTransform& a, const RigidTransform& b) {
  return a.q.angularDistance(b.q) / kDeg;
}

// Projects the model; nullopt if an LED is outside the image or seen at more than 80 degrees from
// its normal (SMD LEDs, §2.1: "perceptible from large viewing angles up to nearly pi/2").
std::optional<est::LedPoints> project(const est::LedMarkerModel& model, const RigidTransform& T_cam_marker,
                                      double noise_px, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, noise_px / kFocal);
  const Vector3d front =
      T_cam_marker.rotation() * (model.T_model_plane().rotation() * Vector3d(0, 0, -model.handedness()));
  est::LedPoints m;
  for (int i = 0; i < 7; ++i) {
    const Vector3d q = T_cam_marker.apply(model.leds()[i]);
    if (q.z() <= 0.05) return std::nullopt;
    if (front.dot(-q.normalized()) < std::cos(80 * kDeg)) return std::nullopt;
    m[i] = q.head<2>() / q.z();
    if (std::abs(m[i].x()) * kFocal > kHalfWidth - 2 || std::abs(m[i].y()) * kFocal > kHalfWidth - 2)
      return std::nullopt;
    m[i] += Vector2d(noise(rng), noise(rng));
  }
  return m;
}

const auto pose = panoptes::led_marker_fixtures::marker_pose;

// The §4.4 sequence: 2290 frames, marker from 0.5 m to 7.5 m, lateral sway, full in-plane roll,
// tilt 20..50 degrees about a rotating axis (20..76 degrees in the first quarter, where the very
// oblique L42 views occur).
RigidTransform sequence_pose(int k, int n) {
  const double s = double(k) / (n - 1);
  const double z = 0.5 + 7.0 * s;
  const double tilt_max = (s < 0.25 ? 76.0 : 50.0) * kDeg;
  const double tilt = 20 * kDeg + (tilt_max - 20 * kDeg) * 0.5 * (1 - std::cos(2 * M_PI * 13 * s));
  return pose(0.12 * z * std::sin(2 * M_PI * 3 * s), 0.08 * z * std::cos(2 * M_PI * 2 * s), z, tilt,
              2 * M_PI * 11 * s, 2 * M_PI * 7 * s);
}

struct Shuffled {
  std::vector<Vector2d> points;
  std::array<int, 7> where{};  // where[i]: index of m_i in points
};
Shuffled shuffle(const est::LedPoints& m, std::mt19937_64& rng) {
  Shuffled s;
  std::vector<int> order(7);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  for (int j = 0; j < 7; ++j) s.points.push_back(m[order[j]]), s.where[order[j]] = j;
  return s;
}

std::optional<RigidTransform> ippe(const est::LedMarkerModel& model, const est::LedPoints& m) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (int i = 0; i < 6; ++i) {
    const Vector3d& p = model.plane_leds()[i];
    object.emplace_back(p.x(), p.y(), 0.0);
    image.emplace_back(m[i].x(), m[i].y());
  }
  cv::Mat rvec, tvec;
  if (!cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                    cv::SOLVEPNP_IPPE))
    return std::nullopt;
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Re(r, c) = R.at<double>(r, c);
  RigidTransform T_cam_plane;
  T_cam_plane.q = Eigen::Quaterniond(Re);
  T_cam_plane.t = Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  return T_cam_plane * model.T_model_plane().inverse();
}

TEST(LedMarkerModel, PaperLayoutAndValidation) {
  const auto model = est::LedMarkerModel::from_points("paper", paper_leds());
  EXPECT_NEAR(model.cross_ratio(), 3.99, 0.02);  // §4.1: CR ~ 3.99
  EXPECT_NEAR(model.d03(), 0.1142, 1e-12);
  EXPECT_EQ(model.handedness(), 1);

  auto expect_error = [](const std::array<Vector3d, 7>& leds, const std::string& what) {
    std::string error;
    EXPECT_FALSE(est::LedMarkerModel::create("bad", leds, &error).has_value()) << what;
    EXPECT_NE(error.find(what), std::string::npos) << "error: " << error;
    EXPECT_THROW(est::LedMarkerModel::from_points("bad", leds), std::invalid_argument);
  };
  auto leds = paper_leds();
  leds[1].y() = 0.01;
  expect_error(leds, "collinear");
  leds = paper_leds();
  leds[4].z() = 0.01;
  expect_error(leds, "coplanar");
  leds = paper_leds();
  leds[6].z() = 0.001;
  expect_error(leds, "elevated");
  leds = paper_leds();
  leds[4].y() = 0.02;
  expect_error(leds, "opposite sides");
  leds = paper_leds();
  std::swap(leds[1], leds[2]);
  expect_error(leds, "order");

  // Any rigid frame is accepted: a body frame rotated and shifted; the mirrored layout flips the
  // handedness.
  panoptes::BodyDefinition body;
  body.name = "wand";
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  for (const auto& p : paper_leds()) body.markers.push_back(q * p + Vector3d(0.1, -0.2, 0.3));
  const auto from_body = est::LedMarkerModel::from_body(body);
  EXPECT_NEAR(from_body.cross_ratio(), model.cross_ratio(), 1e-9);
  body.markers.pop_back();
  EXPECT_THROW(est::LedMarkerModel::from_body(body), std::invalid_argument);
  leds = paper_leds();
  leds[6].z() = -leds[6].z();
  EXPECT_EQ(est::LedMarkerModel::from_points("mirror", leds).handedness(), -1);
}

// Seed 004 §4.4: pose flips over a 2290-frame sequence from 0.5 m to 7.5 m, 0.1 px centroid noise.
// A flip is the wrong planar minimum: a rotation error above 15 degrees. The tilt from the line of
// sight stays above 12 degrees, so the wrong minimum is >= 24 degrees off while the right one
// stays within a few degrees (asserted). Also every LED identified, all three cases seen.
TEST(LedMarkerPose, Seed004PoseFlipsAndIdentification) {
  const auto model = est::LedMarkerModel::from_points("paper", paper_leds());
  const est::LedMarkerDetector detector({model});
  std::mt19937_64 rng(4);
  constexpr int kFrames = 2290;
  constexpr double kFlipDeg = 15.0;
  int visible = 0, detected = 0, wrong = 0;
  int flips_ours = 0, flips_ippe = 0, flips_m1 = 0, flips_m2 = 0, flips_m3 = 0;
  double max_err_ours = 0, far_err_sum = 0;
  int far_count = 0;
  std::map<est::LedCase, int> cases;
  for (int k = 0; k < kFrames; ++k) {
    const RigidTransform truth = sequence_pose(k, kFrames);
    const auto m = project(model, truth, 0.1, rng);
    if (!m) continue;
    ++visible;
    const Shuffled s = shuffle(*m, rng);
    const auto detections = detector.detect(s.points);
    if (detections.size() == 1) {
      ++detected;
      const auto& d = detections[0];
      if (d.blob != s.where) {
        ++wrong;
      } else {
        ++cases[d.led_case];
        const double err = rotation_error_deg(d.T_cam_marker, truth);
        max_err_ours = std::max(max_err_ours, err);
        flips_ours += err > kFlipDeg;
        if (truth.t.z() > 6.5) far_err_sum += err, ++far_count;
      }
    }
    const auto T_ippe = ippe(model, *m);
    flips_ippe += !T_ippe || rotation_error_deg(*T_ippe, truth) > kFlipDeg;
    auto method = [&](est::LedPoseMethod mth) {
      const auto p = est::estimate_led_marker_pose(model, *m, mth);
      return !p || rotation_error_deg(p->T_cam_marker, truth) > kFlipDeg;
    };
    flips_m1 += method(est::LedPoseMethod::kCoplanar);
    flips_m2 += method(est::LedPoseMethod::kCoplanarBestOfTwo);
    flips_m3 += method(est::LedPoseMethod::kAllSeven);
  }
  std::printf(
      "[seed004 4.4] frames %d visible %d detected %d misidentified %d | cases L5 %d L41 %d L42 %d\n"
      "[seed004 4.4] pose flips: ours %d, OpenCV IPPE (6 coplanar) %d, method1 %d, method2 %d, method3 %d\n"
      "[seed004 4.4] ours: max rotation error %.2f deg, mean beyond 6.5 m %.2f deg\n",
      kFrames, visible, detected, wrong, cases[est::LedCase::kL5], cases[est::LedCase::kL41],
      cases[est::LedCase::kL42], flips_ours, flips_ippe, flips_m1, flips_m2, flips_m3, max_err_ours,
      far_count ? far_err_sum / far_count : 0.0);
  EXPECT_GT(visible, 2000);
  EXPECT_EQ(detected, visible);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(cases[est::LedCase::kL5], 0);
  EXPECT_GT(cases[est::LedCase::kL41], 0);
  EXPECT_GT(cases[est::LedCase::kL42], 0);
  EXPECT_EQ(flips_ours, 0);
  EXPECT_LT(max_err_ours, kFlipDeg);
  EXPECT_GE(flips_ippe, 1);
}

// Translation accuracy at 2 m with 0.05 px centroid noise. Seed 004 §4.3 holds the marker parallel
// to the image plane and averages 500 measurements per position (~1 mm at 2 m); we report that
// protocol and the single-frame errors, parallel and at random tilts of 20-50 degrees.
TEST(LedMarkerPose, TranslationAccuracyAt2m) {
  const auto model = est::LedMarkerModel::from_points("paper", paper_leds());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  struct Stats {
    double sum = 0, sum_sq = 0, max = 0, depth_sq = 0;
    Vector3d mean_t = Vector3d::Zero();
    int n = 0;
  };
  auto run = [&](bool parallel) {
    Stats st;
    for (int trial = 0; trial < 1000; ++trial) {
      const RigidTransform truth =
          parallel ? pose(0.05, -0.03, 2.0, 0.0, 0.0, 2 * M_PI * u(rng))
                   : pose(0.2 * (u(rng) - 0.5), 0.2 * (u(rng) - 0.5), 2.0, (20 + 30 * u(rng)) * kDeg,
                          2 * M_PI * u(rng), 2 * M_PI * u(rng));
      const auto m = project(model, truth, 0.05, rng);
      if (!m) continue;
      const auto p = est::estimate_led_marker_pose(model, *m);
      if (!p) continue;
      const Vector3d d = p->T_cam_marker.t - truth.t;
      st.sum += d.norm(), st.sum_sq += d.squaredNorm(), st.max = std::max(st.max, d.norm());
      st.depth_sq += d.z() * d.z();
      if (parallel) st.mean_t += p->T_cam_marker.t - truth.t;  // same origin up to the roll
      ++st.n;
    }
    return st;
  };
  const Stats par = run(true), tilt = run(false);
  // Cramer-Rao bound of the depth for the parallel pose: (J^T J)^-1 sigma^2 with the numeric
  // Jacobian of the seven projections w.r.t. (rotation increment, translation).
  Eigen::Matrix<double, 14, 6> J;
  const RigidTransform T0 = pose(0.05, -0.03, 2.0, 0.0, 0.0, 0.0);
  auto proj = [&](const RigidTransform& T) {
    Eigen::Matrix<double, 14, 1> r;
    for (int i = 0; i < 7; ++i) {
      const Vector3d q = T.apply(model.leds()[i]);
      r.segment<2>(2 * static_cast<Eigen::Index>(i)) = q.head<2>() / q.z();
    }
    return r;
  };
  for (int k = 0; k < 6; ++k) {
    RigidTransform T = T0;
    if (k < 3)
      T.q = Eigen::Quaterniond(Eigen::AngleAxisd(1e-6, Vector3d::Unit(k))) * T.q;
    else
      T.t(k - 3) += 1e-6;
    J.col(k) = (proj(T) - proj(T0)) / 1e-6;
  }
  const double crlb_depth = std::sqrt((J.transpose() * J).inverse()(5, 5)) * 0.05 / kFocal;
  std::printf("[accuracy 2 m, 0.05 px] parallel: Cramer-Rao bound of the single-frame depth error %.3f mm\n",
              crlb_depth * 1e3);
  const double par_rms = std::sqrt(par.sum_sq / par.n), tilt_rms = std::sqrt(tilt.sum_sq / tilt.n);
  const double mean_error = (par.mean_t / par.n).norm();
  std::printf(
      "[accuracy 2 m, 0.05 px] parallel (seed 004 4.3): error of the mean of %d poses %.3f mm; single "
      "frame mean %.3f mm, RMS %.3f mm (depth RMS %.3f mm), max %.3f mm\n",
      par.n, mean_error * 1e3, par.sum / par.n * 1e3, par_rms * 1e3, std::sqrt(par.depth_sq / par.n) * 1e3,
      par.max * 1e3);
  std::printf(
      "[accuracy 2 m, 0.05 px] tilted 20-50 deg: %d poses, single frame mean %.3f mm, RMS %.3f mm (depth "
      "RMS %.3f mm), max %.3f mm\n",
      tilt.n, tilt.sum / tilt.n * 1e3, tilt_rms * 1e3, std::sqrt(tilt.depth_sq / tilt.n) * 1e3,
      tilt.max * 1e3);
  EXPECT_EQ(par.n, 1000);
  EXPECT_GT(tilt.n, 900);
  EXPECT_LE(mean_error, 1e-3);
  EXPECT_LE(par_rms, 2.5e-3);
  EXPECT_LE(tilt_rms, 2.5e-3);
}

// Three markers with different cross-ratios in one frame: separated by k-means and identified.
TEST(LedMarkerDetector, MultipleMarkersByCrossRatio) {
  const std::vector<est::LedMarkerModel> models = {
      est::LedMarkerModel::from_points("a", paper_leds()),                 // CR 3.99
      est::LedMarkerModel::from_points("b", paper_leds(0.0720, 0.0320)),   // CR 4.38
      est::LedMarkerModel::from_points("c", paper_leds(0.0800, 0.0450))};  // CR 3.60
  std::printf("[multi] cross-ratios %.3f %.3f %.3f\n", models[0].cross_ratio(), models[1].cross_ratio(),
              models[2].cross_ratio());
  const est::LedMarkerDetector detector(models);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  int frames = 0, found = 0, wrong = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double z = 1.0 + 3.0 * u(rng);
    std::vector<Vector2d> points;
    std::vector<std::array<int, 7>> where;
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) {
      const RigidTransform truth = pose((k - 1) * 0.3 * z, 0.1 * z * (u(rng) - 0.5), z,
                                        (15 + 40 * u(rng)) * kDeg, 2 * M_PI * u(rng), 2 * M_PI * u(rng));
      const auto m = project(models[k], truth, 0.1, rng);
      if (!m) {
        ok = false;
        break;
      }
      std::array<int, 7> w{};
      for (int i = 0; i < 7; ++i) w[i] = int(points.size()), points.push_back((*m)[i]);
      where.push_back(w);
    }
    if (!ok) continue;
    // Shuffle all 21 points.
    std::vector<int> order(points.size());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<int> position(points.size());
    std::vector<Vector2d> shuffled(points.size());
    for (std::size_t j = 0; j < order.size(); ++j)
      shuffled[j] = points[order[j]], position[order[j]] = int(j);
    ++frames;
    const auto detections = detector.detect(shuffled);
    for (const auto& d : detections) {
      std::array<int, 7> expected{};
      for (int i = 0; i < 7; ++i) expected[i] = position[where[d.model][i]];
      if (d.blob == expected)
        ++found;
      else
        ++wrong;
    }
  }
  std::printf("[multi] %d frames x 3 markers: %d identified, %d wrong\n", frames, found, wrong);
  EXPECT_GT(frames, 200);
  EXPECT_EQ(found, 3 * frames);
  EXPECT_EQ(wrong, 0);
}

// False blobs, a hidden LED, random points: rejected, never misidentified.
TEST(LedMarkerDetector, RejectsPartialAndFalsePatterns) {
  const auto model = est::LedMarkerModel::from_points("paper", paper_leds());
  const est::LedMarkerDetector detector({model});
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(0, 1);
  int hidden_detected = 0, wrong = 0, complete_found = 0, complete_total = 0, random_detected = 0;
  int stray_found = 0, stray_total = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double z = 1.0 + 2.0 * u(rng);
    const RigidTransform truth_a =
        pose(-0.25 * z, 0, z, (20 + 30 * u(rng)) * kDeg, 2 * M_PI * u(rng), 2 * M_PI * u(rng));
    const RigidTransform truth_b =
        pose(0.25 * z, 0, z, (20 + 30 * u(rng)) * kDeg, 2 * M_PI * u(rng), 2 * M_PI * u(rng));
    const auto a = project(model, truth_a, 0.1, rng), b = project(model, truth_b, 0.1, rng);
    if (!a || !b) continue;
    // One marker with a hidden LED alone: nothing.
    std::vector<Vector2d> partial(b->begin(), b->end());
    partial.erase(partial.begin() + trial % 7);
    hidden_detected += !detector.detect(partial).empty();
    // A complete marker and one with a hidden LED (13 points): only the complete one.
    std::vector<Vector2d> both(a->begin(), a->end());
    both.insert(both.end(), partial.begin(), partial.end());
    ++complete_total;
    for (const auto& d : detector.detect(both)) {
      bool right = true;
      for (int i = 0; i < 7; ++i) right &= d.blob[i] == i;
      right ? ++complete_found : ++wrong;
    }
    // A complete marker and a stray blob (reflection) somewhere in the image.
    std::vector<Vector2d> stray(a->begin(), a->end());
    stray.emplace_back(0.6 * (u(rng) - 0.5), 0.6 * (u(rng) - 0.5));
    ++stray_total;
    for (const auto& d : detector.detect(stray)) {
      bool right = true;
      for (int i = 0; i < 7; ++i) right &= d.blob[i] == i;
      right ? ++stray_found : ++wrong;
    }
    // Random points.
    std::vector<Vector2d> random;
    for (int i = 0; i < 7 + trial % 15; ++i) random.emplace_back(0.2 * (u(rng) - 0.5), 0.2 * (u(rng) - 0.5));
    random_detected += int(detector.detect(random).size());
  }
  std::printf(
      "[reject] hidden LED detected %d, complete+partial: %d/%d found, complete+stray: %d/%d found, "
      "random detected %d, misidentified %d\n",
      hidden_detected, complete_found, complete_total, stray_found, stray_total, random_detected, wrong);
  EXPECT_EQ(hidden_detected, 0);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(random_detected, 0);
  EXPECT_GT(complete_found, complete_total * 9 / 10);  // the k + 1 retry
}

TEST(LedMarkerDetector, BadInputGivesNoDetection) {
  const auto model = est::LedMarkerModel::from_points("paper", paper_leds());
  const est::LedMarkerDetector detector({model});
  std::mt19937_64 rng(3);
  const auto m = *project(model, pose(0, 0, 1.5, 30 * kDeg, 0.3, 0.2), 0.0, rng);
  std::vector<Vector2d> points(m.begin(), m.end());
  ASSERT_EQ(detector.detect(points).size(), 1u);
  // NaN / inf points.
  auto with_nan = points;
  with_nan[2].x() = std::nan("");
  EXPECT_TRUE(detector.detect(with_nan).empty());
  auto with_inf = points;
  with_inf[5].y() = INFINITY;
  EXPECT_TRUE(detector.detect(with_inf).empty());
  est::LedPoints nan_points = m;
  nan_points[0].x() = std::nan("");
  EXPECT_FALSE(est::identify_led_pattern(nan_points).has_value());
  EXPECT_FALSE(est::estimate_led_marker_pose(model, nan_points).has_value());
  // Fewer than seven.
  EXPECT_TRUE(detector.detect({points.begin(), points.begin() + 6}).empty());
  EXPECT_TRUE(detector.detect({}).empty());
  // Degenerate: all collinear, all equal.
  std::vector<Vector2d> line, same(7, Vector2d(0.1, 0.1));
  for (int i = 0; i < 7; ++i) line.emplace_back(0.01 * i, 0.02 * i);
  EXPECT_TRUE(detector.detect(line).empty());
  EXPECT_TRUE(detector.detect(same).empty());
  est::LedPoints collinear;
  for (int i = 0; i < 7; ++i) collinear[i] = line[i];
  EXPECT_FALSE(est::estimate_led_marker_pose(model, collinear).has_value() &&
               est::estimate_led_marker_pose(model, collinear)->rms < 1e-3);
  // No models.
  EXPECT_TRUE(est::LedMarkerDetector({}).detect(points).empty());
}

// Seed 004 §3 / Table 1: self-calibration from 500 frames of one camera at 0.4-0.8 m, 0.05 px
// centroid noise, d03 known. LED positions within 0.05 mm.
TEST(LedMarkerCalibration, RecoversLedPositions) {
  // A marker as built (Table 1: LEDs a few tenths of a millimetre off the ideal layout).
  std::array<Vector3d, 7> truth = {Vector3d(0.1142, 0, 0),
                                   Vector3d(0.07591, -0.00012, 0.00014),
                                   Vector3d(0.03791, -0.00004, 0.00024),
                                   Vector3d(0, 0, 0),
                                   Vector3d(-0.00014, -0.03797, 0.00033),
                                   Vector3d(0.00028, 0.03815, 0),
                                   Vector3d(-0.03829, 0.0004, -0.01121)};
  truth = est::canonical_led_frame(truth);
  const auto model = est::LedMarkerModel::from_points("truth", truth);
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<est::LedPoints> frames;
  for (int k = 0; k < 500; ++k) {
    // Hand-held in front of the camera: 0.4-0.8 m, tilts up to 50 degrees.
    const double z = 0.4 + 0.4 * u(rng);
    const RigidTransform T = pose(0.15 * z * (u(rng) - 0.5), 0.15 * z * (u(rng) - 0.5), z,
                                  (10 + 40 * u(rng)) * kDeg, 2 * M_PI * u(rng), 2 * M_PI * u(rng));
    const auto m = project(model, T, 0.05, rng);
    if (!m) continue;
    // The calibration gets frames identified without a model (L42 frames are dropped, §3).
    const auto id = est::identify_led_pattern(*m);
    if (!id || id->alternative) continue;
    est::LedPoints ordered;
    for (int i = 0; i < 7; ++i) ordered[i] = (*m)[id->index[i]];
    frames.push_back(ordered);
  }
  const auto result = est::calibrate_led_marker(frames, 0.1142);
  double init_max = 0, max_err = 0;
  for (int i = 0; i < 7; ++i) {
    init_max = std::max(init_max, (result.initial[i] - truth[i]).norm());
    max_err = std::max(max_err, (result.leds[i] - truth[i]).norm());
    std::printf("[calib] M%d truth (%.3f %.3f %.3f) mm, estimate (%.3f %.3f %.3f) mm, error %.4f mm\n", i,
                truth[i].x() * 1e3, truth[i].y() * 1e3, truth[i].z() * 1e3, result.leds[i].x() * 1e3,
                result.leds[i].y() * 1e3, result.leds[i].z() * 1e3, (result.leds[i] - truth[i]).norm() * 1e3);
  }
  std::printf(
      "[calib] %zu frames, %d pairs, %d iterations, initialisation max error %.3f mm, refined max error "
      "%.4f mm, rms %.3f px\n",
      frames.size(), result.pairs_used, result.iterations, init_max * 1e3, max_err * 1e3,
      result.rms * kFocal);
  EXPECT_LT(max_err, 0.05e-3);
}

// The CLI end to end: calibration YAML + FeatureFrame JSONL (pixels, 0.05 px noise) -> bodies YAML.
TEST(LedMarkerCalibration, CommandLine) {
  const auto dir = std::filesystem::temp_directory_path() / ("led_marker_cli_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  panoptes::SystemCalibration system;
  panoptes::CameraCalibration camera;
  camera.id = "cam0";
  camera.intrinsics = {2048, 2048, kFocal, kFocal, 1023.5, 1023.5, {}};
  camera.T_world_cam = RigidTransform{};
  system.cameras.push_back(camera);
  panoptes::save_calibration(system, dir / "calibration.yaml");
  const auto model = est::LedMarkerModel::from_points("truth", paper_leds());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  {
    panoptes::JsonlWriter out(dir / "features.jsonl");
    for (int k = 0; k < 400; ++k) {
      const double z = 0.4 + 0.4 * u(rng);
      const auto m = project(model,
                             pose(0.15 * z * (u(rng) - 0.5), 0.15 * z * (u(rng) - 0.5), z,
                                  (10 + 40 * u(rng)) * kDeg, 2 * M_PI * u(rng), 2 * M_PI * u(rng)),
                             0.05, rng);
      if (!m) continue;
      panoptes::FeatureFrame frame;
      frame.camera_id = "cam0";
      frame.frame = k;
      frame.stamp_ns = 1'000'000'000LL + k * 10'000'000LL;
      for (const auto& p : *m) {
        panoptes::Blob blob;
        blob.x = kFocal * p.x() + 1023.5;
        blob.y = kFocal * p.y() + 1023.5;
        blob.area = 12;
        frame.blobs.push_back(blob);
      }
      std::shuffle(frame.blobs.begin(), frame.blobs.end(), rng);
      out.write(frame);
    }
  }
  auto run = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "estimator_node calibrate marker");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    return est::run_calibrate_marker(int(argv.size()), argv.data());
  };
  const std::string cal = (dir / "calibration.yaml").string(), features = (dir / "features.jsonl").string(),
                    out = (dir / "bodies.yaml").string();
  ASSERT_EQ(run({"--calibration", cal, "--camera", "cam0", "--in-features", features, "--d03", "0.1142",
                 "--name", "wand", "--out", out}),
            0);
  const auto bodies = panoptes::load_bodies(out);
  ASSERT_EQ(bodies.size(), 1u);
  EXPECT_EQ(bodies[0].name, "wand");
  EXPECT_EQ(bodies[0].kind, panoptes::BodyKind::kLed7);
  ASSERT_EQ(bodies[0].markers.size(), 7u);
  const auto truth = est::canonical_led_frame(paper_leds());
  for (int i = 0; i < 7; ++i) EXPECT_LT((bodies[0].markers[i] - truth[i]).norm(), 0.05e-3) << "M" << i;
  EXPECT_EQ(run({"--calibration", cal, "--camera", "nope", "--in-features", features, "--d03", "0.1142",
                 "--out", out}),
            2);
  EXPECT_EQ(
      run({"--calibration", cal, "--camera", "cam0", "--in-features", features, "--d03", "-1", "--out", out}),
      2);
  EXPECT_EQ(run({"--help"}), 0);
  std::filesystem::remove_all(dir);
}

}  // namespace
