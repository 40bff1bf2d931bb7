// SPDX-License-Identifier: Apache-2.0
// A simulated finger (issue 21's acceptance scene): a 4-marker chain on a slowly moving hand,
// bending and straightening in grab/release cycles at up to 3 rad/s, seen by 4 asynchronous
// cameras at about 2 m with 0.1 px noise and static reflections next to the hand. Deterministic
// for a seed. Shared by the unit tests and bench_estimator.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "panoptes/camera_model.h"
#include "panoptes/chain_definition.h"
#include "panoptes/estimator/chain.h"
#include "panoptes/time.h"
#include "test_cameras.h"

namespace panoptes::estimator {

inline ChainDefinition test_finger() {
  ChainDefinition finger;
  finger.name = "index";
  finger.link_lengths_m = {0.045, 0.030, 0.025};
  finger.joint_limits = {{-0.3, 1.8}, {-0.3, 1.8}};
  finger.tip_offset_m = Eigen::Vector3d(0.012, 0.004, 0.0);
  return finger;
}

struct FingerTruth {
  RigidTransform base;
  JointVector angles = JointVector::Zero();
};

// One grab/release transition of both joints (raised cosine, peak rate kPeakRate).
struct BendTransition {
  double start_s = 0.0;
  bool bending = true;  // true: straight -> bent (grab); false: bent -> straight (release)
};

class FingerScene {
 public:
  static constexpr double kRestAngle = 0.15;
  static constexpr double kBentAngle = 1.35;
  static constexpr double kPeakRate = 3.0;  // rad/s per joint
  static constexpr double kCentreHeight = 1.0;

  FingerScene(double duration_s, unsigned seed) : duration_s_(duration_s), rng_(seed) {
    std::uniform_real_distribution<double> hold(0.5, 1.5);
    double t = 0.8;
    bool bending = true;
    while (t + transition_s() < duration_s_ - 0.5) {
      transitions_.push_back({t, bending});
      t += transition_s() + hold(rng_);
      bending = !bending;
    }
  }

  static double transition_s() { return (kBentAngle - kRestAngle) * M_PI / (2.0 * kPeakRate); }
  const std::vector<BendTransition>& transitions() const { return transitions_; }
  double duration_s() const { return duration_s_; }

  double joint_angle(double t) const {
    double angle = kRestAngle;
    for (const BendTransition& transition : transitions_) {
      if (t < transition.start_s) break;
      const double s = std::min(1.0, (t - transition.start_s) / transition_s());
      const double blend = 0.5 * (1.0 - std::cos(M_PI * s));
      angle = transition.bending ? kRestAngle + (kBentAngle - kRestAngle) * blend
                                 : kBentAngle - (kBentAngle - kRestAngle) * blend;
    }
    return angle;
  }

  FingerTruth truth(double t) const {
    FingerTruth truth;
    const double two_pi = 2.0 * M_PI;
    truth.base.t =
        Eigen::Vector3d(0.05 * std::sin(two_pi * 0.25 * t), 0.04 * std::sin(two_pi * 0.17 * t + 1.0),
                        kCentreHeight + 0.03 * std::sin(two_pi * 0.21 * t));
    // Finger along world x, bending towards -z (base y = -world z), turning slowly.
    Eigen::Matrix3d rest;
    rest << 1, 0, 0, 0, 0, 1, 0, -1, 0;
    const Eigen::Matrix3d turn =
        (Eigen::AngleAxisd(0.4 * std::sin(two_pi * 0.1 * t), Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.3 * std::sin(two_pi * 0.13 * t), Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    truth.base.q = Eigen::Quaterniond(turn * rest).normalized();
    truth.angles(0) = joint_angle(t);
    truth.angles(1) = joint_angle(t);
    return truth;
  }

  // World positions of the markers and the tip.
  static std::vector<Eigen::Vector3d> markers(const ChainDefinition& chain, const FingerTruth& truth) {
    const ChainShape shape = chain_shape(chain, truth.angles);
    std::vector<Eigen::Vector3d> world;
    for (int k = 0; k < shape.marker_count; ++k) world.push_back(truth.base.apply(shape.markers[k]));
    return world;
  }
  static Eigen::Vector3d tip(const ChainDefinition& chain, const FingerTruth& truth) {
    return truth.base.apply(chain_shape(chain, truth.angles).tip);
  }

  // Static reflections a few centimetres from the hand's working volume.
  static std::vector<Eigen::Vector3d> reflections() {
    return {{0.04, 0.03, kCentreHeight - 0.06},
            {-0.03, -0.02, kCentreHeight + 0.05},
            {0.12, -0.04, kCentreHeight - 0.02},
            {0.08, 0.06, kCentreHeight + 0.03}};
  }

 private:
  double duration_s_;
  std::mt19937 rng_;
  std::vector<BendTransition> transitions_;
};

struct SimFrame {
  int camera = 0;
  TimeNs stamp_ns = 0;
};

// Frames of `cameras` cameras at `rate_hz`, phases spread over one period (asynchronous).
inline std::vector<SimFrame> asynchronous_frames(int cameras, double rate_hz, double duration_s) {
  std::vector<SimFrame> frames;
  const TimeNs period = static_cast<TimeNs>(1e9 / rate_hz);
  for (TimeNs t = 0; ns_to_seconds(t) < duration_s; t += period)
    for (int c = 0; c < cameras; ++c) frames.push_back({c, t + c * period / cameras});
  return frames;
}

// The blobs a camera sees: every visible point projected, with Gaussian pixel noise.
inline std::vector<Eigen::Vector2d> observe(const CameraModel& camera,
                                            const std::vector<Eigen::Vector3d>& points, double noise_px,
                                            std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<Eigen::Vector2d> blobs;
  for (const Eigen::Vector3d& point : points) {
    const auto pixel = camera.project(point);
    if (!pixel || !camera.in_image(*pixel)) continue;
    blobs.emplace_back(pixel->x() + noise(rng), pixel->y() + noise(rng));
  }
  return blobs;
}

// The prior after identification the chain tracker uses.
inline ChainPriorSigmas test_chain_prior() {
  return ChainTrackerOptions{}.prior;
}

}  // namespace panoptes::estimator
