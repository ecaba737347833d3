// The feature stage: representative-triangle ownership, and the proof obligations of the CCD
// de-duplication — the hierarchy path produces exactly brute force's feature pairs, each once,
// and every feature pair left out is provably farther apart than the contact distance.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <utility>

#include "ccd/detail/relative_boxes.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/elementary.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/exact_dop.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/culling/welded_character.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using detail::FeatureStageBuild;

/// The feature stage's builds the tests run: AVX-512, AVX2 and the baseline SSE2 one
/// (ccd_candidates_from_triangle_pairs), each clamped to the widest the CPU has.
constexpr std::array<FeatureStageBuild, 3> kEveryBuild{
    FeatureStageBuild::avx512, FeatureStageBuild::avx2, FeatureStageBuild::baseline};

/// A build's name in a failure's trace.
const char* build_name(FeatureStageBuild build) {
  switch (build) {
    case FeatureStageBuild::baseline:
      return "baseline build";
    case FeatureStageBuild::avx2:
      return "AVX2 (or below)";
    case FeatureStageBuild::avx512:
      return "AVX-512 (or below)";
    case FeatureStageBuild::best:
      return "as the CPU allows";
  }
  return "?";
}

struct Scene {
  std::string name;
  skinning::Mesh mesh;
  skinning::Topology topology;
  skinning::Positions x_t0;
  skinning::Positions x_t1;
};

Scene make_scene(std::string name, skinning::Mesh mesh, auto&& move) {
  Scene s;
  s.name = std::move(name);
  s.mesh = std::move(mesh);
  s.topology = test::simple_topology(s.mesh);
  s.x_t0 = test::welded(s.topology, s.mesh.rest_positions);
  s.x_t1 = move(s.x_t0);
  return s;
}

/// A fan of `n` triangles around one centre vertex, winding 1.6 turns as a helical ramp whose
/// pitch reverses over the interval: the layers pass through each other. Every pair of triangles
/// shares the centre, so a broad phase that skipped adjacent triangle pairs would find nothing.
Scene helical_fan(int n) {
  const double turns = 1.6;
  auto ramp = [&](double pitch) {
    skinning::Positions x(n + 2, 3);
    x.row(0) << 0, 0, 0;
    for (int i = 0; i <= n; ++i) {
      const double theta = 2.0 * std::numbers::pi * turns * i / n;
      x.row(1 + i) << std::cos(theta), std::sin(theta), pitch * theta;
    }
    return x;
  };
  skinning::Triangles f(n, 3);
  for (int i = 0; i < n; ++i) f.row(i) << 0, 1 + i, 2 + i;
  Scene s;
  s.name = "helical fan";
  s.mesh = test::single_part_mesh(ramp(0.05), f, "fan");
  s.topology = test::simple_topology(s.mesh);
  s.x_t0 = test::welded(s.topology, ramp(0.05));
  s.x_t1 = test::welded(s.topology, ramp(-0.05));
  return s;
}

std::vector<Scene> scenes() {
  std::vector<Scene> out;
  out.push_back(make_scene("twisting tube", test::tube(10, 10, 0.5, 2.0), [](const auto& x) {
    return test::deformed(x, 1.0, 1.5);
  }));
  out.push_back(
      make_scene("sheet folding through itself", test::sheet(10, 6, 2.0, 1.0), [](const auto& x) {
        return test::folded(x, 1.0, 3.4);
      }));
  {
    auto a = test::uv_sphere(7, 9, 1.0);
    auto b = test::uv_sphere(6, 8, 0.7);
    b.rest_positions = test::translated(b.rest_positions, Eigen::Vector3d(2.0, 0.1, 0.05));
    out.push_back(make_scene("sphere moving into another", test::combine(a, b), [](const auto& x) {
      skinning::Positions y = x;
      for (Eigen::Index v = 0; v < y.rows(); ++v) {
        if (x(v, 0) > 1.05) y(v, 0) -= 1.2;  // the second sphere's vertices
      }
      return y;
    }));
  }
  {
    // A tube (part 0) moving sideways through a sheet (part 1) it starts beside.
    auto t = test::tube(8, 6, 0.3, 1.2);
    auto sh = test::sheet(6, 6, 2.0, 2.0);
    sh.rest_positions = test::translated(sh.rest_positions, Eigen::Vector3d(-1.0, -1.0, 0.6));
    out.push_back(make_scene("tube through a sheet", test::combine(t, sh), [](const auto& x) {
      skinning::Positions y = x;
      for (Eigen::Index v = 0; v < y.rows(); ++v) {
        if (x(v, 2) != 0.6) y(v, 2) += 0.05;  // the tube rises a little
        if (x(v, 2) == 0.6) y(v, 0) += 0.3;   // the sheet slides
      }
      return y;
    }));
  }
  out.push_back(helical_fan(24));
  {
    // Two vertices of a sheet at the same position: welding collapses the triangles that hold
    // both into segments (sides with id -1), which must not break ownership or the stages.
    auto m = test::sheet(8, 4, 2.0, 1.0);
    m.rest_positions.row(12) = m.rest_positions.row(11);
    m.rest_positions.row(30) = m.rest_positions.row(21);
    out.push_back(make_scene("sheet with collapsed triangles", m, [](const auto& x) {
      return test::folded(x, 1.0, 3.4);
    }));
  }
  return out;
}

template <int N>
struct Built {
  FeatureTopology topology;
  FeatureBounds<N> bounds;
};

template <int N>
Built<N> bounds_of(const Scene& s, double min_separation) {
  Built<N> b{FeatureTopology(s.mesh, s.topology), {}};
  swept_vertex_bounds<N>(s.x_t0, s.x_t1, 0.5 * min_separation, b.bounds.vertices);
  b.bounds.derive(b.topology);
  return b;
}

template <int N>
FeatureCandidates hierarchy_candidates(
    const Built<N>& b, const skinning::Positions& build_at, int leaf_size, Counters& counters) {
  Bvh<N> bvh(b.topology.welded_triangles(), build_at, BvhOptions{leaf_size});
  bvh.refit(b.bounds.triangles);
  TraversalScratch scratch;
  std::vector<TrianglePair> pairs;
  self_traverse<N>(bvh, b.bounds.triangles, scratch, pairs, counters.bv_tests);
  FeatureCandidates out;
  ccd_candidates_from_triangle_pairs<N>(b.topology, pairs, b.bounds, out, counters);
  return out;
}

