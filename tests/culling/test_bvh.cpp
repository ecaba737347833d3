// Bvh<N>: build structure (a permutation, nested ranges, balanced) and refit invariants (every
// leaf contains its triangles' vertices at both ends of the interval, exactly; every parent
// contains its children).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <span>
#include <string>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/method.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/exact_dop.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/culling/welded_character.hpp"
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
void check_structure(
    const Bvh<N>& bvh,
    const skinning::Triangles& triangles,
    const skinning::Positions& at,
    int leaf_size,
    BvhSplit split) {
  const auto num_triangles = static_cast<std::int32_t>(triangles.rows());
  // triangle_order is a permutation of the triangles.
  std::vector<std::int32_t> order(bvh.triangle_order().begin(), bvh.triangle_order().end());
  std::sort(order.begin(), order.end());
  std::vector<std::int32_t> all(static_cast<std::size_t>(num_triangles));
  std::iota(all.begin(), all.end(), 0);
  ASSERT_EQ(order, all);
  const auto centroid = [&](std::int32_t slot) {
    const std::int32_t f = bvh.triangle_order()[static_cast<std::size_t>(slot)];
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (Eigen::Index k = 0; k < 3; ++k) c += at.row(triangles(f, k)).transpose();
    return c;
  };
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
    // The children split the parent's range in two non-empty parts...
    EXPECT_EQ(l.begin, n.begin);
    EXPECT_EQ(l.end, r.begin);
    EXPECT_EQ(r.end, n.end);
    EXPECT_GT(l.size(), 0);
    EXPECT_GT(r.size(), 0);
    // ...at its median by count, or (the surface-area split, or its median fallback) by a plane
    // across one axis: no left centroid beyond a right one on it.
    if (split == BvhSplit::median) {
      EXPECT_EQ(l.size(), n.size() / 2);
    }
    bool separated = false;
    for (Eigen::Index k = 0; k < 3 && !separated; ++k) {
      double left_max = -std::numeric_limits<double>::infinity();
      double right_min = std::numeric_limits<double>::infinity();
      for (std::int32_t s = l.begin; s < l.end; ++s) left_max = std::max(left_max, centroid(s)[k]);
      for (std::int32_t s = r.begin; s < r.end; ++s)
        right_min = std::min(right_min, centroid(s)[k]);
      separated = left_max <= right_min;
    }
    EXPECT_TRUE(separated) << "node " << i;
  }
  EXPECT_EQ(leaves_total, num_triangles);
  // A median split is balanced: depth <= ceil(log2(#F / leaf_size)) + 1. The surface-area split
  // stops at depth 48 and continues at the median.
  const int balanced =
      static_cast<int>(std::ceil(std::log2(static_cast<double>(num_triangles) / leaf_size))) + 1;
  EXPECT_LE(bvh.depth(), split == BvhSplit::median ? balanced : 48 + balanced);
}

template <int N>
void check_refit(
    const Scene& s, int leaf_size, double min_separation, BvhSplit split = BvhSplit::surface_area) {
  const FeatureTopology topology(s.mesh, s.topology);
  Bvh<N> bvh(
      topology.welded_triangles(), s.x_t0, BvhOptions{.leaf_size = leaf_size, .split = split});
  check_structure(bvh, topology.welded_triangles(), s.x_t0, leaf_size, split);

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
  for (const BvhSplit split : {BvhSplit::surface_area, BvhSplit::median}) {
    for (const int leaf : {1, 2, 5}) check_refit<3>(s, leaf, 0.0, split);
    check_refit<3>(s, 1, 0.01, split);
  }
}

TEST(Bvh, KdopRefitContainsTrianglesAtBothEndsAndParentsContainChildren) {
  const Scene s = moving_tube();
  for (const BvhSplit split : {BvhSplit::surface_area, BvhSplit::median}) {
    for (const int leaf : {1, 2, 5}) check_refit<8>(s, leaf, 0.0, split);
    check_refit<8>(s, 3, 0.01, split);
  }
}

TEST(Bvh, RefitIsExactForVerticesFarFromTheOrigin) {
  // Coordinates around 1e6 with sub-ulp detail: the 16-DOP diagonals round, the boxes must not.
  Scene s = moving_tube();
  s.x_t0 = test::translated(s.x_t0 * 1e3, Eigen::Vector3d(1e6, -1e6, 3e5));
  s.x_t1 = test::translated(s.x_t1 * 1e3, Eigen::Vector3d(1e6 + 0.1, -1e6, 3e5));
  check_refit<8>(s, 1, 0.0);
  check_refit<3>(s, 1, 0.0);
  check_refit<3>(s, 1, 0.0, BvhSplit::median);
}

