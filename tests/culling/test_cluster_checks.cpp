// The traversals of the radial-view methods against all pairs: a masked self or pair traversal
// reports exactly the overlapping pairs its selection asks for, each once, and `tested` and
// `skipped` split the overlapping pairs between them. The relative AABB filter never removes a
// pair whose triangles touch (checked with the CCD of ccd/), and removes pairs
// that move together. (The conservative CCD accuracy is used: its "no hit" is a proof.)
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/candidates.hpp"
#include "culling/cluster_checks.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/vertex_bounds.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::culling {
namespace {

using Pairs = std::vector<TrianglePair>;

Pairs sorted(Pairs p) {
  for (auto& q : p) {
    if (q.b < q.a) std::swap(q.a, q.b);
  }
  std::sort(p.begin(), p.end());
  return p;
}

struct Scene {
  skinning::Mesh mesh;
  skinning::Topology topology;
  skinning::Positions x_t0, x_t1;
  FeatureBounds<3> bounds;
  FeatureTopology features;
};

Scene folding_sheet(const Eigen::Vector3d& drift = Eigen::Vector3d::Zero()) {
  Scene s;
  s.mesh = test::sheet(16, 10, 2.0, 1.0);
  s.topology = test::simple_topology(s.mesh);
  const auto x = test::welded(s.topology, s.mesh.rest_positions);
  s.x_t0 = test::folded(x, 1.0, 3.0);
  s.x_t1 = test::translated(test::folded(x, 1.0, 3.3), drift);
  s.features = FeatureTopology(s.mesh, s.topology);
  swept_vertex_bounds<3>(s.x_t0, s.x_t1, 0.0, s.bounds.vertices);
  s.bounds.derive(s.features);
  return s;
}

/// Random single-bit masks, with long runs of one sign (as H⁺ regions are).
std::vector<std::uint8_t> random_masks(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::uint8_t> m(n);
  std::uint8_t current = kMaskPositive;
  for (auto& v : m) {
    const auto r = rng() % 20;
    if (r == 0) current = kMaskPositive;
    if (r == 1) current = kMaskNegative;
    v = (rng() % 7 == 0) ? kMaskOther : current;
  }
  return m;
}

TEST(ClusterChecks, SkipRuleOnMasks) {
  EXPECT_TRUE(mask_pair_skipped(kMaskPositive, kMaskPositive));
  EXPECT_TRUE(mask_pair_skipped(kMaskNegative, kMaskNegative));
  EXPECT_FALSE(mask_pair_skipped(kMaskPositive, kMaskNegative));
  EXPECT_FALSE(mask_pair_skipped(kMaskOther, kMaskOther));
  EXPECT_FALSE(mask_pair_skipped(kMaskPositive, kMaskOther));
  // Node masks (unions): only two nodes of one single sign are skipped whole.
  const std::uint8_t mixed = kMaskPositive | kMaskNegative;
  EXPECT_FALSE(mask_pair_skipped(mixed, mixed));
  EXPECT_FALSE(mask_pair_skipped(mixed | kMaskOther, mixed | kMaskOther));
  EXPECT_FALSE(mask_pair_skipped(kMaskPositive | kMaskOther, kMaskPositive | kMaskOther));
}

TEST(ClusterChecks, MaskedSelfTraversalSplitsTheOverlappingPairs) {
  const Scene s = folding_sheet();
  const std::span<const Aabb> tb(s.bounds.triangles);
  const auto nf = static_cast<std::size_t>(s.mesh.num_triangles());
  for (const int leaf : {1, 3}) {
    AabbBvh bvh(s.features.welded_triangles(), s.x_t0, BvhOptions{.leaf_size = leaf});
    bvh.refit(tb);
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
      const auto mask = random_masks(nf, seed);
      ClassMasks node_mask;
      node_class_masks<3>(bvh, mask, node_mask);
      Pairs want_tested, want_skipped;
      for (std::size_t a = 0; a < nf; ++a) {
        for (std::size_t b = a + 1; b < nf; ++b) {
          if (!tb[a].overlaps(tb[b])) continue;
          const TrianglePair p{static_cast<std::int32_t>(a), static_cast<std::int32_t>(b)};
          (mask_pair_skipped(mask[a], mask[b]) ? want_skipped : want_tested).push_back(p);
        }
      }
      ASSERT_FALSE(want_tested.empty());
      ASSERT_FALSE(want_skipped.empty());
      TraversalScratch scratch;
      Pairs tested, skipped;
      std::int64_t bv_tested = 0, bv_skipped = 0;
      masked_self_traverse<3>(bvh, tb, node_mask, MaskedPairs::tested, scratch, tested, bv_tested);
      masked_self_traverse<3>(
          bvh, tb, node_mask, MaskedPairs::skipped, scratch, skipped, bv_skipped);
      EXPECT_EQ(sorted(tested), want_tested) << "leaf " << leaf << " seed " << seed;
      EXPECT_EQ(sorted(skipped), want_skipped) << "leaf " << leaf << " seed " << seed;
      EXPECT_EQ(tested.size(), sorted(tested).size());
      // Pruning by masks: fewer volume tests than the same traversal with nothing to prune (every
      // triangle kMaskOther: all pairs tested; self_traverse counts its wide tests otherwise).
      const std::vector<std::uint8_t> other(nf, kMaskOther);
      ClassMasks other_nodes;
      node_class_masks<3>(bvh, other, other_nodes);
      Pairs all;
      std::int64_t bv_all = 0;
      masked_self_traverse<3>(bvh, tb, other_nodes, MaskedPairs::tested, scratch, all, bv_all);
      EXPECT_EQ(sorted(all).size(), want_tested.size() + want_skipped.size());
      EXPECT_LT(bv_tested, bv_all);
    }
  }
}