template <class T>
bool has_duplicates(std::vector<T> v) {
  std::sort(v.begin(), v.end());
  return std::adjacent_find(v.begin(), v.end()) != v.end();
}

template <class T>
std::vector<T> sorted(std::vector<T> v) {
  std::sort(v.begin(), v.end());
  return v;
}

// --- an exact, independent proof that a left-out pair cannot touch ---------------------------

/// True when some axis of Dop<N> separates the convex hulls of `a` and `b` by more than
/// `distance`·|axis| in exact rational arithmetic: then every point of one is farther than
/// `distance` from every point of the other, at every time of the interval (linear motion keeps
/// each feature inside the hull of its positions at t0 and t1).
template <int N>
bool provably_apart_exact(
    const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double distance) {
  const mpq_class d(distance);
  for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
    const auto& axis = DopAxes<N>::kAxes[k];
    const int len2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
    auto range = [&](const std::vector<Eigen::Vector3d>& pts) {
      mpq_class lo = test::exact_projection<N>(pts[0].x(), pts[0].y(), pts[0].z(), k);
      mpq_class hi = lo;
      for (const auto& p : pts) {
        const mpq_class q = test::exact_projection<N>(p.x(), p.y(), p.z(), k);
        if (q < lo) lo = q;
        if (q > hi) hi = q;
      }
      return std::pair{lo, hi};
    };
    const auto [alo, ahi] = range(a);
    const auto [blo, bhi] = range(b);
    const mpq_class gap = std::max(mpq_class(blo - ahi), mpq_class(alo - bhi));
    if (gap > 0 && gap * gap > d * d * len2) return true;
  }
  return false;
}

/// True when some axis of Dop<N> separates the convex hulls of `a` and `b` by more than
/// `distance`·|axis|: then every point of one is farther than `distance` from every point of the
/// other, at every time of the interval (linear motion keeps each feature inside the hull of its
/// positions at t0 and t1). A floating-point pass with a generous error margin (projections of
/// at most three terms with unit coefficients: error < 4u·Σ|coordinates|; the margin is 100×)
/// settles clear cases; the rest are decided in exact rational arithmetic.
template <int N>
bool provably_apart(
    const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double distance) {
  double scale = 0.0;
  for (const auto* pts : {&a, &b}) {
    for (const auto& p : *pts) scale = std::max(scale, p.cwiseAbs().sum());
  }
  const double margin = 400.0 * std::numeric_limits<double>::epsilon() * scale;
  for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
    const auto& ax = DopAxes<N>::kAxes[k];
    const Eigen::Vector3d axis(ax[0], ax[1], ax[2]);
    auto range = [&](const std::vector<Eigen::Vector3d>& pts) {
      double lo = axis.dot(pts[0]);
      double hi = lo;
      for (const auto& p : pts) {
        lo = std::min(lo, axis.dot(p));
        hi = std::max(hi, axis.dot(p));
      }
      return std::pair{lo, hi};
    };
    const auto [alo, ahi] = range(a);
    const auto [blo, bhi] = range(b);
    const double gap = std::max(blo - ahi, alo - bhi);
    if (gap > distance * axis.norm() * (1.0 + 1e-12) + margin) return true;
  }
  return provably_apart_exact<N>(a, b, distance);
}

template <int N>
void check_left_out_pairs_are_apart(
    const Scene& s, const Built<N>& b, const FeatureCandidates& c, double min_separation) {
  const std::set<VertexFacePair> vf(c.vf.begin(), c.vf.end());
  const std::set<EdgeEdgePair> ee(c.ee.begin(), c.ee.end());
  auto points = [&](std::initializer_list<std::int32_t> ids) {
    std::vector<Eigen::Vector3d> p;
    for (const auto v : ids) {
      p.push_back(s.x_t0.row(v).transpose());
      p.push_back(s.x_t1.row(v).transpose());
    }
    return p;
  };
  const FeatureTopology& t = b.topology;
  std::int64_t left_out = 0;
  for (std::int32_t v = 0; v < t.num_vertices(); ++v) {
    for (std::int32_t f = 0; f < t.num_triangles(); ++f) {
      const auto& tri = t.triangle(f);
      if (v == tri[0] || v == tri[1] || v == tri[2] || t.vertex_face_excluded(v, f)) continue;
      if (vf.count({v, f})) continue;
      ++left_out;
      ASSERT_TRUE(provably_apart<N>(points({v}), points({tri[0], tri[1], tri[2]}), min_separation))
          << s.name << ": VF (" << v << ", " << f << ") was left out but may touch";
    }
  }
  for (std::int32_t e = 0; e < t.num_edges(); ++e) {
    for (std::int32_t g = e + 1; g < t.num_edges(); ++g) {
      const auto& ea = t.edge(e);
      const auto& eb = t.edge(g);
      if (ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1]) continue;
      if (t.edges_excluded(e, g) || ee.count({e, g})) continue;
      ++left_out;
      ASSERT_TRUE(provably_apart<N>(points({ea[0], ea[1]}), points({eb[0], eb[1]}), min_separation))
          << s.name << ": EE (" << e << ", " << g << ") was left out but may touch";
    }
  }
  EXPECT_GT(left_out, 0) << s.name << ": nothing was culled, the check proved nothing";
}

// --- tests -------------------------------------------------------------------------------------

TEST(FeatureTopology, EveryVertexAndEdgeHasExactlyOneOwner) {
  for (const Scene& s : scenes()) {
    const FeatureTopology t(s.mesh, s.topology);
    std::vector<int> vertex_owners(static_cast<std::size_t>(t.num_vertices()), 0);
    std::vector<int> edge_owners(static_cast<std::size_t>(t.num_edges()), 0);
    for (std::int32_t f = 0; f < t.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (t.owned(f) & (1u << k)) {
          const auto v = t.triangle(f)[static_cast<std::size_t>(k)];
          ++vertex_owners[static_cast<std::size_t>(v)];
          EXPECT_EQ(t.vertex_owner(v), f);
        }
        if (t.owned(f) & (1u << (3 + k))) {
          const auto e = t.face_edge(f, k);
          ++edge_owners[static_cast<std::size_t>(e)];
          EXPECT_EQ(t.edge_owner(e), f);
        }
      }
    }
    for (std::int32_t v = 0; v < t.num_vertices(); ++v) {
      EXPECT_EQ(vertex_owners[static_cast<std::size_t>(v)], t.vertex_owner(v) < 0 ? 0 : 1)
          << s.name;
    }
    for (const int n : edge_owners) EXPECT_EQ(n, 1) << s.name;
    if (s.name == "sheet with collapsed triangles") {
      int collapsed_sides = 0;
      for (std::int32_t f = 0; f < t.num_triangles(); ++f) {
        for (int k = 0; k < 3; ++k) collapsed_sides += t.face_edge(f, k) < 0;
      }
      EXPECT_GT(collapsed_sides, 0);
    }
  }
}