TEST(Bvh, SurfaceAreaSplitFindsTheSamePairsWithFewerVolumeTestsOnRealCharacters) {
  // The same DCD pairs and triangle tests and the same CCD contacts as the median tree — the
  // split changes which volumes are compared, never the answer — with fewer volume tests: the
  // siblings of a real character overlap less.
  for (const std::string file : {"CesiumMan.glb", "stormtrooper/stormtrooper.dae"}) {
    const test::WeldedCharacter character(file);
    const skinning::Mesh& mesh = *character.loaded.mesh;
    auto sah = make_method("bvh", mesh, character.topology);
    auto median =
        make_method("bvh", mesh, character.topology, {.bvh = {.split = BvhSplit::median}});
    std::int64_t bv_sah = 0, bv_median = 0, pairs = 0;
    const int n = character.loaded.motion()->num_samples();
    for (int k = 0; k + 1 < n; k += std::max(1, n / 6)) {
      const skinning::Positions x0 = character.sample(k);
      const skinning::Positions x1 = character.sample(k + 1);
      FrameResult a, b;
      sah->detect_dcd(x0, a);
      median->detect_dcd(x0, b);
      ASSERT_EQ(a.dcd_pairs, b.dcd_pairs) << file << " sample " << k;
      EXPECT_EQ(a.counters.tt_tests, b.counters.tt_tests) << file << " sample " << k;
      FrameResult c, d;
      sah->detect_ccd(x0, x1, c);
      median->detect_ccd(x0, x1, d);
      ASSERT_EQ(c.contacts, d.contacts) << file << " interval " << k;
      bv_sah += a.counters.bv_tests + c.counters.bv_tests;
      bv_median += b.counters.bv_tests + d.counters.bv_tests;
      pairs += static_cast<std::int64_t>(a.dcd_pairs.size() + c.contacts.size());
    }
    EXPECT_GT(pairs, 0) << file;
    EXPECT_LT(bv_sah, bv_median) << file;
  }
}

