// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/body_identification.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "panoptes/errors.h"
#include "panoptes/rigid_fit.h"

namespace panoptes::estimator {

namespace {

// Maximal cliques by Bron–Kerbosch with pivoting, bounded below by the best size found so far
// (cliques of that size are still visited, so ties can be compared).
class CliqueSearch {
 public:
  CliqueSearch(const std::vector<std::vector<int>>& adjacency, int min_size, std::size_t max_steps)
      : adjacency_(adjacency), best_size_(min_size), max_steps_(max_steps) {}

  template <class Visit>
  void run(Visit&& visit) {
    std::vector<int> R, P(adjacency_.size()), X;
    for (std::size_t i = 0; i < P.size(); ++i) P[i] = static_cast<int>(i);
    expand(R, P, X, visit);
  }

  void raise_bound(int size) { best_size_ = std::max(best_size_, size); }

 private:
  bool adjacent(int a, int b) const {
    return std::binary_search(adjacency_[a].begin(), adjacency_[a].end(), b);
  }

  template <class Visit>
  void expand(std::vector<int>& R, std::vector<int> P, std::vector<int> X, Visit& visit) {
    if (++steps_ > max_steps_) return;
    if (static_cast<int>(R.size() + P.size()) < best_size_) return;
    if (P.empty()) {
      if (X.empty()) visit(R);
      return;
    }
    // Pivot: the vertex of P ∪ X with the most neighbours in P.
    int pivot = -1;
    std::size_t most = 0;
    for (const auto* set : {&P, &X}) {
      for (int u : *set) {
        std::size_t count = 0;
        for (int v : P) count += adjacent(u, v) ? 1 : 0;
        if (pivot < 0 || count > most) {
          pivot = u;
          most = count;
        }
      }
    }
    std::vector<int> candidates;
    for (int v : P)
      if (!adjacent(pivot, v)) candidates.push_back(v);
    for (int v : candidates) {
      std::vector<int> P2, X2;
      for (int u : P)
        if (adjacent(v, u)) P2.push_back(u);
      for (int u : X)
        if (adjacent(v, u)) X2.push_back(u);
      R.push_back(v);
      expand(R, std::move(P2), std::move(X2), visit);
      R.pop_back();
      P.erase(std::find(P.begin(), P.end(), v));
      X.push_back(v);
    }
  }

  const std::vector<std::vector<int>>& adjacency_;
  int best_size_;
  std::size_t max_steps_;
  std::size_t steps_ = 0;
};

}  // namespace

std::optional<BodyMatch> identify_body(const std::vector<Eigen::Vector3d>& markers,
                                       const std::vector<MeasuredPoint>& points_in,
                                       const IdentificationOptions& options) {
  const int m = static_cast<int>(markers.size());
  const std::size_t n_points = std::min(points_in.size(), options.max_points);
  if (m < options.min_markers || static_cast<int>(n_points) < options.min_markers) return std::nullopt;
  double span = 0;  // the body's largest marker distance
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b) span = std::max(span, (markers[a] - markers[b]).norm());