TEST(FeatureTopology, OwnedFeaturesListTheOwnedBitsInOrder) {
  for (const Scene& s : scenes()) {
    const FeatureTopology t(s.mesh, s.topology);
    for (std::int32_t f = 0; f < t.num_triangles(); ++f) {
      const FeatureTopology::OwnedFeatures& o = t.owned_features(f);
      EXPECT_EQ(o.corners, t.triangle(f)) << s.name << " triangle " << f;
      std::vector<std::int32_t> vertices, edges;
      for (int k = 0; k < 3; ++k) {
        if (t.owned(f) & (1u << k)) vertices.push_back(t.triangle(f)[static_cast<std::size_t>(k)]);
        if (t.owned(f) & (1u << (3 + k))) edges.push_back(t.face_edge(f, k));
      }
      ASSERT_EQ(o.num_vertices, vertices.size()) << s.name << " triangle " << f;
      ASSERT_EQ(o.num_edges, edges.size()) << s.name << " triangle " << f;
      for (std::size_t i = 0; i < vertices.size(); ++i) {
        EXPECT_EQ(o.vertices[i], vertices[i]);
        EXPECT_EQ(o.corners[o.vertex_slots[i]], vertices[i]) << s.name << " triangle " << f;
      }
      for (std::size_t i = 0; i < edges.size(); ++i) {
        EXPECT_EQ(o.edges[i], edges[i]);
        const std::array<std::int32_t, 2> ends{
            o.corners[o.edge_slots[i][0]], o.corners[o.edge_slots[i][1]]};
        EXPECT_EQ(ends, t.edge(edges[i])) << s.name << " triangle " << f;
      }
    }
  }
}

template <int N>
void check_hierarchy_matches_brute_force(double min_separation) {
  for (const Scene& s : scenes()) {
    const Built<N> b = bounds_of<N>(s, min_separation);
    Counters brute_counters;
    FeatureCandidates brute;
    ccd_candidates_brute_force<N>(b.topology, b.bounds, brute, brute_counters);
    EXPECT_FALSE(brute.vf.empty()) << s.name;
    EXPECT_FALSE(brute.ee.empty()) << s.name;
    EXPECT_FALSE(has_duplicates(brute.vf));
    EXPECT_FALSE(has_duplicates(brute.ee));
    check_left_out_pairs_are_apart<N>(s, b, brute, min_separation);
    for (const int leaf : {1, 4}) {
      // Build at t0 and, to show the tree shape does not matter, at a different pose.
      for (const auto* build_at : {&s.x_t0, &s.x_t1}) {
        Counters counters;
        const FeatureCandidates got = hierarchy_candidates<N>(b, *build_at, leaf, counters);
        SCOPED_TRACE(s.name + ", N = " + std::to_string(N) + ", leaf " + std::to_string(leaf));
        EXPECT_FALSE(has_duplicates(got.vf)) << "a VF pair was produced twice";
        EXPECT_FALSE(has_duplicates(got.ee)) << "an EE pair was produced twice";
        EXPECT_EQ(sorted(got.vf), brute.vf);
        EXPECT_EQ(sorted(got.ee), brute.ee);
        EXPECT_EQ(counters.feature_bv_tests <= brute_counters.feature_bv_tests, true);
        EXPECT_GT(counters.candidate_pairs, 0);
      }
    }
  }
}

TEST(CcdCandidates, AabbHierarchyProducesExactlyTheBruteForcePairsEachOnce) {
  check_hierarchy_matches_brute_force<3>(0.0);
}

TEST(CcdCandidates, KdopHierarchyProducesExactlyTheBruteForcePairsEachOnce) {
  check_hierarchy_matches_brute_force<8>(0.0);
}

TEST(CcdCandidates, WithAContactDistanceTooPairsWithinItAreNeverLeftOut) {
  check_hierarchy_matches_brute_force<3>(0.03);
  check_hierarchy_matches_brute_force<8>(0.03);
}

/// True when coordinate axis k separates point sets `a` and `b` (welded vertex ids) strictly at
/// t0 and at t1, the same way round: compared coordinate by coordinate, no arithmetic.
bool apart_on_an_axis_at_both_ends(
    const Scene& s, std::initializer_list<std::int32_t> a, std::initializer_list<std::int32_t> b) {
  for (Eigen::Index k = 0; k < 3; ++k) {
    for (const int below_side : {0, 1}) {
      bool apart = true;
      for (const auto* x : {&s.x_t0, &s.x_t1}) {
        for (const std::int32_t p : below_side == 0 ? a : b) {
          for (const std::int32_t q : below_side == 0 ? b : a)
            apart = apart && (*x)(p, k) < (*x)(q, k);
        }
      }
      if (apart) return true;
    }
  }
  return false;
}

/// True when a face diagonal (x ± y, y ± z, z ± x) separates point sets `a` and `b` (welded
/// vertex ids) strictly at t0 and at t1, the same way round, each projection rounded as a
/// double: rounding is monotone, so rounded projections strictly apart are exact ones strictly
/// apart.
bool apart_on_a_diagonal_at_both_ends(
    const Scene& s, std::initializer_list<std::int32_t> a, std::initializer_list<std::int32_t> b) {
  const auto project = [](const skinning::Positions& x, std::int32_t v, int d) {
    const double px = x(v, 0), py = x(v, 1), pz = x(v, 2);
    switch (d) {
      case 0:
        return px + py;
      case 1:
        return px - py;
      case 2:
        return py + pz;
      case 3:
        return py - pz;
      case 4:
        return pz + px;
      default:
        return pz - px;
    }
  };
  for (int d = 0; d < 6; ++d) {
    for (const int below_side : {0, 1}) {
      bool apart = true;
      for (const auto* x : {&s.x_t0, &s.x_t1}) {
        for (const std::int32_t p : below_side == 0 ? a : b) {
          for (const std::int32_t q : below_side == 0 ? b : a)
            apart = apart && project(*x, p, d) < project(*x, q, d);
        }
      }
      if (apart) return true;
    }
  }
  return false;
}