/// The surface-area tree by its plain definition (docs/culling.md "The hierarchy"), written for
/// clarity, not speed: for every axis whose centroid extent is positive and finite and every
/// split after bin j of 16, the items with bin <= j left, the cost area(left) · #left +
/// area(right) · #right of the two sides' boxes computed from the items themselves; the cheapest
/// (then the more balanced, then the first found) split, the items partitioned stably; else (no
/// split, depth 48, at most a bucket) the median along the longest centroid axis, ties by id.
class ReferenceSah {
 public:
  ReferenceSah(const skinning::Triangles& triangles, const skinning::Positions& x, int leaf_size)
      : leaf_size_(leaf_size) {
    for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
      Item item{
          Eigen::Vector3d::Zero(),
          x.row(triangles(f, 0)).transpose(),
          x.row(triangles(f, 0)).transpose(),
          static_cast<std::int32_t>(f)};
      for (Eigen::Index k = 0; k < 3; ++k) {
        const Eigen::Vector3d p = x.row(triangles(f, k)).transpose();
        item.centroid += p;
        item.lo = item.lo.cwiseMin(p);
        item.hi = item.hi.cwiseMax(p);
      }
      items_.push_back(item);
    }
    if (!items_.empty()) build(0, static_cast<std::int32_t>(items_.size()), 0);
    for (const Item& item : items_) order.push_back(item.id);
  }
  std::vector<BvhNode> nodes;
  std::vector<std::int32_t> order;

 private:
  struct Item {
    Eigen::Vector3d centroid, lo, hi;
    std::int32_t id;
  };
  static double area(const Eigen::Vector3d& l, const Eigen::Vector3d& h) {
    const Eigen::Vector3d d = (h - l).cwiseMax(0.0);
    return d.x() * d.y() + d.y() * d.z() + d.z() * d.x();
  }
  std::int32_t build(std::int32_t begin, std::int32_t end, int depth) {
    const auto index = static_cast<std::int32_t>(nodes.size());
    nodes.push_back({begin, end, 0});
    if (end - begin <= leaf_size_) return index;
    Eigen::Vector3d lo = items_[static_cast<std::size_t>(begin)].centroid, hi = lo;
    for (std::int32_t i = begin; i < end; ++i) {
      lo = lo.cwiseMin(items_[static_cast<std::size_t>(i)].centroid);
      hi = hi.cwiseMax(items_[static_cast<std::size_t>(i)].centroid);
    }
    const auto bin = [&](const Item& item, Eigen::Index axis) {
      const double t = (item.centroid[axis] - lo[axis]) * (16 / (hi[axis] - lo[axis]));
      return static_cast<int>(std::max(0.0, std::min(t, 15.0)));
    };
    double best_cost = std::numeric_limits<double>::infinity();
    std::int32_t best_imbalance = 0;
    Eigen::Index best_axis = -1;
    int best_bin = -1;
    if (depth < 48 && end - begin > bucket_size(leaf_size_)) {
      for (Eigen::Index axis = 0; axis < 3; ++axis) {
        const double extent = hi[axis] - lo[axis];
        if (!(extent > 0.0 && std::isfinite(extent))) continue;
        for (int j = 0; j < 15; ++j) {
          const double inf = std::numeric_limits<double>::infinity();
          Eigen::Vector3d llo = Eigen::Vector3d::Constant(inf), lhi = -llo;
          Eigen::Vector3d rlo = llo, rhi = lhi;
          std::int32_t left = 0, right = 0;
          for (std::int32_t i = begin; i < end; ++i) {
            const Item& item = items_[static_cast<std::size_t>(i)];
            if (bin(item, axis) <= j) {
              ++left;
              llo = llo.cwiseMin(item.lo);
              lhi = lhi.cwiseMax(item.hi);
            } else {
              ++right;
              rlo = rlo.cwiseMin(item.lo);
              rhi = rhi.cwiseMax(item.hi);
            }
          }
          if (left == 0 || right == 0) continue;
          const double cost = area(llo, lhi) * left + area(rlo, rhi) * right;
          const std::int32_t imbalance = std::abs(left - right);
          if (cost < best_cost || (cost == best_cost && imbalance < best_imbalance)) {
            best_cost = cost;
            best_imbalance = imbalance;
            best_axis = axis;
            best_bin = j;
          }
        }
      }
    }
    std::int32_t mid = 0;
    if (best_axis >= 0) {
      const auto middle = std::stable_partition(
          items_.begin() + begin, items_.begin() + end, [&](const Item& item) {
            return bin(item, best_axis) <= best_bin;
          });
      mid = static_cast<std::int32_t>(middle - items_.begin());
    } else {
      Eigen::Index axis = 0;
      (hi - lo).maxCoeff(&axis);
      mid = begin + (end - begin) / 2;
      std::nth_element(
          items_.begin() + begin,
          items_.begin() + mid,
          items_.begin() + end,
          [axis](const Item& s, const Item& t) {
            if (s.centroid[axis] != t.centroid[axis]) return s.centroid[axis] < t.centroid[axis];
            return s.id < t.id;
          });
    }
    build(begin, mid, depth + 1);
    const std::int32_t right = build(mid, end, depth + 1);
    nodes[static_cast<std::size_t>(index)].right = right;
    return index;
  }
  int leaf_size_;
  std::vector<Item> items_;
};

template <int N>
void expect_reference_tree(
    const skinning::Triangles& triangles, const skinning::Positions& x, const std::string& what) {
  for (const int leaf_size : {1, 3, 6}) {
    const Bvh<N> bvh(triangles, x, BvhOptions{leaf_size});
    const ReferenceSah reference(triangles, x, leaf_size);
    const auto nodes = bvh.nodes();
    ASSERT_EQ(nodes.size(), reference.nodes.size()) << what << " leaf " << leaf_size;
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      ASSERT_EQ(nodes[n].begin, reference.nodes[n].begin) << what << " node " << n;
      ASSERT_EQ(nodes[n].end, reference.nodes[n].end) << what << " node " << n;
      ASSERT_EQ(nodes[n].right, reference.nodes[n].right) << what << " node " << n;
    }
    EXPECT_TRUE(std::equal(
        bvh.triangle_order().begin(), bvh.triangle_order().end(), reference.order.begin()))
        << what << " leaf " << leaf_size;
  }
}

