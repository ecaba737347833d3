// Self and pair traversal report exactly the triangle pairs whose volumes overlap (compared with
// an all-pairs test), each once, with far fewer volume tests than all pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "culling/candidates.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::culling {
namespace {

struct Case {
  const char* name;
  skinning::Mesh mesh;
  skinning::Positions x_t0;
  skinning::Positions x_t1;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  {
    auto m = test::tube(20, 25, 0.5, 3.0);
    auto t = test::simple_topology(m);
    auto x = test::welded(t, m.rest_positions);
    out.push_back({"twisting tube", m, x, test::deformed(x, 1.0, 0.8)});
  }
  {
    auto m = test::sheet(20, 12, 2.0, 1.0);
    auto t = test::simple_topology(m);
    auto x = test::welded(t, m.rest_positions);
    out.push_back(
        {"sheet folding through itself", m, test::folded(x, 1.0, 3.0), test::folded(x, 1.0, 3.3)});
  }
  {
    auto a = test::uv_sphere(12, 16, 1.0);
    auto b = test::uv_sphere(10, 14, 0.8);
    b.rest_positions = test::translated(b.rest_positions, Eigen::Vector3d(1.2, 0.1, 0.0));
    auto m = test::combine(a, b);
    auto t = test::simple_topology(m);
    auto x = test::welded(t, m.rest_positions);
    out.push_back(
        {"two interpenetrating spheres",
         m,
         x,
         test::translated(x, Eigen::Vector3d(-0.05, 0.02, 0.01))});
  }
  return out;
}

template <int N>
std::vector<TrianglePair> all_overlapping_pairs(std::span<const Dop<N>> bounds) {
  std::vector<TrianglePair> out;
  for (std::size_t a = 0; a < bounds.size(); ++a) {
    for (std::size_t b = a + 1; b < bounds.size(); ++b) {
      if (bounds[a].overlaps(bounds[b])) {
        out.push_back({static_cast<std::int32_t>(a), static_cast<std::int32_t>(b)});
      }
    }
  }
  return out;
}

template <int N>
void check_self(const Case& c, int leaf_size) {
  SCOPED_TRACE(
      std::string(c.name) + ", N = " + std::to_string(N) +
      ", leaf_size = " + std::to_string(leaf_size));
  const skinning::Topology topo = test::simple_topology(c.mesh);
  const FeatureTopology ft(c.mesh, topo);
  Bvh<N> bvh(ft.welded_triangles(), c.x_t0, BvhOptions{leaf_size});
  FeatureBounds<N> bounds;
  swept_vertex_bounds<N>(c.x_t0, c.x_t1, 0.0, bounds.vertices);
  bounds.derive(ft);
  bvh.refit(bounds.triangles);

  TraversalScratch scratch;
  scratch.reserve_self(bvh);
  const std::size_t capacity = scratch.stack.capacity();
  std::vector<TrianglePair> got;
  std::int64_t bv_tests = 0;
  self_traverse<N>(bvh, bounds.triangles, scratch, got, bv_tests);
  EXPECT_EQ(scratch.stack.capacity(), capacity) << "the proven stack bound was exceeded";
  for (const auto& p : got) ASSERT_LT(p.a, p.b);
  std::vector<TrianglePair> sorted = got;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "duplicate pair";
  const auto want = all_overlapping_pairs<N>(bounds.triangles);
  EXPECT_EQ(sorted, want);
  const auto nf = static_cast<std::int64_t>(ft.num_triangles());
  EXPECT_LT(bv_tests, nf * (nf - 1) / 8) << "the hierarchy culled almost nothing";

  // In installments of at most `block` pairs (+ one leaf pair's), emptied in between as the CCD
  // blocks do: the same pairs, each once, the same volume tests, and no installment too large.
  for (const std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{100}}) {
    std::vector<TrianglePair> all, part;
    std::int64_t tests = 0;
    int installments = 0;
    start_self_traversal<N>(bvh, scratch);
    for (bool done = false; !done; ++installments) {
      part.clear();
      done = self_traverse_some<N>(bvh, bounds.triangles, scratch, part, tests, block);
      ASSERT_LT(part.size(), block + static_cast<std::size_t>(leaf_size * leaf_size));
      all.insert(all.end(), part.begin(), part.end());
    }
    std::sort(all.begin(), all.end());
    EXPECT_EQ(all, want) << "block " << block;
    EXPECT_EQ(tests, bv_tests) << "block " << block;
    EXPECT_EQ(scratch.stack.capacity(), capacity);
    if (want.size() > block) {
      EXPECT_GT(installments, 1);
    }
  }
}