TEST(CcdCandidates, EndsOnTheAxesAndDiagonalsDropOnlyPairsThatNeverTouchAndMatchBruteForce) {
  // Without a contact distance the AABB methods test a feature pair on its features' boxes at
  // t0 and at t1 instead of their swept boxes, then on the face diagonals at both ends: every
  // pair the swept boxes keep or drop, less those an axis or a face diagonal separates at both
  // ends. The dropped pairs are checked against the exact kernels.
  std::int64_t dropped = 0;
  std::int64_t dropped_by_diagonal = 0;
  std::int64_t dropped_by_feature_diagonal = 0;  // whose owner triangles no diagonal separates
  for (const Scene& s : scenes()) {
    SCOPED_TRACE(s.name);
    const Built<3> b = bounds_of<3>(s, 0.0);
    const IntervalEnds ends = interval_ends(0.0, s.x_t0, s.x_t1);
    ASSERT_EQ(ends.x_t0, &s.x_t0);
    EXPECT_EQ(interval_ends(0.01, s.x_t0, s.x_t1).x_t0, nullptr);
    Counters swept_counters, ends_counters;
    FeatureCandidates swept, by_ends;
    ccd_candidates_brute_force<3>(b.topology, b.bounds, swept, swept_counters);
    ccd_candidates_brute_force<3>(b.topology, b.bounds, by_ends, ends_counters, nullptr, ends);
    // The same pairs are asked about; the ends keep a subset of what the swept boxes keep.
    EXPECT_EQ(ends_counters.feature_bv_tests, swept_counters.feature_bv_tests);
    EXPECT_TRUE(
        std::includes(swept.vf.begin(), swept.vf.end(), by_ends.vf.begin(), by_ends.vf.end()));
    EXPECT_TRUE(
        std::includes(swept.ee.begin(), swept.ee.end(), by_ends.ee.begin(), by_ends.ee.end()));
    const std::set<VertexFacePair> kept_vf(by_ends.vf.begin(), by_ends.vf.end());
    const std::set<EdgeEdgePair> kept_ee(by_ends.ee.begin(), by_ends.ee.end());
    const ccd::CcdOptions options;
    for (const VertexFacePair& p : swept.vf) {
      if (kept_vf.count(p)) continue;
      ++dropped;
      const auto& f = b.topology.triangle(p.face);
      if (!apart_on_an_axis_at_both_ends(s, {p.vertex}, {f[0], f[1], f[2]})) {
        ++dropped_by_diagonal;
        EXPECT_TRUE(apart_on_a_diagonal_at_both_ends(s, {p.vertex}, {f[0], f[1], f[2]}))
            << "VF (" << p.vertex << ", " << p.face << ")";
        const auto& owner = b.topology.triangle(b.topology.vertex_owner(p.vertex));
        if (!apart_on_a_diagonal_at_both_ends(
                s, {owner[0], owner[1], owner[2]}, {f[0], f[1], f[2]})) {
          ++dropped_by_feature_diagonal;
        }
      }
      const auto q = vertex_face_query(s.x_t0, s.x_t1, p.vertex, s.x_t0, s.x_t1, f);
      EXPECT_FALSE(ccd::vertex_face_ccd(q, ccd::Accuracy::exact, options).hit)
          << "VF (" << p.vertex << ", " << p.face << ") was dropped but touches";
    }
    for (const EdgeEdgePair& p : swept.ee) {
      if (kept_ee.count(p)) continue;
      ++dropped;
      const auto& ea = b.topology.edge(p.a);
      const auto& eb = b.topology.edge(p.b);
      if (!apart_on_an_axis_at_both_ends(s, {ea[0], ea[1]}, {eb[0], eb[1]})) {
        ++dropped_by_diagonal;
        EXPECT_TRUE(apart_on_a_diagonal_at_both_ends(s, {ea[0], ea[1]}, {eb[0], eb[1]}))
            << "EE (" << p.a << ", " << p.b << ")";
        const auto& ta = b.topology.triangle(b.topology.edge_owner(p.a));
        const auto& tb = b.topology.triangle(b.topology.edge_owner(p.b));
        if (!apart_on_a_diagonal_at_both_ends(s, {ta[0], ta[1], ta[2]}, {tb[0], tb[1], tb[2]})) {
          ++dropped_by_feature_diagonal;
        }
      }
      const auto q = edge_edge_query(s.x_t0, s.x_t1, ea, s.x_t0, s.x_t1, eb);
      EXPECT_FALSE(ccd::edge_edge_ccd(q, ccd::Accuracy::exact, options).hit)
          << "EE (" << p.a << ", " << p.b << ") was dropped but touches";
    }
    // A hierarchy hands over the owners of exactly these pairs, each once — the feature stage's
    // AVX2 build (where the CPU has it) and its baseline build alike.
    for (const int leaf : {1, 4}) {
      Bvh<3> bvh(b.topology.welded_triangles(), s.x_t0, BvhOptions{leaf});
      bvh.refit(b.bounds.triangles);
      TraversalScratch scratch;
      std::vector<TrianglePair> pairs;
      Counters counters;
      self_traverse<3>(bvh, b.bounds.triangles, scratch, pairs, counters.bv_tests);
      for (const FeatureStageBuild build : kEveryBuild) {
        SCOPED_TRACE(build_name(build));
        detail::force_feature_stage_build(build);
        FeatureCandidates got;
        ccd_candidates_from_triangle_pairs<3>(
            b.topology, pairs, b.bounds, got, counters, nullptr, ends);
        detail::force_feature_stage_build(FeatureStageBuild::best);
        EXPECT_FALSE(has_duplicates(got.vf));
        EXPECT_FALSE(has_duplicates(got.ee));
        EXPECT_EQ(sorted(got.vf), by_ends.vf);
        EXPECT_EQ(sorted(got.ee), by_ends.ee);
      }
    }
  }
  // The scenes move their parts past each other: some pairs are dropped, some by the diagonals
  // alone, and some by the features' diagonals where their triangles' do not separate them
  // (else this proved nothing).
  EXPECT_GT(dropped, 0);
  EXPECT_GT(dropped_by_diagonal, 0);
  EXPECT_GT(dropped_by_feature_diagonal, 0);
}