/// expect_reference_tree on real characters, a tube, a random soup, a flat strip and coincident
/// centroids.
void expect_reference_trees() {
  for (const std::string file : {"CesiumMan.glb", "stormtrooper/stormtrooper.dae"}) {
    const test::WeldedCharacter c(file);
    expect_reference_tree<3>(c.topology.welded_triangles, c.sample(0), file);
  }
  const Scene s = moving_tube();
  expect_reference_tree<8>(s.topology.welded_triangles, s.x_t1, "tube");
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  skinning::Positions soup(600, 3);
  skinning::Triangles soup_triangles(200, 3);
  for (Eigen::Index i = 0; i < soup.rows(); ++i) {
    const double scale = i % 7 == 0 ? 30.0 : 1.0;  // a few long triangles
    soup.row(i) << u(rng) * scale, u(rng) * u(rng), std::pow(u(rng), 3.0);
  }
  for (Eigen::Index f = 0; f < soup_triangles.rows(); ++f) {
    soup_triangles.row(f) << static_cast<std::int32_t>(3 * f), static_cast<std::int32_t>(3 * f + 1),
        static_cast<std::int32_t>(3 * f + 2);
  }
  expect_reference_tree<3>(soup_triangles, soup, "random soup");
  skinning::Positions strip = soup;
  strip.col(2).setZero();
  strip.col(1).setZero();  // every triangle a segment on the x axis: boxes of no area
  expect_reference_tree<3>(soup_triangles, strip, "flat strip");
  skinning::Positions same = soup;
  for (Eigen::Index f = 0; f < soup_triangles.rows(); ++f) {
    same.row(3 * f) << 1.0, 2.0, 3.0;
    same.row(3 * f + 1) << 1.0 + static_cast<double>(f), 2.0, 3.0;
    same.row(3 * f + 2) << 1.0 - static_cast<double>(f), 2.0, 3.0;  // every centroid (1, 2, 3)
  }
  expect_reference_tree<3>(soup_triangles, same, "coincident centroids");
}

TEST(Bvh, SurfaceAreaTreeIsTheOneItsPlainDefinitionBuilds) {
  // The build bins, skips empty bins and partitions through a spill of the smaller side; the
  // reference evaluates every split from the items. Real characters (shells, creases), a tube,
  // a random soup (splits of every balance), a flat strip (costs of zero: ties by balance) and
  // coincident centroids (no split: the median). Both binning loops: the AVX one where the CPU has
  // it, and the SSE2 one.
  for (const bool baseline : {false, true}) {
    SCOPED_TRACE(baseline ? "SSE2 binning" : "the CPU's binning");
    detail::force_bvh_baseline_binning(baseline);
    expect_reference_trees();
  }
  detail::force_bvh_baseline_binning(false);
}