  // Nodes (point, marker). A pair of nodes is an edge when the distances agree.
  std::vector<std::pair<int, int>> nodes;
  for (std::size_t i = 0; i < n_points; ++i) {
    if (!points_in[i].p.allFinite()) continue;
    for (int j = 0; j < m; ++j) nodes.emplace_back(static_cast<int>(i), j);
  }
  const auto tolerance = [&](int i, int k) {
    const double s = std::hypot(points_in[i].sigma_m, points_in[k].sigma_m);
    return options.tolerance_floor_m + options.tolerance_sigmas * s;
  };
  std::vector<std::vector<int>> adjacency(nodes.size());
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    const auto [i, j] = nodes[a];
    for (std::size_t b = a + 1; b < nodes.size(); ++b) {
      const auto [k, l] = nodes[b];
      if (i == k || j == l) continue;
      const double measured = (points_in[i].p - points_in[k].p).norm();
      if (measured > span + tolerance(i, k)) continue;
      const double model = (markers[j] - markers[l]).norm();
      if (std::abs(measured - model) <= tolerance(i, k)) {
        adjacency[a].push_back(static_cast<int>(b));
        adjacency[b].push_back(static_cast<int>(a));
      }
    }
  }
  // Nodes with fewer than min_markers - 1 neighbours are in no clique worth having.
  const std::size_t min_degree = static_cast<std::size_t>(options.min_markers - 1);
  std::vector<int> keep(nodes.size(), -1);
  std::vector<int> kept;
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    if (adjacency[a].size() >= min_degree) {
      keep[a] = static_cast<int>(kept.size());
      kept.push_back(static_cast<int>(a));
    }
  }
  if (static_cast<int>(kept.size()) < options.min_markers) return std::nullopt;
  std::vector<std::vector<int>> graph(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) {
    for (int b : adjacency[kept[k]])
      if (keep[b] >= 0) graph[k].push_back(keep[b]);
    std::sort(graph[k].begin(), graph[k].end());
  }

  std::optional<BodyMatch> best;
  CliqueSearch search(graph, options.min_markers, options.max_clique_steps);
  std::vector<Eigen::Vector3d> from, to;
  search.run([&](const std::vector<int>& clique) {
    from.clear();
    to.clear();
    for (int v : clique) {
      const auto [i, j] = nodes[kept[v]];
      from.push_back(markers[j]);
      to.push_back(points_in[i].p);
    }
    double rms = 0;
    const auto T = fit_rigid_transform(from, to, &rms);
    if (!T || rms > options.max_rms_m) return;
    const bool better = !best || clique.size() > best->pairs.size() ||
                        (clique.size() == best->pairs.size() && rms < best->rms_m);
    if (!better) return;
    BodyMatch match;
    for (int v : clique) match.pairs.emplace_back(nodes[kept[v]].first, nodes[kept[v]].second);
    std::sort(match.pairs.begin(), match.pairs.end(),
              [](const auto& x, const auto& y) { return x.second < y.second; });
    match.T_world_body = *T;
    match.rms_m = rms;
    best = std::move(match);
    search.raise_bound(static_cast<int>(clique.size()));
  });
  return best;
}

void validate_body(const BodyDefinition& body, const std::string& file) {
  const auto fail = [&](const std::string& reason) {
    throw ConfigError(file, "body '" + body.name + "'", reason);
  };
  if (body.markers.size() < 3)
    fail("needs at least 3 markers for a pose, has " + std::to_string(body.markers.size()));
  for (std::size_t i = 0; i < body.markers.size(); ++i) {
    if (!body.markers[i].allFinite()) fail("markers[" + std::to_string(i) + "] is not finite");
  }
  for (std::size_t i = 0; i < body.markers.size(); ++i) {
    for (std::size_t k = i + 1; k < body.markers.size(); ++k) {
      if ((body.markers[i] - body.markers[k]).norm() < 0.001) {
        fail("markers[" + std::to_string(i) + "] and markers[" + std::to_string(k) +
             "] coincide (closer than 1 mm)");
      }
    }
  }
  double rms = 0;
  if (!fit_rigid_transform(body.markers, body.markers, &rms))
    fail("all markers lie on one line: the rotation about it cannot be measured");
}

std::vector<std::string> distinguishability_warnings(const std::vector<BodyDefinition>& bodies,
                                                     const IdentificationOptions& options) {
  std::vector<std::string> warnings;
  for (std::size_t a = 0; a < bodies.size(); ++a) {
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      if (a == b || bodies[b].markers.size() > bodies[a].markers.size() ||
          (bodies[b].markers.size() == bodies[a].markers.size() && b < a))
        continue;
      // Body b's markers as exact measurements: does body a find itself among them?
      std::vector<MeasuredPoint> points;
      for (const auto& marker : bodies[b].markers) points.push_back({marker, 0.0});
      const auto match = identify_body(bodies[a].markers, points, options);
      if (!match) continue;
      std::ostringstream out;
      if (match->pairs.size() == bodies[b].markers.size()) {
        out << "bodies '" << bodies[a].name << "' and '" << bodies[b].name << "' cannot be told apart: all "
            << bodies[b].markers.size() << " markers of '" << bodies[b].name << "' match '" << bodies[a].name
            << "' within " << options.tolerance_floor_m * 1e3 << " mm; move a marker";
      } else {
        out << "bodies '" << bodies[a].name << "' and '" << bodies[b].name << "' share "
            << match->pairs.size() << " markers with the same distances (within "
            << options.tolerance_floor_m * 1e3 << " mm): when only those are visible they can be confused";
      }
      warnings.push_back(out.str());
    }
  }
  return warnings;
}

}  // namespace panoptes::estimator
