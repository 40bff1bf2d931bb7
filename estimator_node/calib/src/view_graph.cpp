// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/view_graph.h"

#include <map>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "panoptes/union_find.h"

namespace panoptes::calib {

namespace {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// The cameras of the graph being placed, as the placement goes on.
struct Placement {
  std::vector<bool> usable, registered;
  std::vector<Eigen::Matrix3d> R_world_cam;
  std::vector<Eigen::Vector3d> center;
  int count = 0;
};

// The components of the view graph, its largest (or the reference's) and the reference camera;
// the cameras of the other components fail.
struct Components {
  std::map<int, std::vector<int>> members;  // by root
  std::map<int, int> degree;                // pairs per camera
  int main_root = -1;
};

Components find_components(const ViewGraphInput& input) {
  const int n = static_cast<int>(input.camera_ids.size());
  Components out;
  UnionFind view_graph(static_cast<std::size_t>(n));
  // b's root stays the root (the components below are keyed by it).
  for (const auto& pair : input.pairs)
    view_graph.unite(static_cast<std::size_t>(pair.b), static_cast<std::size_t>(pair.a));
  const auto find = [&](int c) { return static_cast<int>(view_graph.find(static_cast<std::size_t>(c))); };
  for (const auto& pair : input.pairs) {
    ++out.degree[pair.a];
    ++out.degree[pair.b];
  }
  for (int c = 0; c < n; ++c)
    if (input.usable[c]) out.members[find(c)].push_back(c);
  // The reference: asked for, else the camera with most pairs in the largest component.
  std::size_t best_size = 0;
  for (const auto& [root, members] : out.members)
    if (members.size() > best_size) {
      best_size = members.size();
      out.main_root = root;
    }
  if (!input.reference_camera.empty()) {
    for (int c = 0; c < n; ++c)
      if (input.camera_ids[c] == input.reference_camera && input.usable[c]) out.main_root = find(c);
  }
  return out;
}

void fail(int camera, const std::string& reason, Placement& placement, ViewGraphResult& result) {
  if (result.failures[camera].empty()) result.failures[camera] = reason;
  placement.usable[camera] = false;
  placement.registered[camera] = false;
}

void fail_other_components(const ViewGraphInput& input, Components& components, Placement& placement,
                           ViewGraphResult& result) {
  for (const auto& [root, members] : components.members) {
    if (root == components.main_root) continue;
    std::vector<std::string> names, main_names;
    for (int c : members) names.push_back(input.camera_ids[c]);
    for (int c : components.members[components.main_root]) main_names.push_back(input.camera_ids[c]);
    const std::string reason = members.size() == 1 && components.degree[members[0]] == 0
                                   ? "shares too few wand samples with any other camera (need " +
                                         std::to_string(input.min_pair_samples) + " for a relative pose)"
                                   : "disconnected view graph: {" + join(names) +
                                         "} share no usable wand samples with {" + join(main_names) + "}";
    for (int c : members) fail(c, reason, placement, result);
  }
}

int choose_reference(const ViewGraphInput& input, Components& components) {
  int reference = -1;
  for (int c : components.members[components.main_root])
    if (input.camera_ids[c] == input.reference_camera) reference = c;
  if (reference < 0) {
    for (int c : components.members[components.main_root])
      if (reference < 0 || components.degree[c] > components.degree[reference]) reference = c;
  }
  return reference;
}

// The unplaced camera with a pair to a placed one whose pair ranks best; -1 if none.
int next_camera(const ViewGraphInput& input, const Placement& placement) {
  int next = -1;
  double next_score = 1e300;
  for (const auto& pair : input.pairs) {
    const bool a_in = placement.registered[pair.a], b_in = placement.registered[pair.b];
    if (a_in == b_in) continue;
    const int candidate = a_in ? pair.b : pair.a;
    if (!placement.usable[candidate]) continue;
    int neighbours = 0;
    for (const auto& other : input.pairs)
      if ((other.a == candidate && placement.registered[other.b]) ||
          (other.b == candidate && placement.registered[other.a]))
        ++neighbours;
    // A single light gives no scale: place by intersecting rays from two registered cameras
    // (seed 003 §3.3.1), or along the first pair's unit baseline.
    if (!input.metric && neighbours < 2 && placement.count > 1) continue;
    if (pair.score < next_score) {
      next_score = pair.score;
      next = candidate;
    }
  }
  return next;
}

// Every pair of `next` to a placed camera votes, weighted by its rank.
void place(const ViewGraphInput& input, int next, Placement& placement, ViewGraphResult& result) {
  Eigen::Vector4d q_sum = Eigen::Vector4d::Zero();
  Eigen::Vector3d c_sum = Eigen::Vector3d::Zero();
  double w_sum = 0;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  std::optional<Eigen::Quaterniond> first_q;
  for (const auto& pair : input.pairs) {
    int known;
    Eigen::Matrix3d R_known_next;
    Eigen::Vector3d c_next_in_known;
    if (pair.a == next && placement.registered[pair.b]) {
      known = pair.b;
      R_known_next = pair.pose.R_ab.transpose();
      c_next_in_known = -pair.pose.R_ab.transpose() * pair.pose.c_b;
    } else if (pair.b == next && placement.registered[pair.a]) {
      known = pair.a;
      R_known_next = pair.pose.R_ab;
      c_next_in_known = pair.pose.c_b;
    } else {
      continue;
    }
    const double w = 1.0 / (pair.score * pair.score);
    Eigen::Quaterniond q(placement.R_world_cam[known] * R_known_next);
    if (!first_q) first_q = q;
    if (first_q->coeffs().dot(q.coeffs()) < 0) q.coeffs() *= -1;
    q_sum += w * q.coeffs();
    // Seed 003 eq. 3.4: T_WC = T_WA + alpha R_WA T_AC. With a metric wand alpha is known.
    const Eigen::Vector3d direction = placement.R_world_cam[known] * c_next_in_known;
    c_sum += w * (placement.center[known] + direction);
    w_sum += w;
    const Eigen::Vector3d d = direction.normalized();
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += w * P;
    b += w * P * placement.center[known];
    result.used_edges.push_back(pair.edge_index);
  }
  placement.R_world_cam[next] = Eigen::Quaterniond(q_sum.normalized()).toRotationMatrix();
  if (input.metric || placement.count == 1) {
    placement.center[next] = c_sum / w_sum;
  } else {
    placement.center[next] = A.ldlt().solve(b);  // closest point to all rays
  }
  placement.registered[next] = true;
  ++placement.count;
}

}  // namespace

ViewGraphResult unify_view_graph(const ViewGraphInput& input) {
  const std::size_t n = input.camera_ids.size();
  ViewGraphResult result;
  result.T_world_cam.resize(n);
  result.failures.resize(n);
  Components components = find_components(input);
  if (components.main_root < 0) return result;
  Placement placement;
  placement.usable = input.usable;
  placement.registered.assign(n, false);
  placement.R_world_cam.assign(n, Eigen::Matrix3d::Identity());
  placement.center.assign(n, Eigen::Vector3d::Zero());
  fail_other_components(input, components, placement, result);
  result.reference = choose_reference(input, components);
  placement.registered[result.reference] = true;
  placement.count = 1;
  for (int next = next_camera(input, placement); next >= 0; next = next_camera(input, placement))
    place(input, next, placement, result);
  for (std::size_t c = 0; c < n; ++c) {
    if (!placement.usable[c]) continue;
    if (!placement.registered[c]) {
      fail(static_cast<int>(c),
           input.metric
               ? "could not be placed from its pairwise relative poses"
               : "connected to only one calibrated camera: a single light gives no scale for that pair",
           placement, result);
      continue;
    }
    RigidTransform T_world_cam;
    T_world_cam.q = Eigen::Quaterniond(placement.R_world_cam[c]);
    T_world_cam.t = placement.center[c];
    result.T_world_cam[c] = T_world_cam;
  }
  result.placed = placement.count;
  return result;
}

}  // namespace panoptes::calib