TEST(Bvh, BinningLoopsBuildTheSameTreesOnRealMeshes) {
  // The AVX and SSE2 binning loops, and the split boxes handed down from the partition, on a
  // dense character and the stormtrooper's overlapping shells: the same nodes and order.
  for (const std::string file : {"CesiumMan-dense.glb", "stormtrooper/stormtrooper.dae"}) {
    const test::WeldedCharacter c(file);
    detail::force_bvh_baseline_binning(true);
    const Bvh<8> sse2(c.topology.welded_triangles, c.sample(0));
    detail::force_bvh_baseline_binning(false);
    const Bvh<8> best(c.topology.welded_triangles, c.sample(0));
    ASSERT_EQ(sse2.nodes().size(), best.nodes().size()) << file;
    for (std::size_t n = 0; n < sse2.nodes().size(); ++n) {
      ASSERT_EQ(sse2.nodes()[n].begin, best.nodes()[n].begin) << file << " node " << n;
      ASSERT_EQ(sse2.nodes()[n].end, best.nodes()[n].end) << file << " node " << n;
      ASSERT_EQ(sse2.nodes()[n].right, best.nodes()[n].right) << file << " node " << n;
    }
    EXPECT_TRUE(std::ranges::equal(sse2.triangle_order(), best.triangle_order())) << file;
  }
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

/// Every lane of a's wide nodes has b's bits (volumes, children, counts, nodes).
template <int N>
void expect_same_wide_nodes(const Bvh<N>& a, const Bvh<N>& b, const std::string& what) {
  const auto wa = a.wide_nodes();
  const auto wb = b.wide_nodes();
  ASSERT_EQ(wa.size(), wb.size()) << what;
  for (std::size_t n = 0; n < wa.size(); ++n) {
    ASSERT_EQ(wa[n].num_children, wb[n].num_children) << what << " wide node " << n;
    ASSERT_EQ(0, std::memcmp(wa[n].lo, wb[n].lo, sizeof(wa[n].lo))) << what << " wide node " << n;
    ASSERT_EQ(0, std::memcmp(wa[n].hi, wb[n].hi, sizeof(wa[n].hi))) << what << " wide node " << n;
    ASSERT_EQ(0, std::memcmp(wa[n].child, wb[n].child, sizeof(wa[n].child))) << what;
    ASSERT_EQ(0, std::memcmp(wa[n].count, wb[n].count, sizeof(wa[n].count))) << what;
  }
}

/// The triangles' float volumes by slot (Bvh::slot_lo / slot_hi) are their volumes in `bounds`
/// rounded outwards, and the three slots past the last are empty.
template <int N>
void expect_slot_volumes(
    const Bvh<N>& bvh, std::span<const Dop<N>> bounds, const std::string& what) {
  const auto order = bvh.triangle_order();
  for (int k = 0; k < Bvh<N>::kSlotAxes; ++k) {
    for (std::size_t s = 0; s < order.size(); ++s) {
      const Dop<N>& t = bounds[static_cast<std::size_t>(order[s])];
      ASSERT_EQ(bvh.slot_lo(k)[s], float_below(t.lo[static_cast<std::size_t>(k)]))
          << what << " slot " << s;
      ASSERT_EQ(bvh.slot_hi(k)[s], float_above(t.hi[static_cast<std::size_t>(k)]))
          << what << " slot " << s;
    }
    for (std::size_t s = order.size(); s < order.size() + 3; ++s) {
      ASSERT_EQ(bvh.slot_lo(k)[s], std::numeric_limits<float>::infinity()) << what;
      ASSERT_EQ(bvh.slot_hi(k)[s], -std::numeric_limits<float>::infinity()) << what;
    }
  }
}

template <int N>
void check_without_node_volumes(
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const Scene& s,
    std::span<const std::int32_t> subset,
    int leaf_size) {
  const FeatureTopology topology(s.mesh, s.topology);
  const std::string what = "N = " + std::to_string(N) + ", leaf " + std::to_string(leaf_size) +
                           ", subset " + std::to_string(subset.size());
  const BvhOptions with{.leaf_size = leaf_size};
  const BvhOptions without{.leaf_size = leaf_size, .node_volumes = false};
  Bvh<N> a = subset.empty() ? Bvh<N>(topology.welded_triangles(), x_t0, with)
                            : Bvh<N>(topology.welded_triangles(), x_t0, subset, with);
  Bvh<N> b = subset.empty() ? Bvh<N>(topology.welded_triangles(), x_t0, without)
                            : Bvh<N>(topology.welded_triangles(), x_t0, subset, without);
  // c: the cone methods' hierarchy, node volumes as floats rounded outwards.
  const BvhOptions floats{.leaf_size = leaf_size, .float_node_volumes = true};
  Bvh<N> c = subset.empty() ? Bvh<N>(topology.welded_triangles(), x_t0, floats)
                            : Bvh<N>(topology.welded_triangles(), x_t0, subset, floats);
  EXPECT_FALSE(a.node_bounds().empty()) << what;
  EXPECT_TRUE(b.node_bounds().empty()) << what;
  EXPECT_TRUE(c.node_bounds().empty()) << what;
  EXPECT_EQ(c.float_node_bounds().size(), a.nodes().size()) << what;
  EXPECT_TRUE(a.float_node_bounds().empty()) << what;
  // Each float node volume is its exact volume rounded outwards, bit for bit; the root's exact
  // volume is kept without double node volumes too (root_bounds: what `dynamic` bounds an atomic
  // cluster with).
  const auto expect_rounded_nodes = [&](const std::string& when) {
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      const double lo = a.node_bounds()[0].lo[k];
      const double hi = a.node_bounds()[0].hi[k];
      EXPECT_LT(lo, hi) << what << when;
      EXPECT_EQ(a.root_bounds().lo[k], lo) << what << when;
      EXPECT_EQ(b.root_bounds().lo[k], lo) << what << when;
      EXPECT_EQ(b.root_bounds().hi[k], hi) << what << when;
      EXPECT_EQ(c.root_bounds().lo[k], lo) << what << when;
      EXPECT_EQ(c.root_bounds().hi[k], hi) << what << when;
    }
    for (std::size_t n = 0; n < a.nodes().size(); ++n) {
      for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
        ASSERT_EQ(c.float_node_bounds()[n].lo[k], float_below(a.node_bounds()[n].lo[k]))
            << what << when << " node " << n;
        ASSERT_EQ(c.float_node_bounds()[n].hi[k], float_above(a.node_bounds()[n].hi[k]))
            << what << when << " node " << n;
      }
    }
  };
  // Each wide lane of a is its binary node's exact volume rounded outwards, bit for bit (refit()
  // forms the lanes from the slots' floats where those hold every axis, else by rounding).
  const auto expect_rounded_lanes = [&](const std::string& when) {
    std::int64_t lanes = 0;
    for (const WideBvhNode<N>& w : a.wide_nodes()) {
      for (int i = 0; i < w.num_children; ++i) {
        const auto& exact = a.node_bounds()[static_cast<std::size_t>(w.node[i])];
        for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
          ASSERT_EQ(w.lo[k][i], float_below(exact.lo[k])) << what << when << " lane " << i;
          ASSERT_EQ(w.hi[k][i], float_above(exact.hi[k])) << what << when << " lane " << i;
        }
        ++lanes;
      }
    }
    EXPECT_GT(lanes, 0) << what << when;
  };
  // Two refits in a row (the second must not keep anything of the first): an instant, then an
  // interval with a contact distance.
  FeatureBounds<N> bounds;
  static_vertex_bounds<N>(x_t0, bounds.vertices);
  bounds.derive(topology, false);
  a.refit(bounds.triangles);
  b.refit(bounds.triangles);
  c.refit(bounds.triangles);
  expect_same_wide_nodes(a, b, what + ", static");
  expect_same_wide_nodes(a, c, what + ", static, float node volumes");
  expect_slot_volumes<N>(a, bounds.triangles, what + ", static, with node volumes");
  expect_slot_volumes<N>(b, bounds.triangles, what + ", static, without");
  expect_slot_volumes<N>(c, bounds.triangles, what + ", static, float node volumes");
  expect_rounded_nodes(", static");
  expect_rounded_lanes(", static");
  swept_vertex_bounds<N>(x_t0, x_t1, 0.005, bounds.vertices);
  bounds.derive(topology);
  a.refit(bounds.triangles);
  b.refit(bounds.triangles);
  c.refit(bounds.triangles);
  expect_same_wide_nodes(a, b, what + ", swept");
  expect_same_wide_nodes(a, c, what + ", swept, float node volumes");
  expect_slot_volumes<N>(a, bounds.triangles, what + ", swept, with node volumes");
  expect_slot_volumes<N>(b, bounds.triangles, what + ", swept, without");
  expect_slot_volumes<N>(c, bounds.triangles, what + ", swept, float node volumes");
  expect_rounded_nodes(", swept");
  expect_rounded_lanes(", swept");
}