/// The kernels' relative stage on every feature pair of `kept` and of `swept` (the same scene's
/// pairs by their swept boxes): how many of each it finds apart at both ends on the nine
/// directions (ccd::detail::ends_apart).
std::pair<std::int64_t, std::int64_t> ends_apart_counts(
    const FeatureTopology& t,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const FeatureCandidates& kept,
    const FeatureCandidates& swept) {
  const auto count = [&](const FeatureCandidates& c) {
    std::int64_t apart = 0;
    for (const VertexFacePair& p : c.vf) {
      const auto q = vertex_face_query(x_t0, x_t1, p.vertex, x_t0, x_t1, t.triangle(p.face));
      apart += ccd::detail::ends_apart<1>(
          {&q.v_t0, &q.f0_t0, &q.f1_t0, &q.f2_t0}, {&q.v_t1, &q.f0_t1, &q.f1_t1, &q.f2_t1});
    }
    for (const EdgeEdgePair& p : c.ee) {
      const auto q = edge_edge_query(x_t0, x_t1, t.edge(p.a), x_t0, x_t1, t.edge(p.b));
      apart += ccd::detail::ends_apart<2>(
          {&q.ea0_t0, &q.ea1_t0, &q.eb0_t0, &q.eb1_t0},
          {&q.ea0_t1, &q.ea1_t1, &q.eb0_t1, &q.eb1_t1});
    }
    return apart;
  };
  return {count(kept), count(swept)};
}

TEST(CcdCandidates, TheKernelsRelativeStageRejectsNoFeaturePairTheFeatureStageKeeps) {
  // Without a contact distance the methods leave the conservative kernels' relative stage out
  // (culling/method.cpp): its test, nine directions apart at both ends, is the one the feature
  // stage makes on every feature pair it keeps, with the same roundings. So it must find none
  // of the kept pairs apart — on the generated scenes and on real characters between two
  // samples (the stormtrooper's overlapping shells, CesiumMan's walk), from a k-DOP hierarchy's
  // pairs in both builds of the feature stage and from brute force — while it does find some
  // of the pairs the swept boxes alone keep (else this proved nothing).
  struct Case {
    std::string name;
    skinning::Mesh mesh;
    skinning::Topology topology;
    skinning::Positions x_t0, x_t1;
  };
  std::vector<Case> cases;
  for (const Scene& s : scenes()) cases.push_back({s.name, s.mesh, s.topology, s.x_t0, s.x_t1});
  for (const auto& [file, k] :
       {std::pair{"stormtrooper/stormtrooper.dae", 7}, std::pair{"CesiumMan.glb", 10}}) {
    const test::WeldedCharacter c(file);
    cases.push_back({file, *c.loaded.mesh, c.topology, c.sample(k), c.sample(k + 3)});
  }
  std::int64_t kept_total = 0;
  std::int64_t swept_apart = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const FeatureTopology t(c.mesh, c.topology);
    FeatureBounds<8> bounds;
    swept_vertex_bounds<8>(c.x_t0, c.x_t1, 0.0, bounds.vertices);
    bounds.derive(t);
    const IntervalEnds ends = interval_ends(0.0, c.x_t0, c.x_t1);
    Counters counters;
    FeatureCandidates swept, brute;
    ccd_candidates_brute_force<8>(t, bounds, swept, counters);
    ccd_candidates_brute_force<8>(t, bounds, brute, counters, nullptr, ends);
    Bvh<8> bvh(t.welded_triangles(), c.x_t0, BvhOptions{4});
    bvh.refit(bounds.triangles);
    TraversalScratch scratch;
    std::vector<TrianglePair> pairs;
    self_traverse<8>(bvh, bounds.triangles, scratch, pairs, counters.bv_tests);
    for (const FeatureStageBuild build : kEveryBuild) {
      SCOPED_TRACE(build_name(build));
      detail::force_feature_stage_build(build);
      FeatureCandidates got;
      ccd_candidates_from_triangle_pairs<8>(t, pairs, bounds, got, counters, nullptr, ends);
      detail::force_feature_stage_build(FeatureStageBuild::best);
      const auto [apart, unused] = ends_apart_counts(t, c.x_t0, c.x_t1, got, FeatureCandidates{});
      EXPECT_EQ(apart, 0);
      EXPECT_EQ(sorted(got.vf), brute.vf);
      EXPECT_EQ(sorted(got.ee), brute.ee);
    }
    const auto [apart, of_swept] = ends_apart_counts(t, c.x_t0, c.x_t1, brute, swept);
    EXPECT_EQ(apart, 0) << "brute force";
    kept_total += static_cast<std::int64_t>(brute.vf.size() + brute.ee.size());
    swept_apart += of_swept;
  }
  EXPECT_GT(kept_total, 1000);
  EXPECT_GT(swept_apart, 1000);
}

TEST(CcdCandidates, FanSharingOneVertexStillYieldsItsCrossings) {
  // Every triangle pair of the fan shares the centre: skipping adjacent pairs would miss all.
  const Scene s = helical_fan(24);
  const Built<3> b = bounds_of<3>(s, 0.0);
  Counters counters;
  const auto got = hierarchy_candidates<3>(b, s.x_t0, 1, counters);
  EXPECT_GT(got.vf.size(), 20u);
  EXPECT_GT(got.ee.size(), 20u);
  for (const auto& p : got.vf) EXPECT_NE(p.vertex, 0) << "the centre is a corner of every face";
}

