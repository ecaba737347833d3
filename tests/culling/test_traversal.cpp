// Self and pair traversal report exactly the triangle pairs whose volumes overlap (compared with
// an all-pairs test), each once, with far fewer volume tests than all pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <string>

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

  // In installments of at most `block` pairs (+ one bucket pair's), emptied in between as the CCD
  // blocks do: the same pairs, each once, the same volume tests, and no installment too large.
  const auto bucket = static_cast<std::size_t>(bucket_size(leaf_size));
  for (const std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{100}}) {
    std::vector<TrianglePair> all, part;
    std::int64_t tests = 0;
    int installments = 0;
    start_self_traversal<N>(bvh, scratch);
    for (bool done = false; !done; ++installments) {
      part.clear();
      done = self_traverse_some<N>(bvh, bounds.triangles, scratch, part, tests, block);
      ASSERT_LT(part.size(), block + bucket * bucket);
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
  // same volume tests, no installment larger than a block plus one bucket pair's.
  const auto bucket = static_cast<std::size_t>(bucket_size(std::max(leaf_a, leaf_b)));
  for (const std::size_t block : {std::size_t{1}, std::size_t{7}, std::size_t{100}}) {
    std::vector<TrianglePair> all, part;
    std::int64_t tests = 0;
    int installments = 0;
    start_pair_traversal<N>(a, b, scratch);
    for (bool done = false; !done; ++installments) {
      part.clear();
      done = pair_traverse_some<N>(
          a, bounds.triangles, b, bounds.triangles, scratch, part, tests, block);
      ASSERT_LT(part.size(), block + bucket * bucket);
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

// Volumes that are not of any motion, where the float node volumes must not decide: boxes on a
// lattice of step `step` around `base`, so that many touch exactly (shared bounds) and many miss
// by one or two double ulps — which vanish in float — at magnitudes from double subnormals to
// beyond the float range. The traversals must report exactly the pairs whose double volumes
// overlap. Triangles are degenerate, at the boxes' centres (the tree splits by them).
template <int N>
struct BoxSoup {
  skinning::Triangles triangles;
  skinning::Positions centres;
  std::vector<Dop<N>> boxes;
};

template <int N>
BoxSoup<N> box_soup(int count, double base, double step, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> cell(0, N == 3 ? 6 : 2);  // 8 axes must all overlap
  std::uniform_int_distribution<int> width(0, 2);
  std::uniform_int_distribution<int> nudge(-2, 2);
  const auto at = [&](int i) { return base + step * i; };
  const auto nudged = [&](double x) {
    const int n = nudge(rng);  // -2 .. 2 ulps, or exactly on the lattice
    for (int k = 0; k < n; ++k) x = next_up(x);
    for (int k = 0; k > n; --k) x = next_down(x);
    return x;
  };
  BoxSoup<N> s;
  s.triangles.resize(count, 3);
  s.centres.resize(3 * count, 3);
  for (int f = 0; f < count; ++f) {
    Dop<N> d;
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      const int c = cell(rng);
      d.lo[k] = nudged(at(c));
      d.hi[k] = std::max(d.lo[k], nudged(at(c + width(rng))));
    }
    s.boxes.push_back(d);
    for (int v = 0; v < 3; ++v) {
      s.triangles(f, v) = 3 * f + v;
      for (int k = 0; k < 3; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        s.centres(3 * f + v, k) = 0.5 * d.lo[kk] + 0.5 * d.hi[kk];
      }
    }
  }
  return s;
}

template <int N>
void check_box_soup(const BoxSoup<N>& s, int leaf_size, const std::string& what) {
  SCOPED_TRACE(what + ", N = " + std::to_string(N) + ", leaf_size = " + std::to_string(leaf_size));
  const std::span<const Dop<N>> boxes(s.boxes);
  const auto want = all_overlapping_pairs<N>(boxes);
  ASSERT_FALSE(want.empty());
  ASSERT_LT(want.size(), s.boxes.size() * (s.boxes.size() - 1) / 2) << "nothing to cull";
  Bvh<N> bvh(s.triangles, s.centres, BvhOptions{leaf_size});
  bvh.refit(boxes);
  TraversalScratch scratch;
  std::vector<TrianglePair> got;
  std::int64_t bv_tests = 0;
  self_traverse<N>(bvh, boxes, scratch, got, bv_tests);
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, want);
  // Across two trees: the even and the odd boxes.
  std::vector<std::int32_t> even, odd;
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(s.boxes.size()); ++f) {
    (f % 2 ? odd : even).push_back(f);
  }
  Bvh<N> a(s.triangles, s.centres, even, BvhOptions{leaf_size});
  Bvh<N> b(s.triangles, s.centres, odd, BvhOptions{1});
  a.refit(boxes);
  b.refit(boxes);
  std::vector<TrianglePair> cross, want_cross;
  pair_traverse<N>(a, boxes, b, boxes, scratch, cross, bv_tests);
  for (auto& p : cross) {
    ASSERT_EQ(p.a % 2, 0);
    if (p.b < p.a) std::swap(p.a, p.b);
  }
  for (const auto& p : want) {
    if (p.a % 2 != p.b % 2) want_cross.push_back(p);
  }
  std::sort(cross.begin(), cross.end());
  EXPECT_EQ(cross, want_cross);
}

TEST(SelfTraverse, FloatNodeVolumesNeverDecideAPair) {
  struct Scale {
    const char* name;
    double base;
    double step;
  };
  const Scale scales[] = {
      {"unit lattice", 0.0, 1.0},
      {"1e-8 apart near 1", 1.0, 1e-8},
      {"1e-8 apart near -1", -1.0, 1e-8},
      {"around zero, tiny", -3e-30, 1e-30},
      {"double subnormals", -3e-310, 1e-310},
      {"beyond the float range", 1e39, 1e33},
      {"huge", -3e300, 1e300},
      {"float ulps near 1", 1.0, 1.2e-7},
  };
  for (const Scale& sc : scales) {
    for (const std::uint64_t seed : {1u, 2u}) {
      const std::string what = std::string(sc.name) + ", seed " + std::to_string(seed);
      for (const int leaf : {1, 2, 4, 5}) {
        check_box_soup<3>(box_soup<3>(300, sc.base, sc.step, seed), leaf, what);
      }
      check_box_soup<8>(box_soup<8>(300, sc.base, sc.step, seed), 1, what);
      check_box_soup<8>(box_soup<8>(300, sc.base, sc.step, seed), 3, what);
    }
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