TEST(Bvh, WithoutNodeVolumesRefitGivesTheWideNodesTheSameBits) {
  // The `bvh`, `kdop` and `auto` hierarchies keep no binary node volumes (2·#F volumes less,
  // docs/culling.md "Bounded memory"): their traversals read only the wide copy, which must be
  // what the refit through the node volumes gives, bit for bit. The cone methods keep them as
  // floats (BvhOptions::float_node_volumes): each the exact one rounded outwards, and the same
  // wide copy.
  const Scene s = moving_tube();
  const std::vector<std::int32_t> all;
  const std::vector<std::int32_t> small{5, 9, 100, 3};
  std::vector<std::int32_t> half;
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(s.topology.welded_triangles.rows());
       f += 2) {
    half.push_back(f);
  }
  for (const int leaf : {1, 2, 5, 9}) {
    for (const auto& subset : {all, small, half}) {
      check_without_node_volumes<3>(s.x_t0, s.x_t1, s, subset, leaf);
      check_without_node_volumes<8>(s.x_t0, s.x_t1, s, subset, leaf);
    }
  }
  // Far from the origin, where the floats round most of the doubles' bits away.
  const skinning::Positions far_t0 =
      test::translated(s.x_t0 * 1e3, Eigen::Vector3d(1e6, -1e6, 3e5));
  const skinning::Positions far_t1 =
      test::translated(s.x_t1 * 1e3, Eigen::Vector3d(1e6 + 0.1, -1e6, 3e5));
  check_without_node_volumes<3>(far_t0, far_t1, s, all, 1);
  check_without_node_volumes<8>(far_t0, far_t1, s, all, 1);
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
