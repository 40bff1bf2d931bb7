// SPDX-License-Identifier: Apache-2.0
#include "panoptes/union_find.h"

#include <numeric>

namespace panoptes {

UnionFind::UnionFind(std::size_t node_count) : parent_(node_count), parity_(node_count, 0) {
  std::iota(parent_.begin(), parent_.end(), std::size_t{0});
}

std::size_t UnionFind::find(std::size_t x) {
  std::size_t root = x;
  int parity_to_root = 0;
  while (parent_[root] != root) {
    parity_to_root ^= parity_[root];
    root = parent_[root];
  }
  // Path compression: every node on the way now points at the root, its parity made relative to it.
  while (parent_[x] != root && parent_[x] != x) {
    const std::size_t next = parent_[x];
    const int own = parity_[x];
    parent_[x] = root;
    parity_[x] = parity_to_root;
    parity_to_root ^= own;
    x = next;
  }
  return root;
}

int UnionFind::parity(std::size_t x) {
  find(x);  // after compression x is the root or a child of it
  return parent_[x] == x ? 0 : parity_[x];
}

bool UnionFind::unite(std::size_t keep, std::size_t join, int relative_parity) {
  const std::size_t root_keep = find(keep), root_join = find(join);
  if (root_keep == root_join) return false;
  const int parity_keep = parity(keep), parity_join = parity(join);
  parent_[root_join] = root_keep;
  parity_[root_join] = parity_keep ^ parity_join ^ (relative_parity & 1);
  return true;
}

}  // namespace panoptes