TEST(CcdCandidates, PartExclusionsApplyPerFeatureAndRespectSharedVertices) {
  // Two sheets in parts 0 and 1 meet along the seam x = 1 (welded across the parts); a tube in
  // part 2 crosses the seam. Excluding (0, 1) and (2, 2): no pair of a part-0-only feature with
  // a part-1-only one, none within part 2 — but a seam vertex (parts 0 and 1) is still tested
  // against faces of either sheet, since (0, 0) and (1, 1) are allowed.
  auto a = test::sheet(4, 4, 1.0, 1.0);
  auto c = test::sheet(4, 4, 1.0, 1.0);
  c.rest_positions = test::translated(c.rest_positions, Eigen::Vector3d(1.0, 0.0, 0.0));
  auto cross = test::tube(6, 4, 0.2, 1.0);
  cross.rest_positions = test::translated(cross.rest_positions, Eigen::Vector3d(1.0, 0.5, -0.5));
  auto mesh = test::combine(test::combine(a, c), cross);
  mesh.excluded_part_pairs = {{0, 1}, {2, 2}};
  const Scene s = make_scene("parts", mesh, [](const auto& x) {
    skinning::Positions y = x;
    for (Eigen::Index v = 0; v < y.rows(); ++v) {
      y(v, 0) += 0.3 * std::sin(5.0 * x(v, 1));
      y(v, 2) += 0.3 * std::sin(4.0 * x(v, 0));
    }
    return y;
  });
  for (const auto* name : {"aabb", "kdop"}) {
    SCOPED_TRACE(name);
    const bool aabb = std::string(name) == "aabb";
    FeatureCandidates brute, got;
    FeatureTopology t(s.mesh, s.topology);
    if (aabb) {
      const Built<3> b = bounds_of<3>(s, 0.0);
      Counters c1, c2;
      ccd_candidates_brute_force<3>(b.topology, b.bounds, brute, c1);
      got = hierarchy_candidates<3>(b, s.x_t0, 2, c2);
    } else {
      const Built<8> b = bounds_of<8>(s, 0.0);
      Counters c1, c2;
      ccd_candidates_brute_force<8>(b.topology, b.bounds, brute, c1);
      got = hierarchy_candidates<8>(b, s.x_t0, 2, c2);
    }
    EXPECT_EQ(sorted(got.vf), brute.vf);
    EXPECT_EQ(sorted(got.ee), brute.ee);
    // Independent restatement of the rule on the result.
    auto vertex_parts = [&](std::int32_t v) {
      std::set<std::int32_t> parts;
      for (std::int32_t f = 0; f < t.num_triangles(); ++f) {
        const auto& tri = t.triangle(f);
        if (v == tri[0] || v == tri[1] || v == tri[2]) parts.insert(t.face_part(f));
      }
      return parts;
    };
    auto allowed = [&](std::int32_t p, std::int32_t q) {
      return !((std::min(p, q) == 0 && std::max(p, q) == 1) || (p == 2 && q == 2));
    };
    bool seam_pair_seen = false;
    for (const auto& p : got.vf) {
      const auto parts = vertex_parts(p.vertex);
      const std::int32_t q = t.face_part(p.face);
      EXPECT_TRUE(std::any_of(parts.begin(), parts.end(), [&](auto pp) { return allowed(pp, q); }))
          << "VF (" << p.vertex << ", " << p.face << ") crosses an excluded part pair";
      if (parts.size() == 2) seam_pair_seen = true;
    }
    EXPECT_TRUE(seam_pair_seen) << "the scene should exercise a vertex shared by two parts";
    EXPECT_TRUE(t.has_exclusions());
  }
}

// The feature stage as it was written before it wrote its candidates without branches, pair by
// pair and test by test: the reference the stage must match exactly — the same candidates in the
// same order, the same counters.
template <int N>
void reference_feature_stage(
    const FeatureTopology& t,
    std::span<const TrianglePair> pairs,
    const FeatureBounds<N>& bounds,
    FeatureCandidates& out,
    Counters& counters) {
  const auto at = [](std::int32_t i) { return static_cast<std::size_t>(i); };
  for (const TrianglePair& p : pairs) {
    if (t.owned_pairs_excluded(p.a, p.b)) continue;
    ++counters.candidate_pairs;
    for (const auto& [owner, face] : {std::pair{p.a, p.b}, std::pair{p.b, p.a}}) {
      const auto& o = t.owned_features(owner);
      const auto& corners = t.triangle(face);
      for (std::size_t k = 0; k < o.num_vertices; ++k) {
        const std::int32_t v = o.vertices[k];
        if (v == corners[0] || v == corners[1] || v == corners[2]) continue;
        if (t.vertex_face_excluded(v, face)) continue;
        ++counters.feature_bv_tests;
        if (bounds.vertices[at(v)].overlaps(bounds.triangles[at(face)]))
          out.vf.push_back({v, face});
      }
    }
    const auto& a = t.owned_features(p.a);
    const auto& b = t.owned_features(p.b);
    for (std::size_t i = 0; i < a.num_edges; ++i) {
      for (std::size_t j = 0; j < b.num_edges; ++j) {
        const auto& ea = t.edge(a.edges[i]);
        const auto& eb = t.edge(b.edges[j]);
        if (ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1]) continue;
        if (t.edges_excluded(a.edges[i], b.edges[j])) continue;
        ++counters.feature_bv_tests;
        if (bounds.edges[at(a.edges[i])].overlaps(bounds.edges[at(b.edges[j])])) {
          out.ee.push_back({std::min(a.edges[i], b.edges[j]), std::max(a.edges[i], b.edges[j])});
        }
      }
    }
  }
}

template <int N>
void expect_feature_stage_matches_reference(const Scene& s, double min_separation) {
  SCOPED_TRACE(s.name + ", N = " + std::to_string(N));
  const Built<N> b = bounds_of<N>(s, min_separation);
  Bvh<N> bvh(b.topology.welded_triangles(), s.x_t0);
  bvh.refit(b.bounds.triangles);
  TraversalScratch scratch;
  std::vector<TrianglePair> pairs;
  std::int64_t bv_tests = 0;
  self_traverse<N>(bvh, b.bounds.triangles, scratch, pairs, bv_tests);
  // Both orders within a pair, and every triangle pair too (most do not overlap), in several
  // chunk alignments: the stage takes any pairs.
  std::vector<TrianglePair> swapped = pairs;
  for (auto& p : swapped) std::swap(p.a, p.b);
  std::vector<TrianglePair> all;
  for (std::int32_t f = 0; f < b.topology.num_triangles(); ++f) {
    for (std::int32_t g = f + 1; g < b.topology.num_triangles(); ++g) all.push_back({f, g});
  }
  for (const auto* list : {&pairs, &swapped, &all}) {
    ASSERT_GT(list->size(), 200u);
    for (const std::size_t skip : {std::size_t{0}, std::size_t{37}}) {
      const std::span<const TrianglePair> in(list->data() + skip, list->size() - skip);
      FeatureCandidates want, got;
      Counters want_counters, got_counters;
      reference_feature_stage<N>(b.topology, in, b.bounds, want, want_counters);
      ccd_candidates_from_triangle_pairs<N>(b.topology, in, b.bounds, got, got_counters);
      EXPECT_FALSE(want.vf.empty());
      EXPECT_FALSE(want.ee.empty());
      EXPECT_EQ(got.vf, want.vf);
      EXPECT_EQ(got.ee, want.ee);
      EXPECT_EQ(got_counters.feature_bv_tests, want_counters.feature_bv_tests);
      EXPECT_EQ(got_counters.candidate_pairs, want_counters.candidate_pairs);
    }
  }
}