TEST(ClusterChecks, MaskedPairTraversalSplitsTheOverlappingPairs) {
  const Scene s = folding_sheet();
  const std::span<const Aabb> tb(s.bounds.triangles);
  const auto nf = static_cast<std::int32_t>(s.mesh.num_triangles());
  // Two "atomic clusters": the two halves of the sheet (they overlap where it folds).
  std::vector<std::int32_t> left, right;
  for (std::int32_t f = 0; f < nf; ++f) (f < nf / 2 ? left : right).push_back(f);
  AabbBvh a(s.features.welded_triangles(), s.x_t0, left);
  AabbBvh b(s.features.welded_triangles(), s.x_t0, right);
  a.refit(tb);
  b.refit(tb);
  const auto mask = random_masks(static_cast<std::size_t>(nf), 11);
  ClassMasks ma, mb;
  node_class_masks<3>(a, mask, ma);
  node_class_masks<3>(b, mask, mb);
  Pairs want_tested, want_skipped;
  for (const auto fa : left) {
    for (const auto fb : right) {
      if (!tb[static_cast<std::size_t>(fa)].overlaps(tb[static_cast<std::size_t>(fb)])) continue;
      const bool skip =
          mask_pair_skipped(mask[static_cast<std::size_t>(fa)], mask[static_cast<std::size_t>(fb)]);
      (skip ? want_skipped : want_tested).push_back({fa, fb});
    }
  }
  ASSERT_FALSE(want_tested.empty());
  ASSERT_FALSE(want_skipped.empty());
  TraversalScratch scratch;
  Pairs tested, skipped;
  std::int64_t bv = 0;
  masked_pair_traverse<3>(a, ma, b, mb, tb, MaskedPairs::tested, scratch, tested, bv);
  masked_pair_traverse<3>(a, ma, b, mb, tb, MaskedPairs::skipped, scratch, skipped, bv);
  EXPECT_EQ(sorted(tested), sorted(want_tested));
  EXPECT_EQ(sorted(skipped), sorted(want_skipped));
}

