// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <random>

#include "panoptes/union_find.h"

namespace panoptes {
namespace {

TEST(UnionFind, JoinsSetsAndKeepsTheRootOfTheFirstArgument) {
  UnionFind sets(6);
  EXPECT_EQ(sets.size(), 6U);
  EXPECT_TRUE(sets.unite(4, 1));
  EXPECT_EQ(sets.find(1), 4U);
  EXPECT_TRUE(sets.unite(0, 1));  // 1's root (4) goes under 0
  EXPECT_EQ(sets.find(4), 0U);
  EXPECT_FALSE(sets.unite(4, 0));  // already one set
  EXPECT_TRUE(sets.same_set(1, 0));
  EXPECT_FALSE(sets.same_set(2, 3));
  EXPECT_EQ(sets.find(5), 5U);
}

TEST(UnionFind, AgreesWithLabelPropagationOnRandomGraphs) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 50; ++trial) {
    const std::size_t n = 40;
    std::uniform_int_distribution<std::size_t> node(0, n - 1);
    UnionFind sets(n);
    std::vector<std::size_t> label(n);
    for (std::size_t i = 0; i < n; ++i) label[i] = i;
    for (int e = 0; e < 25; ++e) {
      const std::size_t a = node(rng), b = node(rng);
      sets.unite(a, b);
      const std::size_t from = label[b], to = label[a];
      for (auto& l : label)
        if (l == from) l = to;
    }
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b) EXPECT_EQ(sets.same_set(a, b), label[a] == label[b]);
  }
}

TEST(UnionFind, ParitiesFollowTheRelationsThroughLongChains) {
  // A chain 0 - 1 - ... - 19 where every odd link is "reversed": parity(i) relative to node 0 is
  // the number of reversed links on the way, mod 2, whatever the root and the compression.
  UnionFind sets(20);
  for (std::size_t i = 19; i > 0; --i) sets.unite(i, i - 1, static_cast<int>(i % 2));
  int expected = 0;
  for (std::size_t i = 1; i < 20; ++i) {
    expected ^= static_cast<int>(i % 2);
    EXPECT_EQ(sets.parity(i) ^ sets.parity(0), expected) << i;
  }
  EXPECT_FALSE(sets.unite(0, 19, 1));  // joined already: the relation is not changed
  EXPECT_EQ(sets.parity(19) ^ sets.parity(0), expected);
}

}  // namespace
}  // namespace panoptes