TEST(SelfTraverse, FindsExactlyTheOverlappingPairs) {
  for (const Case& c : cases()) {
    for (const int leaf : {1, 3, 8}) {
      check_self<3>(c, leaf);
      check_self<8>(c, leaf);
    }
  }
}

template <int N>
void check_pair(const Case& c, int leaf_a, int leaf_b) {
  // Two hierarchies over the two halves of the triangles (by id parity: interleaved in space).
  const skinning::Topology topo = test::simple_topology(c.mesh);
  const FeatureTopology ft(c.mesh, topo);
  std::vector<std::int32_t> even, odd;
  for (std::int32_t f = 0; f < ft.num_triangles(); ++f) (f % 2 ? odd : even).push_back(f);
  Bvh<N> a(ft.welded_triangles(), c.x_t0, even, BvhOptions{leaf_a});
  Bvh<N> b(ft.welded_triangles(), c.x_t0, odd, BvhOptions{leaf_b});
  FeatureBounds<N> bounds;
  swept_vertex_bounds<N>(c.x_t0, c.x_t1, 0.0, bounds.vertices);
  bounds.derive(ft);
  a.refit(bounds.triangles);
  b.refit(bounds.triangles);
  TraversalScratch scratch;
  scratch.reserve_pair(a, b);
  const std::size_t capacity = scratch.stack.capacity();
  std::vector<TrianglePair> got;
  std::int64_t bv_tests = 0;
  pair_traverse<N>(a, bounds.triangles, b, bounds.triangles, scratch, got, bv_tests);
  EXPECT_EQ(scratch.stack.capacity(), capacity);
  std::vector<TrianglePair> want;
  for (const auto fa : even) {
    for (const auto fb : odd) {
      if (bounds.triangles[static_cast<std::size_t>(fa)].overlaps(
              bounds.triangles[static_cast<std::size_t>(fb)])) {
        want.push_back({fa, fb});
      }
    }
  }
  for (const auto& p : got) {
    ASSERT_EQ(p.a % 2, 0) << "a must come from the first hierarchy";
    ASSERT_EQ(p.b % 2, 1);
  }
  // In installments (auto's blocks between its groups): the same pairs in the same order, the
  // same volume tests, no installment larger than a block plus one leaf pair's.
  for (const std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{100}}) {
    std::vector<TrianglePair> all, part;
    std::int64_t tests = 0;
    int installments = 0;
    start_pair_traversal<N>(a, b, scratch);
    for (bool done = false; !done; ++installments) {
      part.clear();
      done = pair_traverse_some<N>(
          a, bounds.triangles, b, bounds.triangles, scratch, part, tests, block);
      ASSERT_LT(part.size(), block + static_cast<std::size_t>(leaf_a * leaf_b));
      all.insert(all.end(), part.begin(), part.end());
    }
    EXPECT_EQ(all, got) << c.name << ", block " << block;
    EXPECT_EQ(tests, bv_tests) << c.name << ", block " << block;
    EXPECT_EQ(scratch.stack.capacity(), capacity);
    if (got.size() > block) {
      EXPECT_GT(installments, 1);
    }
  }
  std::sort(got.begin(), got.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(got, want) << c.name;
}

TEST(PairTraverse, FindsExactlyTheOverlappingCrossPairs) {
  for (const Case& c : cases()) {
    check_pair<3>(c, 1, 1);
    check_pair<3>(c, 4, 1);
    check_pair<8>(c, 2, 5);
  }
}

TEST(SelfTraverse, EmptyHierarchyReportsNothing) {
  const Bvh<3> empty;
  TraversalScratch scratch;
  std::vector<TrianglePair> out;
  std::int64_t tests = 0;
  self_traverse<3>(empty, {}, scratch, out, tests);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(tests, 0);
}

}  // namespace
}  // namespace skelcd::culling
