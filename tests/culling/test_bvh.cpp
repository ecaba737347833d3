// Bvh<N>: build structure (a permutation, nested ranges, balanced) and refit invariants (every
// leaf contains its triangles' vertices at both ends of the interval, exactly; every parent
// contains its children).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/exact_dop.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

struct Scene {
  skinning::Mesh mesh;
  skinning::Topology topology;
  skinning::Positions x_t0;
  skinning::Positions x_t1;
};

Scene moving_tube() {
  Scene s;
  s.mesh = test::tube(24, 30, 0.5, 3.0);
  s.topology = test::simple_topology(s.mesh);
  s.x_t0 = test::welded(s.topology, s.mesh.rest_positions);
  s.x_t1 = test::deformed(s.x_t0, 1.0, 0.7);
  return s;
}

template <int N>
void check_structure(const Bvh<N>& bvh, std::int32_t num_triangles, int leaf_size) {
  // triangle_order is a permutation of the triangles.
  std::vector<std::int32_t> order(bvh.triangle_order().begin(), bvh.triangle_order().end());
  std::sort(order.begin(), order.end());
  std::vector<std::int32_t> all(static_cast<std::size_t>(num_triangles));
  std::iota(all.begin(), all.end(), 0);
  ASSERT_EQ(order, all);
  const auto nodes = bvh.nodes();
  ASSERT_FALSE(nodes.empty());
  EXPECT_EQ(nodes[0].begin, 0);
  EXPECT_EQ(nodes[0].end, num_triangles);
  std::int32_t leaves_total = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const BvhNode& n = nodes[i];
    ASSERT_LT(n.begin, n.end);
    if (n.is_leaf()) {
      EXPECT_LE(n.size(), leaf_size);
      leaves_total += n.size();
      continue;
    }
    EXPECT_GT(n.size(), leaf_size);
    const BvhNode& l = nodes[i + 1];
    const BvhNode& r = nodes[static_cast<std::size_t>(n.right)];
    // The children split the parent's range at its median.
    EXPECT_EQ(l.begin, n.begin);
    EXPECT_EQ(l.end, r.begin);
    EXPECT_EQ(r.end, n.end);
    EXPECT_EQ(l.size(), n.size() / 2);
  }
  EXPECT_EQ(leaves_total, num_triangles);
  // A median split is balanced: depth <= ceil(log2(#F / leaf_size)) + 1.
  EXPECT_LE(
      bvh.depth(),
      static_cast<int>(std::ceil(std::log2(static_cast<double>(num_triangles) / leaf_size))) + 1);
}

template <int N>
void check_refit(const Scene& s, int leaf_size, double min_separation) {
  const FeatureTopology topology(s.mesh, s.topology);
  Bvh<N> bvh(topology.welded_triangles(), s.x_t0, BvhOptions{leaf_size});
  check_structure(bvh, topology.num_triangles(), leaf_size);

  FeatureBounds<N> bounds;
  swept_vertex_bounds<N>(s.x_t0, s.x_t1, 0.5 * min_separation, bounds.vertices);
  bounds.derive(topology);
  bvh.refit(bounds.triangles);

  const auto nodes = bvh.nodes();
  const auto volumes = bvh.node_bounds();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const BvhNode& n = nodes[i];
    if (!n.is_leaf()) {
      ASSERT_TRUE(volumes[i].contains(volumes[i + 1])) << "node " << i;
      ASSERT_TRUE(volumes[i].contains(volumes[static_cast<std::size_t>(n.right)])) << "node " << i;
      continue;
    }
    for (std::int32_t slot = n.begin; slot < n.end; ++slot) {
      const std::int32_t f = bvh.triangle_order()[static_cast<std::size_t>(slot)];
      for (const std::int32_t v : topology.triangle(f)) {
        ASSERT_TRUE(test::contains_exactly<N>(volumes[i], s.x_t0.row(v).transpose()))
            << "leaf " << i << " triangle " << f << " vertex " << v << " at t0";
        ASSERT_TRUE(test::contains_exactly<N>(volumes[i], s.x_t1.row(v).transpose()))
            << "leaf " << i << " triangle " << f << " vertex " << v << " at t1";
        // ...and the vertex's own volume, which the feature stage tests.
        ASSERT_TRUE(volumes[i].contains(bounds.vertices[static_cast<std::size_t>(v)]));
      }
    }
  }
}

