// SPDX-License-Identifier: Apache-2.0
// 7-LED marker model, 2D identification (seed 004 §2.2.2), k-means clustering and the detector
// (§2.2.4). The pose is in led_marker_pose.cpp, the calibration in led_marker_calibration.cpp.
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>

#include "panoptes/estimator/led_marker.h"

namespace panoptes::estimator {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

std::string mm(double metres) {
  std::ostringstream s;
  s.precision(3);
  s << metres * 1e3 << " mm";
  return s.str();
}

double cross2(const Vector2d& a, const Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// A 2D line: points p with n . (p - c) = 0, |n| = 1.
struct Line {
  Vector2d c = Vector2d::Zero();
  Vector2d n = Vector2d::UnitY();
  double distance(const Vector2d& p) const { return n.dot(p - c); }
};

Line line_through(const Vector2d& a, const Vector2d& b) {
  const Vector2d d = b - a;
  const double len = d.norm();
  Line l;
  l.c = a;
  l.n = len > 0 ? Vector2d(-d.y() / len, d.x() / len) : Vector2d::UnitY();
  return l;
}

// Orthogonal regression line of the points selected by `mask` (bit i = point i); `quality` is
// the distance of the furthest point from it (§2.2.2: "quality is determined by the distance of
// the furthest outlier to the line").
Line fit_line(const LedPoints& p, unsigned mask, double* quality) {
  Vector2d c = Vector2d::Zero();
  int n = 0;
  for (int i = 0; i < kLedCount; ++i)
    if (mask & (1u << i)) c += p[i], ++n;
  c /= n;
  double sxx = 0, sxy = 0, syy = 0;
  for (int i = 0; i < kLedCount; ++i) {
    if (!(mask & (1u << i))) continue;
    const Vector2d d = p[i] - c;
    sxx += d.x() * d.x(), sxy += d.x() * d.y(), syy += d.y() * d.y();
  }
  // Normal = eigenvector of the smaller eigenvalue of the scatter matrix (closed form, no trig).
  const double half = 0.5 * (sxx - syy);
  const double small = 0.5 * (sxx + syy) - std::sqrt(half * half + sxy * sxy);
  Vector2d n1(sxy, small - sxx), n2(small - syy, sxy);
  const Vector2d normal = n1.squaredNorm() > n2.squaredNorm() ? n1 : n2;
  const double len = normal.norm();
  Line l;
  l.c = c;
  l.n = len > 0 ? Vector2d(normal / len) : Vector2d::UnitY();
  if (quality) {
    double q = 0;
    for (int i = 0; i < kLedCount; ++i)
      if (mask & (1u << i)) q = std::max(q, std::abs(l.distance(p[i])));
    *quality = q;
  }
  return l;
}

std::vector<int> members(unsigned mask) {
  std::vector<int> out;
  for (int i = 0; i < kLedCount; ++i)
    if (mask & (1u << i)) out.push_back(i);
  return out;
}

// m4/m5 from the sign of cross(m0 - m3, p - m3): m5 on the positive side (handedness +1).
double side_of_l03(const LedPoints& p, int i0, int i3, int i) {
  return cross2(p[i0] - p[i3], p[i] - p[i3]);
}

std::optional<LedIdentification> identify_l5(const LedPoints& p, unsigned line_mask) {
  // L5: five points on l1; the two others (m4, m5) define l2; m3 is the point of l1 closest to
  // l1 x l2; m6 lies alone on one side of l2; m0, m1, m2 by descending |distance to l2|; m4, m5
  // by their signed distance to l03.
  const Line l1 = fit_line(p, line_mask, nullptr);
  const std::vector<int> off = members(~line_mask & 0x7Fu);
  const Line l2 = line_through(p[off[0]], p[off[1]]);
  // Intersection: point on l2 (c2 + s d2) with n1 . (x - c1) = 0.
  const Vector2d d2(l2.n.y(), -l2.n.x());
  const double denom = l1.n.dot(d2);
  if (std::abs(denom) < 1e-9) return std::nullopt;
  const Vector2d x = l2.c + d2 * (l1.n.dot(l1.c - l2.c) / denom);
  std::vector<int> on = members(line_mask);
  const auto m3_it = std::min_element(on.begin(), on.end(), [&](int a, int b) {
    return (p[a] - x).squaredNorm() < (p[b] - x).squaredNorm();
  });
  const int m3 = *m3_it;
  on.erase(m3_it);
  int positive = 0;
  for (int i : on) positive += l2.distance(p[i]) > 0;
  if (positive != 1 && positive != 3) return std::nullopt;
  const bool lone_positive = positive == 1;
  const auto m6_it =
      std::find_if(on.begin(), on.end(), [&](int i) { return (l2.distance(p[i]) > 0) == lone_positive; });
  const int m6 = *m6_it;
  on.erase(m6_it);
  std::sort(on.begin(), on.end(),
            [&](int a, int b) { return std::abs(l2.distance(p[a])) > std::abs(l2.distance(p[b])); });
  LedIdentification id;
  id.led_case = LedCase::kL5;
  id.index = {on[0], on[1], on[2], m3, -1, -1, m6};
  const double s0 = side_of_l03(p, on[0], m3, off[0]), s1 = side_of_l03(p, on[0], m3, off[1]);
  if (s0 * s1 >= 0) return std::nullopt;
  id.index[5] = s0 > 0 ? off[0] : off[1];
  id.index[4] = s0 > 0 ? off[1] : off[0];
  return id;
}

// After m0..m3 are known: among the three other points, the one alone on its side of l03 is m5
// (positive) or m4; the remaining two are ordered by their distance to the line m3-lone, closest
// first (L41). `ambiguous_within` > 0 marks the pair ambiguous (L42) when both are that close.
std::optional<LedIdentification> assign_cross_arm(const LedPoints& p, std::array<int, 4> m0123,
                                                  std::vector<int> rest, LedCase led_case,
                                                  double ambiguous_within) {
  const int m0 = m0123[0], m3 = m0123[3];
  int positive = 0;
  for (int i : rest) positive += side_of_l03(p, m0, m3, i) > 0;
  if (positive == 0 || positive == 3) return std::nullopt;
  const bool lone_positive = positive == 1;
  const auto lone_it = std::find_if(rest.begin(), rest.end(),
                                    [&](int i) { return (side_of_l03(p, m0, m3, i) > 0) == lone_positive; });
  const int lone = *lone_it;
  rest.erase(lone_it);
  const Line l = line_through(p[m3], p[lone]);
  if (std::abs(l.distance(p[rest[1]])) < std::abs(l.distance(p[rest[0]]))) std::swap(rest[0], rest[1]);
  LedIdentification id;
  id.led_case = led_case;
  const int partner = rest[0], m6 = rest[1];
  id.index = {
      m0123[0], m0123[1], m0123[2], m3, lone_positive ? partner : lone, lone_positive ? lone : partner, m6};
  if (led_case == LedCase::kL42 || std::abs(l.distance(p[m6])) < ambiguous_within) {
    std::array<int, 7> alt = id.index;
    std::swap(alt[lone_positive ? 4 : 5], alt[6]);
    id.alternative = alt;
  }
  return id;
}

}  // namespace

double led_cross_ratio(const Vector2d& a, const Vector2d& b, const Vector2d& c, const Vector2d& d) {
  const double den = (b - c).norm() * (a - d).norm();
  return den > 0 ? (a - c).norm() * (b - d).norm() / den : std::numeric_limits<double>::quiet_NaN();
}

std::string_view to_string(LedCase c) {
  switch (c) {
    case LedCase::kL5:
      return "L5";
    case LedCase::kL41:
      return "L41";
    case LedCase::kL42:
      return "L42";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
// Model

std::optional<LedMarkerModel> LedMarkerModel::create(std::string name, const std::array<Vector3d, 7>& leds,
                                                     std::string* error) {
  auto fail = [&](const std::string& message) -> std::optional<LedMarkerModel> {
    if (error) *error = message;
    return std::nullopt;
  };
  for (int i = 0; i < kLedCount; ++i)
    if (!leds[i].allFinite()) return fail(std::string("M") + char('0' + i) + " is not finite");
  const double d03 = (leds[0] - leds[3]).norm();
  if (d03 < 1e-4) return fail("M0 and M3 coincide (|M0 M3| = " + mm(d03) + ")");
  const double tol = 0.02 * d03;
  const Vector3d x = (leds[0] - leds[3]) / d03;
  double along[4];
  for (int i = 0; i < 4; ++i) {
    const Vector3d v = leds[i] - leds[3];
    along[i] = x.dot(v);
    const double off = (v - x * along[i]).norm();
    if (off > tol)
      return fail(std::string("M0..M3 must be collinear: M") + char('0' + i) + " is " + mm(off) +
                  " off the line M0-M3");
  }
  if (!(along[2] > tol && along[1] > along[2] + tol && d03 > along[1] + tol))
    return fail("M1 and M2 must lie between M0 and M3 in the order M0, M1, M2, M3");
  Vector3d y = leds[5] - leds[3];
  y -= x * x.dot(y);
  if (y.norm() < tol) return fail("M5 lies on the line M0-M3");
  y.normalize();
  const Vector3d z = x.cross(y);
  Eigen::Matrix3d R;
  R << x, y, z;
  LedMarkerModel model;
  model.name_ = std::move(name);
  model.leds_ = leds;
  model.d03_ = d03;
  model.T_model_plane_.q = Eigen::Quaterniond(R).normalized();
  model.T_model_plane_.t = leds[3];
  for (int i = 0; i < kLedCount; ++i) model.plane_leds_[i] = R.transpose() * (leds[i] - leds[3]);
  const auto& pl = model.plane_leds_;
  for (int i = 0; i < 6; ++i)
    if (std::abs(pl[i].z()) > tol)
      return fail(std::string("M0..M5 must be coplanar: M") + char('0' + i) + " is " +
                  mm(std::abs(pl[i].z())) + " off the plane of M0, M3, M5");
  if (pl[4].y() > -tol) return fail("M4 and M5 must lie on opposite sides of the line M0-M3");
  // M3 on the line M4-M5 (the arms cross at M3).
  const Vector2d p4 = pl[4].head<2>(), p5 = pl[5].head<2>();
  const Line l45 = line_through(p4, p5);
  if (std::abs(l45.distance(Vector2d::Zero())) > tol)
    return fail("M3 must lie on the line M4-M5 (it is " + mm(std::abs(l45.distance(Vector2d::Zero()))) +
                " off)");
  if (std::abs(pl[6].z()) < 0.03 * d03)
    return fail("M6 must be elevated off the plane of M0..M5 (it is " + mm(std::abs(pl[6].z())) +
                " off, need " + mm(0.03 * d03) + ")");
  if (l45.distance(pl[6].head<2>()) * l45.distance(pl[0].head<2>()) >= 0)
    return fail("M6 must lie beyond the line M4-M5, on the side away from M0");
  model.handedness_ = pl[6].z() < 0 ? 1 : -1;
  model.cross_ratio_ = (leds[0] - leds[2]).norm() * (leds[3] - leds[1]).norm() /
                       ((leds[3] - leds[2]).norm() * (leds[0] - leds[1]).norm());
  return model;
}

LedMarkerModel LedMarkerModel::from_points(std::string name, const std::array<Vector3d, 7>& leds) {
  std::string error;
  const std::string label = name;
  auto model = create(std::move(name), leds, &error);
  if (!model) throw std::invalid_argument("7-LED marker '" + label + "': " + error);
  return *std::move(model);
}

LedMarkerModel LedMarkerModel::from_body(const BodyDefinition& body) {
  if (body.markers.size() != kLedCount)
    throw std::invalid_argument("7-LED marker '" + body.name + "': needs exactly 7 markers (M0..M6), has " +
                                std::to_string(body.markers.size()));
  std::array<Vector3d, 7> leds;
  std::copy(body.markers.begin(), body.markers.end(), leds.begin());
  return from_points(body.name, leds);
}

// ---------------------------------------------------------------------------------------------
// Identification (§2.2.2)

std::optional<LedIdentification> identify_led_pattern(const LedPoints& p, double line_tolerance) {
  double diameter = 0;
  for (int i = 0; i < kLedCount; ++i) {
    if (!p[i].allFinite()) return std::nullopt;
    for (int j = 0; j < i; ++j) diameter = std::max(diameter, (p[i] - p[j]).norm());
  }
  if (!(diameter > 1e-12)) return std::nullopt;
  const double tol = line_tolerance * diameter;

  // Regression lines of all 35 four-point subsets, with their quality.
  struct Subset {
    unsigned mask;
    double quality;
  };
  std::array<Subset, 35> subsets{};
  int count = 0;
  for (unsigned mask = 0; mask < 128; ++mask) {
    if (std::popcount(mask) != 4) continue;
    double q = 0;
    fit_line(p, mask, &q);
    subsets[count++] = {mask, q};
  }
  std::sort(subsets.begin(), subsets.end(),
            [](const Subset& a, const Subset& b) { return a.quality < b.quality; });
  const Subset& s1 = subsets[0];
  if (s1.quality > tol) return std::nullopt;  // no dominant line: not a 7-LED pattern

  // L5: a fifth point on the dominant line.
  {
    const Line l1 = fit_line(p, s1.mask, nullptr);
    int best = -1;
    for (int i = 0; i < kLedCount; ++i)
      if (!(s1.mask & (1u << i)) &&
          (best < 0 || std::abs(l1.distance(p[i])) < std::abs(l1.distance(p[best]))))
        best = i;
    double q5 = 0;
    fit_line(p, s1.mask | (1u << best), &q5);
    if (q5 <= tol) return identify_l5(p, s1.mask | (1u << best));
  }

  // L42: a second dominant line sharing exactly one point (m3) with the first.
  for (int k = 1; k < count && subsets[k].quality <= tol; ++k) {
    if (std::popcount(s1.mask & subsets[k].mask) != 1) continue;
    const unsigned a = s1.mask, b = subsets[k].mask;
    const int m3 = std::countr_zero(a & b);
    // l1 is the line whose other points all lie on one side of the other line.
    auto one_sided = [&](unsigned line_mask, unsigned other_mask) {
      const Line other = fit_line(p, other_mask, nullptr);
      int positive = 0, n = 0;
      for (int i : members(line_mask & ~(1u << m3))) positive += other.distance(p[i]) > 0, ++n;
      return positive == 0 || positive == n;
    };
    const bool a_is_l1 = one_sided(a, b), b_is_l1 = one_sided(b, a);
    if (a_is_l1 == b_is_l1) return std::nullopt;
    const unsigned l1 = a_is_l1 ? a : b;
    std::vector<int> on = members(l1 & ~(1u << m3));
    std::sort(on.begin(), on.end(),
              [&](int i, int j) { return (p[i] - p[m3]).squaredNorm() > (p[j] - p[m3]).squaredNorm(); });
    return assign_cross_arm(p, {on[0], on[1], on[2], m3}, members(~l1 & 0x7Fu), LedCase::kL42, 0);
  }

  // L41: m0 is the point of l1 furthest from the centroid of the three others; m1, m2, m3 by
  // ascending distance to m0.
  const std::vector<int> rest = members(~s1.mask & 0x7Fu);
  const Vector2d g = (p[rest[0]] + p[rest[1]] + p[rest[2]]) / 3.0;
  std::vector<int> on = members(s1.mask);
  const int m0 = *std::max_element(on.begin(), on.end(), [&](int i, int j) {
    return (p[i] - g).squaredNorm() < (p[j] - g).squaredNorm();
  });
  std::sort(on.begin(), on.end(),
            [&](int i, int j) { return (p[i] - p[m0]).squaredNorm() < (p[j] - p[m0]).squaredNorm(); });
  // Near-L42 configurations (m6 close to the line m4-m5 but not within the tolerance) keep the
  // swapped pair as an alternative for the 3D check.
  return assign_cross_arm(p, {on[0], on[1], on[2], on[3]}, rest, LedCase::kL41, 2 * tol);
}

// ---------------------------------------------------------------------------------------------
// k-means (§2.2.4)

std::vector<std::vector<int>> cluster_led_points(const std::vector<Vector2d>& points, int k,
                                                 std::uint64_t seed, int max_iterations) {
  const int n = static_cast<int>(points.size());
  k = std::min(k, n);
  if (k <= 0) return {};
  std::mt19937_64 rng(seed);
  std::vector<Vector2d> centers;
  std::vector<char> taken(n, 0);
  std::vector<int> unassigned(n);
  std::iota(unassigned.begin(), unassigned.end(), 0);
  // Seven-member initialisation: a random unassigned point and its six nearest unassigned
  // neighbours; the centre is their barycentre.
  for (int c = 0; c < k && !unassigned.empty(); ++c) {
    const int pick = unassigned[std::uniform_int_distribution<int>(0, int(unassigned.size()) - 1)(rng)];
    std::vector<std::pair<double, int>> near;
    near.reserve(unassigned.size());
    for (int i : unassigned) near.emplace_back((points[i] - points[pick]).squaredNorm(), i);
    const int m = std::min<int>(kLedCount, int(near.size()));
    std::partial_sort(near.begin(), near.begin() + m, near.end());
    Vector2d center = Vector2d::Zero();
    for (int j = 0; j < m; ++j) center += points[near[j].second], taken[near[j].second] = 1;
    centers.push_back(center / m);
    unassigned.erase(
        std::remove_if(unassigned.begin(), unassigned.end(), [&](int i) { return taken[i] != 0; }),
        unassigned.end());
  }
  k = int(centers.size());
  std::vector<int> label(n, -1);
  for (int iteration = 0; iteration < std::max(1, max_iterations); ++iteration) {
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      int best = 0;
      double best_d = std::numeric_limits<double>::infinity();
      for (int c = 0; c < k; ++c) {
        const double d = (points[i] - centers[c]).squaredNorm();
        if (d < best_d) best_d = d, best = c;
      }
      changed |= label[i] != best;
      label[i] = best;
    }
    if (!changed) break;
    std::vector<Vector2d> sum(k, Vector2d::Zero());
    std::vector<int> size(k, 0);
    for (int i = 0; i < n; ++i) sum[label[i]] += points[i], ++size[label[i]];
    for (int c = 0; c < k; ++c)
      if (size[c] > 0) centers[c] = sum[c] / size[c];
  }
  std::vector<std::vector<int>> clusters(k);
  for (int i = 0; i < n; ++i) clusters[label[i]].push_back(i);
  return clusters;
}

// ---------------------------------------------------------------------------------------------
// Detector

LedMarkerDetector::LedMarkerDetector(std::vector<LedMarkerModel> models, LedMarkerOptions options)
    : models_(std::move(models)), options_(options) {}

std::optional<LedMarkerDetection> LedMarkerDetector::detect_cluster(const std::vector<Vector2d>& points,
                                                                    const std::array<int, 7>& cluster) const {
  LedPoints p;
  for (int i = 0; i < kLedCount; ++i) {
    if (cluster[i] < 0 || cluster[i] >= int(points.size())) return std::nullopt;
    p[i] = points[cluster[i]];
  }
  const auto id = identify_led_pattern(p, options_.line_tolerance);
  if (!id) return std::nullopt;
  // Which marker: the cross-ratio of the collinear LEDs (eq. 6), nearest first.
  const double cr = led_cross_ratio(p[id->index[0]], p[id->index[3]], p[id->index[2]], p[id->index[1]]);
  if (!std::isfinite(cr)) return std::nullopt;
  // First-order relative error of the CR for the centroid noise, from the positions s of m0, m3,
  // m2, m1 along the line: d ln CR / d s_a = 1/(a-c) - 1/(a-d), etc.
  const Vector2d dir = (p[id->index[0]] - p[id->index[3]]).normalized();
  auto along = [&](int i) { return dir.dot(p[id->index[i]] - p[id->index[3]]); };
  const double a = along(0), b = along(3), c = along(2), d = along(1);
  const double g2 = std::pow(1 / (a - c) - 1 / (a - d), 2) + std::pow(1 / (b - d) - 1 / (b - c), 2) +
                    std::pow(1 / (b - c) - 1 / (a - c), 2) + std::pow(1 / (a - d) - 1 / (b - d), 2);
  if (!std::isfinite(g2)) return std::nullopt;
  const double tolerance = std::max(options_.cross_ratio_tolerance,
                                    options_.cross_ratio_sigmas * options_.centroid_sigma * std::sqrt(g2));
  std::vector<std::pair<double, int>> candidates;
  for (int m = 0; m < int(models_.size()); ++m) {
    const double rel = std::abs(cr - models_[m].cross_ratio()) / models_[m].cross_ratio();
    if (rel <= tolerance) candidates.emplace_back(rel, m);
  }
  std::sort(candidates.begin(), candidates.end());
  for (const auto& [rel, m] : candidates) {
    const LedMarkerModel& model = models_[m];
    std::array<std::array<int, 7>, 2> orders{id->index, id->alternative.value_or(id->index)};
    const int n_orders = id->alternative ? 2 : 1;
    if (model.handedness() < 0)
      for (auto& order : orders) std::swap(order[4], order[5]);
    auto ordered = [&](const std::array<int, 7>& order) {
      LedPoints q;
      for (int i = 0; i < kLedCount; ++i) q[i] = p[order[i]];
      return q;
    };
    if (n_orders == 2) {
      // L42 (§2.2.2): homography poses P_H46, P_H64 from the six "coplanar" LEDs of each
      // assignment; the smaller reprojection error over all seven LEDs goes first.
      double error[2];
      for (int k = 0; k < 2; ++k) {
        const LedPoints q = ordered(orders[k]);
        const auto T = led_marker_homography_pose(model, q);
        error[k] = T ? led_reprojection_error(model, *T, q) : std::numeric_limits<double>::infinity();
      }
      if (error[1] < error[0]) std::swap(orders[0], orders[1]);
    }
    for (int k = 0; k < n_orders; ++k) {
      const auto pose = estimate_led_marker_pose(model, ordered(orders[k]));
      if (!pose || !(pose->rms <= options_.max_rms)) continue;
      LedMarkerDetection detection;
      detection.model = m;
      for (int i = 0; i < kLedCount; ++i) detection.blob[i] = cluster[orders[k][i]];
      detection.T_cam_marker = pose->T_cam_marker;
      detection.rms = pose->rms;
      detection.led_case = id->led_case;
      return detection;
    }
  }
  return std::nullopt;
}

std::vector<LedMarkerDetection> LedMarkerDetector::detect(const std::vector<Vector2d>& ideal_points) const {
  std::vector<int> valid;
  std::vector<Vector2d> points;
  for (int i = 0; i < int(ideal_points.size()); ++i)
    if (ideal_points[i].allFinite()) valid.push_back(i), points.push_back(ideal_points[i]);
  const int n = int(points.size());
  if (n < kLedCount || models_.empty()) return {};
  auto run = [&](int k) {
    std::vector<LedMarkerDetection> found;
    bool all_seven = true;
    for (const auto& cluster : cluster_led_points(points, k, options_.seed, options_.kmeans_iterations)) {
      if (cluster.size() != std::size_t(kLedCount)) {  // §2.2.4: clusters of != 7 points are dropped
        all_seven = false;
        continue;
      }
      std::array<int, 7> idx{};
      for (int i = 0; i < kLedCount; ++i) idx[i] = valid[cluster[i]];
      if (auto d = detect_cluster(ideal_points, idx)) found.push_back(*d);
    }
    return std::make_pair(found, all_seven);
  };
  const int k = n / kLedCount;
  auto [found, all_seven] = run(k);
  if (options_.retry_extra_cluster && !all_seven && n % kLedCount != 0) {
    auto [again, unused] = run(k + 1);
    if (again.size() > found.size()) found = std::move(again);
  }
  return found;
}

}  // namespace panoptes::estimator