TEST(ClusterChecks, RelativeBoxesNeverDropATouchingPair) {
  // The sheet folds through itself while drifting far: the swept boxes are long, the relative
  // ones short.
  const Scene s = folding_sheet(Eigen::Vector3d(3.0, 1.0, 0.5));
  const auto nf = static_cast<std::int32_t>(s.mesh.num_triangles());
  // Every non-adjacent pair of the folding sheet: those the filter removes must have no VF or EE
  // contact in the interval (exact CCD), and it must remove a good share of them.
  Pairs pairs;
  for (std::int32_t a = 0; a < nf; ++a) {
    for (std::int32_t b = a + 1; b < nf; ++b) pairs.push_back({a, b});
  }
  Pairs kept = pairs;
  const auto removed = relative_aabb_filter(s.features, s.x_t0, s.x_t1, 0.0, kept);
  EXPECT_EQ(static_cast<std::size_t>(removed), pairs.size() - kept.size());
  EXPECT_GT(removed, static_cast<std::int64_t>(pairs.size() / 2));
  // The prepared filter (per-triangle boxes): sound too, and as tight up to the rounding of the
  // common displacement (a few pairs at most may differ).
  RelativeAabbFilter prepared;
  prepared.prepare(s.features, s.x_t0, s.x_t1);
  Pairs kept_prepared = pairs;
  const auto removed_prepared = prepared.filter(s.features, 0.0, kept_prepared);
  EXPECT_EQ(static_cast<std::size_t>(removed_prepared), pairs.size() - kept_prepared.size());
  EXPECT_NEAR(
      static_cast<double>(removed_prepared),
      static_cast<double>(removed),
      1e-3 * static_cast<double>(pairs.size()));
  for (const Pairs* which : {&kept, &kept_prepared}) {
    const std::set<TrianglePair> kept_set(which->begin(), which->end());
    const auto row = [](const skinning::Positions& x, std::int32_t v) -> Eigen::Vector3d {
      return x.row(v).transpose();
    };
    std::int64_t checked = 0;
    for (const auto& p : pairs) {
      if (kept_set.count(p) != 0) continue;
      const auto& ta = s.features.triangle(p.a);
      const auto& tb = s.features.triangle(p.b);
      // Only pairs that the coarse swept boxes cannot separate are interesting.
      if (!s.bounds.triangles[static_cast<std::size_t>(p.a)].overlaps(
              s.bounds.triangles[static_cast<std::size_t>(p.b)])) {
        continue;
      }
      if (++checked > 1500) break;
      for (int side = 0; side < 2; ++side) {
        const auto& t = side == 0 ? ta : tb;
        const auto& f = side == 0 ? tb : ta;
        for (const auto v : t) {
          const ccd::VertexFaceQuery q{
              row(s.x_t0, v),
              row(s.x_t0, f[0]),
              row(s.x_t0, f[1]),
              row(s.x_t0, f[2]),
              row(s.x_t1, v),
              row(s.x_t1, f[0]),
              row(s.x_t1, f[1]),
              row(s.x_t1, f[2])};
          ASSERT_FALSE(ccd::vertex_face_ccd(q, ccd::Accuracy::conservative, {}).hit)
              << "pair " << p.a << "," << p.b;
        }
      }
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          const auto a0 = ta[static_cast<std::size_t>(i)],
                     a1 = ta[static_cast<std::size_t>((i + 1) % 3)];
          const auto b0 = tb[static_cast<std::size_t>(j)],
                     b1 = tb[static_cast<std::size_t>((j + 1) % 3)];
          const ccd::EdgeEdgeQuery q{
              row(s.x_t0, a0),
              row(s.x_t0, a1),
              row(s.x_t0, b0),
              row(s.x_t0, b1),
              row(s.x_t1, a0),
              row(s.x_t1, a1),
              row(s.x_t1, b0),
              row(s.x_t1, b1)};
          ASSERT_FALSE(ccd::edge_edge_ccd(q, ccd::Accuracy::conservative, {}).hit)
              << "pair " << p.a << "," << p.b;
        }
      }
    }
    EXPECT_GT(checked, 0);
  }
}

TEST(ClusterChecks, RelativeBoxesOfARigidTranslation) {
  // Two parallel triangles 1 apart translating together by 100: their swept boxes overlap, the
  // relative ones (no relative motion) do not; 0.5 of contact distance each makes them touch.
  skinning::Positions x0(6, 3), x1(6, 3);
  x0 << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1;
  x1 = x0;
  x1.col(2).array() += 100.0;
  skinning::Mesh mesh = test::single_part_mesh(x0, (skinning::Triangles(2, 3) << 0, 1, 2, 3, 4, 5).finished());
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology ft(mesh, topo);
  EXPECT_FALSE(relative_boxes_overlap(ft, {0, 1}, x0, x1, 0.0));
  EXPECT_FALSE(relative_boxes_overlap(ft, {0, 1}, x0, x1, 0.49));
  EXPECT_TRUE(relative_boxes_overlap(ft, {0, 1}, x0, x1, 0.5));
  RelativeAabbFilter prepared;
  prepared.prepare(ft, x0, x1);
  EXPECT_FALSE(prepared.overlap({0, 1}, 0.0));
  EXPECT_FALSE(prepared.overlap({0, 1}, 0.49));
  EXPECT_TRUE(prepared.overlap({0, 1}, 0.5));
  // Closing in on each other: the relative boxes meet.
  skinning::Positions x2 = x0;
  x2.block(3, 2, 3, 1).array() -= 1.0;
  EXPECT_TRUE(relative_boxes_overlap(ft, {0, 1}, x0, x2, 0.0));
  prepared.prepare(ft, x0, x2);
  EXPECT_TRUE(prepared.overlap({0, 1}, 0.0));
}