TEST(CcdCandidates, FeatureStageMatchesThePairByPairReferenceExactly) {
  for (const Scene& s : scenes()) {
    expect_feature_stage_matches_reference<3>(s, 0.0);
    expect_feature_stage_matches_reference<8>(s, 0.0);
    expect_feature_stage_matches_reference<3>(s, 0.05);
  }
  // With part exclusions (the other instantiation of the stage).
  auto a = test::sheet(6, 6, 1.0, 1.0);
  auto c = test::sheet(6, 6, 1.0, 1.0);
  c.rest_positions = test::translated(c.rest_positions, Eigen::Vector3d(1.0, 0.0, 0.0));
  auto cross = test::tube(6, 6, 0.2, 1.0);
  cross.rest_positions = test::translated(cross.rest_positions, Eigen::Vector3d(1.0, 0.5, -0.5));
  auto mesh = test::combine(test::combine(a, c), cross);
  mesh.excluded_part_pairs = {{0, 1}, {2, 2}};
  const Scene parts = make_scene("parts", mesh, [](const auto& x) {
    skinning::Positions y = x;
    for (Eigen::Index v = 0; v < y.rows(); ++v) {
      y(v, 0) += 0.3 * std::sin(5.0 * x(v, 1));
      y(v, 2) += 0.3 * std::sin(4.0 * x(v, 0));
    }
    return y;
  });
  ASSERT_TRUE(FeatureTopology(parts.mesh, parts.topology).has_exclusions());
  expect_feature_stage_matches_reference<3>(parts, 0.0);
  expect_feature_stage_matches_reference<8>(parts, 0.0);
}

TEST(DcdCandidates, HierarchyPathMatchesBruteForceAndKeepsSharedVertexPairs) {
  for (const Scene& s : scenes()) {
    const FeatureTopology t(s.mesh, s.topology);
    std::vector<Dop<3>> vb;
    static_vertex_bounds<3>(s.x_t1, vb);
    FeatureBounds<3> bounds;
    bounds.vertices = vb;
    bounds.derive(t, false);
    Counters brute_counters, counters;
    std::vector<TrianglePair> brute, got;
    dcd_candidates_brute_force<3>(t, bounds.triangles, brute, brute_counters);
    Bvh<3> bvh(t.welded_triangles(), s.x_t0, BvhOptions{3});
    bvh.refit(bounds.triangles);
    TraversalScratch scratch;
    self_traverse<3>(bvh, bounds.triangles, scratch, got, counters.bv_tests);
    dcd_filter_triangle_pairs(t, got, counters);
    EXPECT_EQ(sorted(got), brute) << s.name;
    EXPECT_EQ(counters.candidate_pairs, static_cast<std::int64_t>(got.size()));
    const auto nf = static_cast<std::int64_t>(t.num_triangles());
    EXPECT_EQ(brute_counters.candidate_pairs, nf * (nf - 1) / 2);
    // Pairs sharing one or two vertices are kept for the exact shared-corner test.
    const auto shared = std::count_if(brute.begin(), brute.end(), [&](const TrianglePair& p) {
      int n = 0;
      (void)t.shared_corners(p.a, p.b, n);
      return n > 0;
    });
    EXPECT_GT(shared, 0) << s.name;
  }
}

// The DCD's triangle volumes straight from the corners are the vertex volumes' unions bit for
// bit, for AABBs and 16-DOPs, on every generated scene and on a posed real character (whose
// coordinates are not the round numbers of a generated one).
template <int N>
void expect_static_triangles_equal_derived(
    const FeatureTopology& t, const skinning::Positions& x, const std::string& what) {
  FeatureBounds<N> derived;
  static_vertex_bounds<N>(x, derived.vertices);
  derived.derive(t, false);
  FeatureBounds<N> direct;
  direct.vertices.assign(3, Dop<N>::empty());
  direct.static_triangles(t, x);
  EXPECT_TRUE(direct.vertices.empty()) << what;
  ASSERT_EQ(direct.triangles.size(), derived.triangles.size()) << what;
  for (std::size_t f = 0; f < derived.triangles.size(); ++f) {
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      ASSERT_EQ(
          std::bit_cast<std::uint64_t>(direct.triangles[f].lo[k]),
          std::bit_cast<std::uint64_t>(derived.triangles[f].lo[k]))
          << what << " triangle " << f;
      ASSERT_EQ(
          std::bit_cast<std::uint64_t>(direct.triangles[f].hi[k]),
          std::bit_cast<std::uint64_t>(derived.triangles[f].hi[k]))
          << what << " triangle " << f;
    }
  }
}

TEST(FeatureBounds, StaticTrianglesFromTheCornersAreTheDerivedVolumesBitForBit) {
  for (const Scene& s : scenes()) {
    const FeatureTopology t(s.mesh, s.topology);
    expect_static_triangles_equal_derived<3>(t, s.x_t1, s.name);
    expect_static_triangles_equal_derived<8>(t, s.x_t1, s.name);
  }
  const test::WeldedCharacter trooper("stormtrooper/stormtrooper.dae");
  const FeatureTopology t(*trooper.loaded.mesh, trooper.topology);
  const skinning::Positions x = trooper.sample(7);
  expect_static_triangles_equal_derived<3>(t, x, "stormtrooper");
  expect_static_triangles_equal_derived<8>(t, x, "stormtrooper");
}