TEST(Bvh, AabbRefitContainsTrianglesAtBothEndsAndParentsContainChildren) {
  const Scene s = moving_tube();
  for (const int leaf : {1, 2, 5}) check_refit<3>(s, leaf, 0.0);
  check_refit<3>(s, 1, 0.01);
}

TEST(Bvh, KdopRefitContainsTrianglesAtBothEndsAndParentsContainChildren) {
  const Scene s = moving_tube();
  for (const int leaf : {1, 2, 5}) check_refit<8>(s, leaf, 0.0);
  check_refit<8>(s, 3, 0.01);
}

TEST(Bvh, RefitIsExactForVerticesFarFromTheOrigin) {
  // Coordinates around 1e6 with sub-ulp detail: the 16-DOP diagonals round, the boxes must not.
  Scene s = moving_tube();
  s.x_t0 = test::translated(s.x_t0 * 1e3, Eigen::Vector3d(1e6, -1e6, 3e5));
  s.x_t1 = test::translated(s.x_t1 * 1e3, Eigen::Vector3d(1e6 + 0.1, -1e6, 3e5));
  check_refit<8>(s, 1, 0.0);
  check_refit<3>(s, 1, 0.0);
}

TEST(Bvh, SubsetBuildHoldsOnlyTheSubset) {
  const Scene s = moving_tube();
  const std::vector<std::int32_t> subset{5, 9, 100, 3, 700, 42, 43};
  const Bvh<3> bvh(s.topology.welded_triangles, s.x_t0, subset, BvhOptions{2});
  std::vector<std::int32_t> got(bvh.triangle_order().begin(), bvh.triangle_order().end());
  std::vector<std::int32_t> want = subset;
  std::sort(got.begin(), got.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(got, want);
}

TEST(Bvh, BuildIsDeterministic) {
  const Scene s = moving_tube();
  const Bvh<8> a(s.topology.welded_triangles, s.x_t0, BvhOptions{1});
  const Bvh<8> b(s.topology.welded_triangles, s.x_t0, BvhOptions{1});
  ASSERT_EQ(a.nodes().size(), b.nodes().size());
  EXPECT_TRUE(
      std::equal(a.triangle_order().begin(), a.triangle_order().end(), b.triangle_order().begin()));
}

TEST(Bvh, EmptyAndSingleTriangle) {
  const skinning::Triangles none(0, 3);
  const skinning::Positions x(0, 3);
  const Bvh<3> empty(none, x);
  EXPECT_TRUE(empty.empty());
  skinning::Triangles one(1, 3);
  one << 0, 1, 2;
  skinning::Positions p(3, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  const Bvh<3> single(one, p);
  ASSERT_EQ(single.nodes().size(), 1u);
  EXPECT_TRUE(single.nodes()[0].is_leaf());
  EXPECT_EQ(single.depth(), 0);
}

TEST(Bvh, RejectsBadInput) {
  const Scene s = moving_tube();
  EXPECT_THROW_MESSAGE(
      (Bvh<3>(s.topology.welded_triangles, s.x_t0, BvhOptions{0})), InvalidInput, "leaf_size");
  skinning::Triangles bad = s.topology.welded_triangles;
  bad(7, 2) = 1 << 30;
  EXPECT_THROW_MESSAGE((Bvh<3>(bad, s.x_t0)), InvalidInput, "triangle 7");
  const std::vector<std::int32_t> subset{1, -4};
  EXPECT_THROW_MESSAGE(
      (Bvh<3>(s.topology.welded_triangles, s.x_t0, subset)), InvalidInput, "subset entry 1");
}

}  // namespace
}  // namespace skelcd::culling