TEST(ClusterChecks, EndBoxesAreApartOnlyWhenTheExactPointsAre) {
  // The filters compare the triangles' boxes at t = 0 and at t = 1 (relative_aabb.hpp): min and
  // max of doubles, exact. Every coordinate here lies in [1, 2) on a grid of a few ulps, so boxes
  // tie and cross at the last bit. Every pair a filter calls apart must be apart, exactly, on an
  // axis at t = 0 and at t = 1, the same way round (checked in long double), which by the
  // header's argument keeps them apart at every t in between.
  static_assert(std::numeric_limits<long double>::digits >= 64);
  constexpr double kUlp = 0x1p-52;
  std::mt19937 rng(20261127);
  std::uniform_int_distribution<int> grid(-6, 6);
  std::uniform_int_distribution<int> low_bits(0, 64);
  skinning::Positions x0(6, 3), x1(6, 3);
  x0 << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1;  // six distinct vertices at rest
  skinning::Mesh mesh =
      test::single_part_mesh(x0, (skinning::Triangles(2, 3) << 0, 1, 2, 3, 4, 5).finished());
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology ft(mesh, topo);
  ASSERT_EQ(ft.triangle(0), (std::array<std::int32_t, 3>{0, 1, 2}));
  ASSERT_EQ(ft.triangle(1), (std::array<std::int32_t, 3>{3, 4, 5}));
  const auto exactly_apart = [&] {
    for (Eigen::Index k = 0; k < 3; ++k) {
      // lo/hi[time][side]
      long double lo[2][2], hi[2][2];
      for (std::size_t time = 0; time < 2; ++time) {
        for (std::size_t side = 0; side < 2; ++side) {
          lo[time][side] = INFINITY;
          hi[time][side] = -INFINITY;
          const auto first = 3 * static_cast<Eigen::Index>(side);
          for (Eigen::Index v = first; v < first + 3; ++v) {
            const long double p = (time == 0 ? x0 : x1)(v, k);
            lo[time][side] = std::min(lo[time][side], p);
            hi[time][side] = std::max(hi[time][side], p);
          }
        }
      }
      if ((hi[0][0] < lo[0][1] && hi[1][0] < lo[1][1]) ||
          (hi[0][1] < lo[0][0] && hi[1][1] < lo[1][0])) {
        return true;
      }
    }
    return false;
  };
  int prepared_apart = 0, unprepared_apart = 0;
  RelativeAabbFilter prepared;
  for (int trial = 0; trial < 200000; ++trial) {
    for (Eigen::Index v = 0; v < 6; ++v) {
      for (Eigen::Index k = 0; k < 3; ++k) {
        x0(v, k) = 1.5 + grid(rng) * kUlp;
        x1(v, k) = x0(v, k) + (0.1 + low_bits(rng) * 0x1p-56);
      }
    }
    prepared.prepare(ft, x0, x1);
    const bool prepared_says = !prepared.overlap({0, 1}, 0.0);
    const bool unprepared_says = !relative_boxes_overlap(ft, {0, 1}, x0, x1, 0.0);
    ASSERT_EQ(prepared_says, unprepared_says) << "trial " << trial;
    if (prepared_says) {
      ++prepared_apart;
      ASSERT_TRUE(exactly_apart()) << "trial " << trial;
    }
    unprepared_apart += unprepared_says ? 1 : 0;
  }
  // Enough separated pairs for the check to mean something.
  EXPECT_GT(prepared_apart, 1000);
  EXPECT_GT(unprepared_apart, 1000);
}

TEST(ClusterChecks, EndBoxesWithWidthAndWhenCrossing) {
  // Two still triangles in z = 0, 0.7 apart on x (a: x ≤ 0, b: x ≥ 0.7): apart without width and
  // with 0.34 each (0.68 < 0.7); within reach with 0.36 each (0.72).
  skinning::Positions x0(6, 3);
  x0 << 0, 0, 0, -1, 1, 0, -1, -1, 0, 0.7, 0, 0, 1.7, 1, 0, 1.7, -1, 0;
  skinning::Mesh mesh =
      test::single_part_mesh(x0, (skinning::Triangles(2, 3) << 0, 1, 2, 3, 4, 5).finished());
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology ft(mesh, topo);
  RelativeAabbFilter prepared;
  prepared.prepare(ft, x0, x0);
  for (const double half_width : {0.0, 0.34}) {
    EXPECT_FALSE(relative_boxes_overlap(ft, {0, 1}, x0, x0, half_width)) << half_width;
    EXPECT_FALSE(prepared.overlap({0, 1}, half_width)) << half_width;
  }
  EXPECT_TRUE(relative_boxes_overlap(ft, {0, 1}, x0, x0, 0.36));
  EXPECT_TRUE(prepared.overlap({0, 1}, 0.36));
  // b carried across a over the interval (apart at t = 0, on the other side at t = 1): it meets.
  skinning::Positions x1 = x0;
  x1.block(3, 0, 3, 1).array() -= 3.0;
  prepared.prepare(ft, x0, x1);
  EXPECT_TRUE(relative_boxes_overlap(ft, {0, 1}, x0, x1, 0.0));
  EXPECT_TRUE(prepared.overlap({0, 1}, 0.0));
  // A coordinate that is not finite: never apart.
  skinning::Positions bad = x0;
  bad(0, 0) = std::numeric_limits<double>::quiet_NaN();
  prepared.prepare(ft, bad, bad);
  EXPECT_TRUE(relative_boxes_overlap(ft, {0, 1}, bad, bad, 0.0));
  EXPECT_TRUE(prepared.overlap({0, 1}, 0.0));
}

}  // namespace
}  // namespace skelcd::culling