// The CCD's triangle volumes straight from the six corners (no contact distance; `bvh` and
// `kdop` without vertex volumes): on the coordinate axes the derived volumes bit for bit; on the
// 16-DOP's diagonals one step outwards from the corners' extreme projections, bit for bit, never
// inside the derived volumes (so they hold the motion wherever those do) and at most one step
// wider at each end — on every generated scene and on a real character's interval.
template <int N>
void expect_swept_triangles_hold_derived(
    const FeatureTopology& t,
    const skinning::Positions& x0,
    const skinning::Positions& x1,
    const std::string& what) {
  FeatureBounds<N> derived;
  swept_vertex_bounds<N>(x0, x1, 0.0, derived.vertices);
  derived.derive(t, false);
  FeatureBounds<N> direct;
  direct.vertices.assign(3, Dop<N>::empty());
  direct.swept_triangles(t, x0, x1);
  EXPECT_TRUE(direct.vertices.empty()) << what;
  ASSERT_EQ(direct.triangles.size(), derived.triangles.size()) << what;
  for (std::size_t f = 0; f < derived.triangles.size(); ++f) {
    const Dop<N>& d = direct.triangles[f];
    const Dop<N>& e = derived.triangles[f];
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      if (k < 3) {
        ASSERT_EQ(std::bit_cast<std::uint64_t>(d.lo[k]), std::bit_cast<std::uint64_t>(e.lo[k]))
            << what << " triangle " << f;
        ASSERT_EQ(std::bit_cast<std::uint64_t>(d.hi[k]), std::bit_cast<std::uint64_t>(e.hi[k]))
            << what << " triangle " << f;
        continue;
      }
      // Exactly one step outwards from the least and greatest of the six corners' rounded
      // projections (the SSE2 lanes compute them as the scalar loop did).
      const auto& axis = DopAxes<N>::kAxes[k];
      double least = std::numeric_limits<double>::infinity();
      double greatest = -least;
      for (const skinning::Positions* x : {&x0, &x1}) {
        for (const std::int32_t v : t.triangle(static_cast<std::int32_t>(f))) {
          double p = 0.0;
          for (std::size_t a = 0; a < 3; ++a) {
            if (axis[a] != 0) p = p + axis[a] * (*x)(v, static_cast<Eigen::Index>(a));
          }
          least = std::min(least, p);
          greatest = std::max(greatest, p);
        }
      }
      ASSERT_EQ(
          std::bit_cast<std::uint64_t>(d.lo[k]), std::bit_cast<std::uint64_t>(next_down(least)))
          << what << " triangle " << f << " axis " << k;
      ASSERT_EQ(
          std::bit_cast<std::uint64_t>(d.hi[k]), std::bit_cast<std::uint64_t>(next_up(greatest)))
          << what << " triangle " << f << " axis " << k;
      ASSERT_LE(d.lo[k], e.lo[k]) << what << " triangle " << f << " axis " << k;
      ASSERT_GE(d.lo[k], next_down(e.lo[k])) << what << " triangle " << f << " axis " << k;
      ASSERT_GE(d.hi[k], e.hi[k]) << what << " triangle " << f << " axis " << k;
      ASSERT_LE(d.hi[k], next_up(e.hi[k])) << what << " triangle " << f << " axis " << k;
    }
  }
}

TEST(FeatureBounds, SweptTrianglesFromTheCornersHoldTheDerivedVolumes) {
  for (const Scene& s : scenes()) {
    const FeatureTopology t(s.mesh, s.topology);
    expect_swept_triangles_hold_derived<3>(t, s.x_t0, s.x_t1, s.name);
    expect_swept_triangles_hold_derived<8>(t, s.x_t0, s.x_t1, s.name);
  }
  const test::WeldedCharacter trooper("stormtrooper/stormtrooper.dae");
  const FeatureTopology t(*trooper.loaded.mesh, trooper.topology);
  const skinning::Positions x0 = trooper.sample(7);
  const skinning::Positions x1 = trooper.sample(8);
  expect_swept_triangles_hold_derived<3>(t, x0, x1, "stormtrooper");
  expect_swept_triangles_hold_derived<8>(t, x0, x1, "stormtrooper");
}

TEST(FeatureTopology, SharedCornersMapCornersAndCountDistinctVertices) {
  skinning::Positions x(5, 3);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 2, 0;
  skinning::Triangles f(4, 3);
  f << 0, 1, 2,  // a
      2, 1, 3,   // shares edge 1-2 with a
      3, 4, 0,   // shares vertex 0 with a
      1, 2, 0;   // same three vertices as a
  const auto mesh = test::single_part_mesh(x, f);
  const FeatureTopology t(mesh, test::simple_topology(mesh));
  int n = 0;
  EXPECT_EQ(t.shared_corners(0, 1, n), (ccd::SharedCorners{-1, 1, 0}));
  EXPECT_EQ(n, 2);
  EXPECT_EQ(t.shared_corners(0, 2, n), (ccd::SharedCorners{2, -1, -1}));
  EXPECT_EQ(n, 1);
  (void)t.shared_corners(0, 3, n);
  EXPECT_EQ(n, 3);
  // The duplicate face is dropped from DCD, the others kept.
  std::vector<TrianglePair> pairs{{0, 1}, {0, 2}, {0, 3}};
  Counters counters;
  dcd_filter_triangle_pairs(t, pairs, counters);
  EXPECT_EQ(pairs, (std::vector<TrianglePair>{{0, 1}, {0, 2}}));
}

TEST(FeatureTopology, RejectsATopologyThatDoesNotMatchTheMesh) {
  const auto mesh = test::sheet(2, 2);
  auto topo = test::simple_topology(mesh);
  auto bad = topo;
  bad.face_edges(3, 1) = bad.face_edges(3, 0);
  EXPECT_THROW_MESSAGE(FeatureTopology(mesh, bad), InvalidInput, "triangle 3");
  bad = topo;
  bad.welded_triangles(2, 0) = 99;
  EXPECT_THROW_MESSAGE(FeatureTopology(mesh, bad), InvalidInput, "welded triangle 2");
  auto bad_mesh = mesh;
  bad_mesh.excluded_part_pairs = {{0, 3}};
  EXPECT_THROW_MESSAGE(FeatureTopology(bad_mesh, topo), InvalidInput, "excluded_part_pairs");
  bad = topo;
  bad.face_edges.conservativeResize(2, 3);
  EXPECT_THROW_MESSAGE(FeatureTopology(mesh, bad), InvalidInput, "face_edges");
}

}  // namespace
}  // namespace skelcd::culling
