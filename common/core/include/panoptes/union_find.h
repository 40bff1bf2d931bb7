// SPDX-License-Identifier: Apache-2.0
// Disjoint sets over the nodes 0..n-1 (union-find with path compression), each node optionally
// carrying a parity relative to its set's root: the one implementation behind the tracker's
// association clusters, the calibration's view graph and bar-end labels, and the simulator's merged
// blobs. With every relation's parity 0 it is a plain union-find.
#pragma once

#include <cstddef>
#include <vector>

namespace panoptes {

class UnionFind {
 public:
  explicit UnionFind(std::size_t node_count);

  std::size_t size() const { return parent_.size(); }

  // The root of x's set.
  std::size_t find(std::size_t x);
  // x's parity (0 or 1) relative to the root of its set.
  int parity(std::size_t x);

  // Joins the sets of `keep` and `join`: the root of `join`'s set goes under the root of `keep`'s
  // (callers that key results by root rely on which one stays), with parities set so that
  // parity(keep) ^ parity(join) == relative_parity. False if they already were one set.
  bool unite(std::size_t keep, std::size_t join, int relative_parity = 0);

  bool same_set(std::size_t a, std::size_t b) { return find(a) == find(b); }

 private:
  std::vector<std::size_t> parent_;
  std::vector<int> parity_;  // relative to the parent
};

}  // namespace panoptes
