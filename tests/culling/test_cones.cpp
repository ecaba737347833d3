// Cones (SNC/BNC, continuous normal cones), the contour predicates against exact rational
// arithmetic, and the per-node contours of the cone methods.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "culling/bvh.hpp"
#include "culling/cones.hpp"
#include "culling/contour.hpp"
#include "culling/contour_predicates.hpp"
#include "culling/feature_topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using Vec = Eigen::Vector3d;
using LVec = Eigen::Matrix<long double, 3, 1>;

LVec to_long(const Vec& v) { return v.cast<long double>(); }

/// True when x (long double, near-exact) lies in the cone up to a relative 1e-15 in its favour.
bool inside(const DirectionCone& c, const LVec& x) {
  if (c.is_full()) return true;
  if (c.is_empty()) return false;
  const long double n = x.norm();
  return x.dot(to_long(c.axis)) >= n * static_cast<long double>(c.cos_angle) - 1e-15L * n;
}

// --- cones -------------------------------------------------------------------------------------

TEST(Cones, VectorConeContainsItsVectorAndIsFullWhenDegenerate) {
  const DirectionCone c = cone_of_vector(Vec(1, 2, 3), 0.0);
  ASSERT_TRUE(c.in_open_half_space());
  EXPECT_TRUE(c.contains(Vec(1, 2, 3)));
  EXPECT_LT(c.angle(), 1e-14);
  EXPECT_FALSE(c.contains(Vec(1, 2, 3.001)));
  // A ball of radius 1 around a vector of length 10 spans asin(0.1).
  const DirectionCone ball = cone_of_vector(Vec(10, 0, 0), 1.0);
  EXPECT_NEAR(ball.angle(), std::asin(0.1), 1e-12);
  EXPECT_GE(ball.angle(), std::asin(0.1));
  EXPECT_TRUE(ball.contains(Vec(10, 1, 0) / std::sqrt(1.01) * 1.0));
  EXPECT_TRUE(cone_of_vector(Vec::Zero(), 0.0).is_full());
  EXPECT_TRUE(cone_of_vector(Vec(1, 0, 0), 0.6).is_full());  // beyond 30°: degenerate
  EXPECT_TRUE(cone_of_vector(Vec(std::nan(""), 0, 0), 0.0).is_full());
}

TEST(Cones, MergeIsNearOptimalAndConservative) {
  // Two directions 100° apart: the minimal enclosing cone has half-angle 50°.
  const double a = 100.0 * std::numbers::pi / 180.0;
  const Vec u(1, 0, 0);
  const Vec w(std::cos(a), std::sin(a), 0);
  const DirectionCone m = merge(cone_of_vector(u, 0.0), cone_of_vector(w, 0.0));
  ASSERT_TRUE(m.in_open_half_space());
  EXPECT_NEAR(m.angle(), 0.5 * a, 1e-12);
  EXPECT_TRUE(m.contains(u));
  EXPECT_TRUE(m.contains(w));
  // 170° apart: 85°, still inside a half-space. Three directions 120° apart in a plane: full.
  const double b = 170.0 * std::numbers::pi / 180.0;
  const DirectionCone wide =
      merge(cone_of_vector(u, 0.0), cone_of_vector(Vec(std::cos(b), std::sin(b), 0), 0.0));
  ASSERT_TRUE(wide.in_open_half_space());
  EXPECT_NEAR(wide.angle(), 0.5 * b, 1e-12);
  const double c = 2.0 * std::numbers::pi / 3.0;
  EXPECT_TRUE(merge(wide, cone_of_vector(Vec(std::cos(-c), std::sin(-c), 0), 0.0)).is_full());
  // Opposite vectors: full. Empty is the identity.
  EXPECT_TRUE(merge(cone_of_vector(u, 0.0), cone_of_vector(-u, 0.0)).is_full());
  EXPECT_EQ(merge(DirectionCone::empty_cone(), m).angle(), m.angle());
  EXPECT_TRUE(merge(DirectionCone::empty_cone(), DirectionCone::empty_cone()).is_empty());
  // A cone inside another: the merge keeps the bigger one's size.
  const DirectionCone big = cone_of_vector(Vec(10, 0, 0), 4.0);
  const DirectionCone small = cone_of_vector(Vec(10, 0.5, 0), 0.01);
  EXPECT_NEAR(merge(big, small).angle(), big.angle(), 1e-12);
}

TEST(Cones, RandomMergesContainEveryVector) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec centre = Vec(g(rng), g(rng), g(rng)).normalized();
    const double spread = 0.05 + 0.6 * (trial % 7) / 7.0;
    std::vector<Vec> vs;
    DirectionCone c = DirectionCone::empty_cone();
    for (int k = 0; k < 12; ++k) {
      const Vec v = (centre + spread * Vec(g(rng), g(rng), g(rng))) * std::exp(3.0 * g(rng));
      vs.push_back(v);
      c = merge(c, cone_of_vector(v, 0.0));
    }
    for (const Vec& v : vs) {
      EXPECT_TRUE(inside(c, to_long(v))) << "trial " << trial;
      if (c.in_open_half_space()) {
        EXPECT_GT(to_long(v).dot(to_long(c.axis)), 0.0L);
      }
    }
  }
}

/// Exact normal (b − a) × (c − a) in long double.
LVec exact_normal(const LVec& a, const LVec& b, const LVec& c) { return (b - a).cross(c - a); }

TEST(Cones, StaticNormalConesContainEveryTriangleNormalUpTheTree) {
  auto mesh = test::sheet(12, 9);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-0.03, 0.03);
  for (Eigen::Index v = 0; v < mesh.rest_positions.rows(); ++v) {
    mesh.rest_positions(v, 2) = 0.3 * std::sin(3.0 * mesh.rest_positions(v, 0)) + jitter(rng);
  }
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  const AabbBvh bvh(features.welded_triangles(), x);
  NormalConeTree tree;
  tree.refit(bvh, features, x);
  const auto nodes = bvh.nodes();
  const auto order = bvh.triangle_order();
  int bounded_nodes = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const DirectionCone c = tree.node_cone(bvh, static_cast<std::int32_t>(i));
    bounded_nodes += c.in_open_half_space() ? 1 : 0;
    for (std::int32_t s = nodes[i].begin; s < nodes[i].end; ++s) {
      const auto& t = features.triangle(order[static_cast<std::size_t>(s)]);
      const LVec n = exact_normal(
          to_long(x.row(t[0]).transpose()),
          to_long(x.row(t[1]).transpose()),
          to_long(x.row(t[2]).transpose()));
      ASSERT_TRUE(inside(c, n)) << "node " << i;
    }
  }
  // A mildly wavy sheet: the root's normals lie in a half-space.
  EXPECT_TRUE(tree.node_cone(bvh, 0).in_open_half_space());
  EXPECT_EQ(bounded_nodes, static_cast<int>(nodes.size()));
}

TEST(Cones, ContinuousConesContainNormalsAtEverySampledTimeAndTheControlVectors) {
  auto mesh = test::sheet(8, 8);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const skinning::Positions x0 = test::welded(topo, mesh.rest_positions);
  skinning::Positions x1 = x0;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> move(-0.04, 0.04);
  for (Eigen::Index v = 0; v < x1.rows(); ++v) {
    x1.row(v) += Eigen::RowVector3d(move(rng), move(rng), 0.5 * x0(v, 0) * x0(v, 0) + move(rng));
  }
  const AabbBvh bvh(features.welded_triangles(), x0);
  NormalConeTree tree;
  tree.refit(bvh, features, x0, x1);
  const auto nodes = bvh.nodes();
  const auto order = bvh.triangle_order();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const DirectionCone c = tree.node_cone(bvh, static_cast<std::int32_t>(i));
    for (std::int32_t s = nodes[i].begin; s < nodes[i].end; ++s) {
      const auto& t = features.triangle(order[static_cast<std::size_t>(s)]);
      std::array<LVec, 3> p0;
      std::array<LVec, 3> p1;
      for (std::size_t k = 0; k < 3; ++k) {
        p0[k] = to_long(x0.row(t[k]).transpose());
        p1[k] = to_long(x1.row(t[k]).transpose());
      }
      for (int step = 0; step <= 40; ++step) {
        const long double tt = step / 40.0L;
        std::array<LVec, 3> p;
        for (std::size_t k = 0; k < 3; ++k) p[k] = p0[k] + tt * (p1[k] - p0[k]);
        ASSERT_TRUE(inside(c, exact_normal(p[0], p[1], p[2]))) << "node " << i << " t " << tt;
      }
      // The Bernstein control vectors themselves.
      const LVec e10 = p0[1] - p0[0], e20 = p0[2] - p0[0], e11 = p1[1] - p1[0], e21 = p1[2] - p1[0];
      EXPECT_TRUE(inside(c, e10.cross(e20)));
      EXPECT_TRUE(inside(c, (e10.cross(e21) + e11.cross(e20)) / 2));
      EXPECT_TRUE(inside(c, e11.cross(e21)));
    }
  }
  EXPECT_TRUE(tree.node_cone(bvh, 0).in_open_half_space());
}

TEST(Cones, FlippingTriangleMakesItsContinuousConeFull) {
  // A triangle turning over during the interval: n(t) passes through zero or flips.
  skinning::Positions x0(3, 3);
  x0 << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  skinning::Positions x1(3, 3);
  x1 << 0, 0, 0, 1, 0, 0, 0, -1, 0;
  skinning::Triangles f(1, 3);
  f << 0, 1, 2;
  const auto mesh = test::single_part_mesh(x0, f);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const AabbBvh bvh(features.welded_triangles(), x0);
  NormalConeTree tree;
  tree.refit(bvh, features, x0, x1);
  EXPECT_TRUE(tree.node_cone(bvh, 0).is_full());
  tree.refit(bvh, features, x0, x0);
  EXPECT_TRUE(tree.node_cone(bvh, 0).in_open_half_space());
}

TEST(Cones, DirectTestAroundTheMeanNormalProvesWhatTheCheckAllowsAndNothingElse) {
  // A strip folded by 150° along its middle: normals 75° either side of the mean normal. The
  // direct test around the mean normal passes; folded by 180° + a little (normals more than 90°
  // from any common axis) it must fail, and a triangle seen exactly edge-on fails too.
  const auto mesh = test::sheet(8, 2, 2.0, 0.5);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  const AabbBvh bvh(features.welded_triangles(), x);
  NormalConeTree tree;
  const skinning::Positions bent = test::folded(x, 1.0, 150.0 * std::numbers::pi / 180.0);
  tree.refit(bvh, features, bent);
  const Vec mean = tree.mean_normal(bvh, 0);
  EXPECT_NEAR(mean.norm(), 1.0, 1e-12);
  EXPECT_TRUE(tree.normals_in_half_space(bvh, 0, mean));
  EXPECT_FALSE(tree.normals_in_half_space(bvh, 0, Vec(0, 0, 1)));  // the far half faces down
  tree.refit(bvh, features, bent, bent);                           // CCD: the same, constant
  EXPECT_TRUE(tree.normals_in_half_space(bvh, 0, tree.mean_normal(bvh, 0)));
  // Folded by 181°: the two halves' normals are 179° apart — still a half-space, barely; the
  // opposite direction never is.
  // (The tree reads the positions at its queries: they must outlive them.)
  const skinning::Positions x181 = test::folded(x, 1.0, 181.0 * std::numbers::pi / 180.0);
  tree.refit(bvh, features, x181);
  EXPECT_TRUE(tree.normals_in_half_space(bvh, 0, tree.mean_normal(bvh, 0)));
  EXPECT_FALSE(tree.normals_in_half_space(bvh, 0, -tree.mean_normal(bvh, 0)));
  // A closed sphere: its normals cancel, no direction passes.
  const auto sphere = test::uv_sphere(6, 8);
  const auto st = test::simple_topology(sphere);
  const FeatureTopology sf(sphere, st);
  const skinning::Positions sx = test::welded(st, sphere.rest_positions);
  const AabbBvh sb(sf.welded_triangles(), sx);
  NormalConeTree stree;
  stree.refit(sb, sf, sx);
  for (const Vec& v : {Vec(0, 0, 1), Vec(1, 0, 0), Vec(0.3, -0.2, 0.9), stree.mean_normal(sb, 0)}) {
    EXPECT_FALSE(stree.normals_in_half_space(sb, 0, v));
  }
  tree.refit(bvh, features, x);
  EXPECT_FALSE(tree.normals_in_half_space(bvh, 0, Vec(1, 0, 0)));  // every normal ⟂ V
  EXPECT_TRUE(tree.normals_in_half_space(bvh, 0, Vec(1e-12, 0, 1)));
}

TEST(Cones, BinormalConesContainTheBoundaryBinormalsAtSampledTimes) {
  // FASTCD's BNC of a triangle's boundary sides: b(t) = n(t) × e(t) inside the cone at every
  // sampled t (its control vectors bound the cubic while the cone is below π/2).
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int bounded = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::array<Vec, 3> p0{Vec(0, 0, 0), Vec(1, 0, 0), Vec(0, 1, 0)};
    std::array<Vec, 3> p1 = p0;
    for (std::size_t k = 0; k < 3; ++k) {
      p0[k] += 0.2 * Vec(u(rng), u(rng), u(rng));
      p1[k] = p0[k] + 0.15 * Vec(u(rng), u(rng), u(rng));
    }
    const auto sides = static_cast<std::uint8_t>(1 + trial % 7);
    const DirectionCone c = boundary_binormal_cone(p0, p1, sides, true);
    ASSERT_FALSE(c.is_empty());
    if (c.is_full()) continue;
    ++bounded;
    for (int step = 0; step <= 20; ++step) {
      const long double t = step / 20.0L;
      std::array<LVec, 3> p;
      for (std::size_t k = 0; k < 3; ++k)
        p[k] = to_long(p0[k]) + t * (to_long(p1[k]) - to_long(p0[k]));
      const LVec n = (p[1] - p[0]).cross(p[2] - p[0]);
      for (std::size_t k = 0; k < 3; ++k) {
        if ((sides & (1u << k)) == 0) continue;
        const LVec b = n.cross(p[(k + 1) % 3] - p[k]);
        // The baseline's cones carry no error bounds: allow a relative 1e-12.
        EXPECT_GE(
            b.dot(to_long(c.axis)), b.norm() * (static_cast<long double>(c.cos_angle) - 1e-12L))
            << "trial " << trial << " t " << static_cast<double>(t);
      }
    }
  }
  EXPECT_GT(bounded, 100);
  EXPECT_TRUE(boundary_binormal_cone(
                  {Vec(0, 0, 0), Vec(1, 0, 0), Vec(0, 1, 0)},
                  {Vec(0, 0, 0), Vec(1, 0, 0), Vec(0, 1, 0)},
                  0,
                  false)
                  .is_empty());
}

// --- predicates vs exact rationals ---------------------------------------------------------------

mpq_class q(double d) { return mpq_class(d); }

int exact_det_v(const Vec& v, const Vec& p, const Vec& a, const Vec& b) {
  // V · ((a − p) × (b − p)) in rationals.
  const mpq_class ax = q(a.x()) - q(p.x()), ay = q(a.y()) - q(p.y()), az = q(a.z()) - q(p.z());
  const mpq_class bx = q(b.x()) - q(p.x()), by = q(b.y()) - q(p.y()), bz = q(b.z()) - q(p.z());
  const mpq_class r = q(v.x()) * (ay * bz - az * by) + q(v.y()) * (az * bx - ax * bz) +
                      q(v.z()) * (ax * by - ay * bx);
  return sgn(r);
}

int exact_dot_v(const Vec& v, const Vec& p, const Vec& a, const Vec& b) {
  const mpq_class ax = q(a.x()) - q(p.x()), ay = q(a.y()) - q(p.y()), az = q(a.z()) - q(p.z());
  const mpq_class bx = q(b.x()) - q(p.x()), by = q(b.y()) - q(p.y()), bz = q(b.z()) - q(p.z());
  const mpq_class vx = q(v.x()), vy = q(v.y()), vz = q(v.z());
  const mpq_class r = (ax * bx + ay * by + az * bz) * (vx * vx + vy * vy + vz * vz) -
                      (ax * vx + ay * vy + az * vz) * (bx * vx + by * vy + bz * vz);
  return sgn(r);
}

TEST(ContourPredicates, ProvenSignsAgreeWithExactArithmeticIncludingNearDegenerateInput) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int proven = 0;
  int uncertain = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const double scale = std::pow(10.0, static_cast<double>(trial % 13) - 6.0);
    const Vec v(u(rng), u(rng), u(rng));
    const Vec p = scale * Vec(u(rng), u(rng), u(rng));
    const Vec a = p + scale * Vec(u(rng), u(rng), u(rng));
    Vec b = p + scale * Vec(u(rng), u(rng), u(rng));
    if (trial % 2 == 0) {
      // b nearly in the plane of V and a − p (projections collinear), or nearly orthogonal.
      const double eps = (trial % 4 == 0 ? 1e-16 : 1e-9) * scale * u(rng);
      b = p + 0.7 * (a - p) + 0.3 * v * scale + eps * v.cross(a - p);
    }
    const ProvenSign d = sign_of(det_v(v, a - p, b - p));
    const ProvenSign o = sign_of(dot_v(v, a - p, b - p));
    if (d != ProvenSign::uncertain) {
      ++proven;
      EXPECT_EQ(static_cast<int>(d), exact_det_v(v, p, a, b)) << trial;
    } else {
      ++uncertain;
    }
    if (o != ProvenSign::uncertain) {
      EXPECT_EQ(static_cast<int>(o), exact_dot_v(v, p, a, b)) << trial;
    }
  }
  EXPECT_GT(proven, 3000);  // the filter decides almost everything
  EXPECT_GT(uncertain, 0);  // and the exactly collinear cases are left undecided
}

TEST(ContourPredicates, BernsteinQuadraticSignMatchesSampledSigns) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const double c0 = u(rng), c1 = u(rng), c2 = u(rng);
    const ProvenSign s = bernstein_quadratic_sign({c0, 1e-12}, {c1, 1e-12}, {c2, 1e-12});
    if (s == ProvenSign::uncertain) continue;
    for (int k = 0; k <= 100; ++k) {
      const double t = k / 100.0;
      const double f = c0 * (1 - t) * (1 - t) + 2 * c1 * t * (1 - t) + c2 * t * t;
      ASSERT_EQ(f > 0 ? 1 : -1, static_cast<int>(s)) << trial << " t=" << t;
    }
  }
  // A quadratic with a root inside is never proven.
  EXPECT_EQ(bernstein_quadratic_sign({1.0, 0}, {-2.0, 0}, {1.0, 0}), ProvenSign::uncertain);
  // Positive coefficients except a negative middle one, yet positive: the split proves it.
  EXPECT_EQ(bernstein_quadratic_sign({1.0, 0}, {-0.2, 0}, {1.0, 0}), ProvenSign::positive);
}

TEST(ContourPredicates, ProjectionFrameIsExactlyOrthogonalToV) {
  const Vec v(0.3, -1.7, 0.2);
  const ProjectionFrame f(v);
  EXPECT_EQ(f.k, 1);
  EXPECT_EQ(f.g1.dot(v), 0.0);
  EXPECT_EQ(f.g2.dot(v), 0.0);
  EXPECT_GT(f.g1.cross(f.g2).norm(), 0.0);
}

// --- contours ------------------------------------------------------------------------------------

TEST(NodeContours, SheetRootIsItsBoundaryLoopWithChainsBySubSurface) {
  const auto mesh = test::sheet(10, 6);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const AabbBvh bvh(features.welded_triangles(), test::welded(topo, mesh.rest_positions));
  const NodeContours contours(bvh, features);
  ASSERT_EQ(contours.status(0), ContourStatus::loops);
  const auto edges = contours.edges(0);
  EXPECT_EQ(edges.size(), 2u * (10 + 6));
  // A closed, consistently directed loop.
  for (std::size_t k = 0; k < edges.size(); ++k) {
    EXPECT_EQ(edges[k].to, edges[(k + 1) % edges.size()].from);
  }
  // Chains: runs of one sub-surface; every part of the four appears, starts are increasing.
  const auto chains = contours.chain_starts(0);
  ASSERT_GE(chains.size(), 5u);
  EXPECT_EQ(chains.front(), 0);
  EXPECT_EQ(chains.back(), static_cast<std::int32_t>(edges.size()));
  std::set<int> parts;
  for (std::size_t c = 0; c + 1 < chains.size(); ++c) {
    const int p = edges[static_cast<std::size_t>(chains[c])].part;
    parts.insert(p);
    for (auto k = chains[c]; k < chains[c + 1]; ++k)
      EXPECT_EQ(edges[static_cast<std::size_t>(k)].part, p);
    if (c > 0) {
      EXPECT_NE(p, edges[static_cast<std::size_t>(chains[c] - 1)].part);
    }
  }
  EXPECT_EQ(parts.size(), 4u);
  EXPECT_EQ(contours.loop_starts(0).size(), 2u);  // one loop
  EXPECT_TRUE(contours.fans(0).empty());
}

TEST(NodeContours, InternalBoundaryEdgesAreOnTheContourOfInnerNodes) {
  // Every contour edge of a node has exactly one triangle in the node, and every edge with one
  // triangle in the node is on its contour (brute-force recount for all tested nodes).
  const auto mesh = test::sheet(9, 7);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const AabbBvh bvh(features.welded_triangles(), test::welded(topo, mesh.rest_positions));
  const NodeContours contours(bvh, features);
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> edge_id;
  for (std::int32_t e = 0; e < features.num_edges(); ++e) {
    const auto& ends = features.edge(e);
    edge_id[{std::min(ends[0], ends[1]), std::max(ends[0], ends[1])}] = e;
  }
  const auto nodes = bvh.nodes();
  int checked = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto n = static_cast<std::int32_t>(i);
    if (contours.status(n) != ContourStatus::loops) continue;
    std::map<std::int32_t, int> count;
    for (std::int32_t s = nodes[i].begin; s < nodes[i].end; ++s) {
      for (int k = 0; k < 3; ++k)
        ++count[features.face_edge(bvh.triangle_order()[static_cast<std::size_t>(s)], k)];
    }
    std::set<std::int32_t> expected;
    for (const auto& [e, c] : count) {
      if (c == 1) expected.insert(e);
    }
    std::set<std::int32_t> got;
    for (const auto& e : contours.edges(n)) {
      got.insert(edge_id.at({std::min(e.from, e.to), std::max(e.from, e.to)}));
    }
    EXPECT_EQ(got, expected) << "node " << i;
    ++checked;
  }
  EXPECT_GT(checked, 5);
  EXPECT_EQ(contours.status_counts()[static_cast<std::size_t>(ContourStatus::loops)], checked);
}

TEST(NodeContours, ClosedSurfaceHasNoContourAndSeparatePiecesGiveOneLoopEach) {
  const auto sphere = test::uv_sphere(8, 10);
  const auto ts = test::simple_topology(sphere);
  const FeatureTopology fs(sphere, ts);
  const AabbBvh bs(fs.welded_triangles(), test::welded(ts, sphere.rest_positions));
  EXPECT_EQ(NodeContours(bs, fs).status(0), ContourStatus::no_contour);

  auto b = test::sheet(4, 4);
  b.rest_positions = test::translated(b.rest_positions, Vec(0.2, 0.3, 0.5));
  const auto two = test::combine(test::sheet(4, 4), b);
  const auto tt = test::simple_topology(two);
  const FeatureTopology ft(two, tt);
  const AabbBvh bt(ft.welded_triangles(), test::welded(tt, two.rest_positions));
  const NodeContours c(bt, ft);
  ASSERT_EQ(c.status(0), ContourStatus::loops);
  EXPECT_EQ(c.loop_starts(0).size(), 3u);  // two loops
  EXPECT_EQ(c.edges(0).size(), 32u);
  for (const std::int32_t probe : c.loop_probe(0)) EXPECT_GE(probe, 0);
}

TEST(NodeContours, PinchVertexIsUnpinchedIntoTwoLoopsWithTwoFans) {
  // Two triangles meeting only at vertex 0 (a bowtie), plus enough triangles elsewhere for the
  // root to have grandchildren.
  skinning::Positions x(9, 3);
  x << 0, 0, 0, 1, -0.5, 0, 1, 0.5, 0, -1, 0.5, 0, -1, -0.5, 0, 5, 5, 0, 6, 5, 0, 5, 6, 0, 6, 6, 0;
  skinning::Triangles f(4, 3);
  f << 0, 1, 2, 0, 3, 4, 5, 6, 7, 6, 8, 7;
  const auto mesh = test::single_part_mesh(x, f);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const AabbBvh bvh(features.welded_triangles(), test::welded(topo, mesh.rest_positions));
  const NodeContours c(bvh, features);
  ASSERT_EQ(c.status(0), ContourStatus::loops);
  EXPECT_EQ(c.loop_starts(0).size(), 4u);  // bowtie: two triangles' loops; the far square: one
  ASSERT_EQ(c.fans(0).size(), 2u);
  EXPECT_EQ(c.fans(0)[0].vertex, 0);
  EXPECT_EQ(c.fans(0)[1].vertex, 0);
  // Each fan pairs the in- and out-edge of its own triangle.
  for (const ContourFan& fan : c.fans(0)) {
    const auto e = c.edges(0);
    EXPECT_EQ(e[static_cast<std::size_t>(fan.in_edge)].to, 0);
    EXPECT_EQ(e[static_cast<std::size_t>(fan.out_edge)].from, 0);
    const int t_in = e[static_cast<std::size_t>(fan.in_edge)].from <= 2 ? 0 : 1;
    const int t_out = e[static_cast<std::size_t>(fan.out_edge)].to <= 2 ? 0 : 1;
    EXPECT_EQ(t_in, t_out);
  }
  // Side by side the bowtie's fans are disjoint: simple. Folding one triangle over the other
  // (same normal direction, overlapping wedges) is not.
  ContourTester tester;
  ContourTestCounters counters;
  const skinning::Positions xw = test::welded(topo, mesh.rest_positions);
  EXPECT_TRUE(tester.test(c, 0, Vec(0, 0, 1), xw, ContourMode::every_edge, counters).simple);
  skinning::Positions y = xw;
  y.row(3) << 1.2, 0.3, 0.1;  // triangle (0, 3, 4) now spans a wedge inside triangle (0, 1, 2)'s
  y.row(4) << 1.2, -0.3, 0.1;
  const ContourVerdict v = tester.test(c, 0, Vec(0, 0, 1), y, ContourMode::every_edge, counters);
  EXPECT_FALSE(v.simple);
  EXPECT_GT(counters.pinch_tests, 0);
}

TEST(ContourTester, NestedPiecesFacingTheSameWayAreNotSimpleButAHoleIs) {
  // A small sheet floating above the middle of a big one, both facing +z: two loops, nested,
  // both counter-clockwise — two sheets over one point. The projection is never crossed, so only
  // the nesting test can refuse it.
  auto small = test::sheet(2, 2, 0.4, 0.4);
  small.rest_positions = test::translated(small.rest_positions, Vec(0.3, 0.3, 0.2));
  const auto mesh = test::combine(test::sheet(6, 6), small);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  const AabbBvh bvh(features.welded_triangles(), x);
  const NodeContours c(bvh, features);
  ASSERT_EQ(c.status(0), ContourStatus::loops);
  ContourTester tester;
  ContourTestCounters counters;
  const ContourVerdict nested =
      tester.test(c, 0, Vec(0, 0, 1), x, ContourMode::every_edge, counters);
  EXPECT_FALSE(nested.simple);
  EXPECT_TRUE(nested.failed_nesting);
  // Moved aside (no overlap in projection), the same two loops are fine.
  skinning::Positions aside = x;
  for (Eigen::Index w = 0; w < aside.rows(); ++w) {
    if (aside(w, 2) > 0.1) aside(w, 0) += 2.0;
  }
  EXPECT_TRUE(tester.test(c, 0, Vec(0, 0, 1), aside, ContourMode::every_edge, counters).simple);
  EXPECT_GT(counters.nesting_tests, 0);
  // A sheet with a hole (one quad's two triangles removed): outer loop counter-clockwise, inner
  // clockwise — covered once.
  auto holed = test::sheet(5, 5);
  skinning::Triangles kept(holed.triangles.rows() - 2, 3);
  for (Eigen::Index t = 0, r = 0; t < holed.triangles.rows(); ++t) {
    if (t == 24 || t == 25) continue;  // the middle cell
    kept.row(r++) = holed.triangles.row(t);
  }
  const auto hm = test::single_part_mesh(holed.rest_positions, kept);
  const auto ht = test::simple_topology(hm);
  const FeatureTopology hf(hm, ht);
  const skinning::Positions hx = test::welded(ht, hm.rest_positions);
  const AabbBvh hb(hf.welded_triangles(), hx);
  const NodeContours hc(hb, hf);
  ASSERT_EQ(hc.status(0), ContourStatus::loops);
  EXPECT_EQ(hc.loop_starts(0).size(), 3u);
  EXPECT_TRUE(tester.test(hc, 0, Vec(0, 0, 1), hx, ContourMode::chains, counters).simple);
  EXPECT_TRUE(tester.test(hc, 0, Vec(0, 0, 1), hx, hx, ContourMode::every_edge, counters).simple);
}

TEST(NodeContours, InconsistentOrientationIsRefused) {
  auto mesh = test::sheet(4, 4);
  mesh.triangles.row(5) = mesh.triangles.row(5).reverse().eval();
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const AabbBvh bvh(features.welded_triangles(), test::welded(topo, mesh.rest_positions));
  EXPECT_EQ(NodeContours(bvh, features).status(0), ContourStatus::inconsistent_orientation);
}

// --- the contour test ----------------------------------------------------------------------------

TEST(ContourTester, FlatSheetIsSimpleAndAFoldedSheetIsNot) {
  const auto mesh = test::sheet(12, 8, 2.0, 1.0);
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  const AabbBvh bvh(features.welded_triangles(), x);
  const NodeContours contours(bvh, features);
  ContourTester tester;
  ContourTestCounters counters;
  for (const ContourMode mode : {ContourMode::chains, ContourMode::every_edge}) {
    EXPECT_TRUE(tester.test(contours, 0, Vec(0, 0, 1), x, mode, counters).simple);
    EXPECT_TRUE(tester.test(contours, 0, Vec(0.1, -0.2, 1), x, x, mode, counters).simple);
    // Seen edge-on (V in the sheet's plane) the projection degenerates: never proven.
    EXPECT_FALSE(tester.test(contours, 0, Vec(1, 0, 0), x, mode, counters).simple);
  }
  // Folded by 200° about x = 1: the far half's boundary crosses the near half's in projection.
  const skinning::Positions y = test::folded(x, 1.0, 200.0 * std::numbers::pi / 180.0);
  for (const ContourMode mode : {ContourMode::chains, ContourMode::every_edge}) {
    EXPECT_FALSE(tester.test(contours, 0, Vec(0, 0, 1), y, mode, counters).simple);
    EXPECT_FALSE(tester.test(contours, 0, Vec(0, 0, 1), x, y, mode, counters).simple);
  }
  EXPECT_GT(counters.edge_pair_tests, 0);
  EXPECT_GT(counters.chain_tests, 0);
}

// The tree keeps cones and normal sums for internal nodes only, and no normal per triangle: a
// leaf's cone and mean normal are formed on request from its triangle's normal at the refit's
// positions, and must be exactly the triangle's cone (DCD: the cone of its one normal) and unit
// normal, as the refit merged them.
TEST(Cones, LeafConesAreFormedFromTheirTrianglesNormals) {
  auto mesh = test::sheet(6, 5);
  for (Eigen::Index v = 0; v < mesh.rest_positions.rows(); ++v) {
    mesh.rest_positions(v, 2) = 0.2 * std::sin(2.0 * mesh.rest_positions(v, 1));
  }
  const auto topo = test::simple_topology(mesh);
  const FeatureTopology features(mesh, topo);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  const AabbBvh bvh(features.welded_triangles(), x);
  NormalConeTree tree;
  tree.refit(bvh, features, x);
  const auto nodes = bvh.nodes();
  const auto order = bvh.triangle_order();
  int leaves = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (!nodes[i].is_leaf()) continue;
    const auto& t = features.triangle(order[static_cast<std::size_t>(nodes[i].begin)]);
    const BoundedNormal n =
        triangle_normal(x.row(t[0]).transpose(), x.row(t[1]).transpose(), x.row(t[2]).transpose());
    const DirectionCone want = cone_of_vector(n.n, n.error);
    const DirectionCone got = tree.node_cone(bvh, static_cast<std::int32_t>(i));
    ASSERT_EQ(got.kind, want.kind) << "leaf " << i;
    EXPECT_EQ(got.axis, want.axis) << "leaf " << i;
    EXPECT_EQ(got.cos_angle, want.cos_angle) << "leaf " << i;
    EXPECT_EQ(got.sin_angle, want.sin_angle) << "leaf " << i;
    EXPECT_EQ(tree.mean_normal(bvh, static_cast<std::int32_t>(i)), unit_or_zero(n.n)) << i;
    ++leaves;
  }
  EXPECT_EQ(leaves, static_cast<int>(features.num_triangles()));
  // An internal node's mean normal is the unit sum of its two children's sums.
  const Eigen::Vector3d root_sum = [&] {
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (const std::int32_t f : order) {
      const auto& t = features.triangle(f);
      s +=
          triangle_normal(x.row(t[0]).transpose(), x.row(t[1]).transpose(), x.row(t[2]).transpose())
              .n;
    }
    return s;
  }();
  EXPECT_LT((tree.mean_normal(bvh, 0) - unit_or_zero(root_sum)).norm(), 1e-12);
}

// The contours are stored as compressed rows with a record per tested node: every node's rows
// must still be its own — loops that close on themselves, chain and loop starts that end at its
// edge count, one probe per loop, fans whose edges meet at their vertex — and nodes without a
// contour test must have none. On the real cloth-funnel mesh (18,484 triangles, many pinches).
TEST(NodeContours, CompressedRowsHoldEachNodesOwnLoopsOnARealMesh) {
  const test::OpenScene s = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  const FeatureTopology features(s.mesh, s.topo);
  const AabbBvh bvh(features.welded_triangles(), s.frames[0]);
  const NodeContours contours(bvh, features);
  std::int64_t edges = 0;
  int with_loops = 0;
  int with_fans = 0;
  for (std::int32_t n = 0; n < static_cast<std::int32_t>(bvh.nodes().size()); ++n) {
    const auto e = contours.edges(n);
    const auto loops = contours.loop_starts(n);
    const auto chains = contours.chain_starts(n);
    const auto probes = contours.loop_probe(n);
    const auto fans = contours.fans(n);
    edges += static_cast<std::int64_t>(e.size());
    if (contours.status(n) != ContourStatus::loops) {
      EXPECT_TRUE(e.empty() && loops.empty() && chains.empty() && probes.empty() && fans.empty())
          << "node " << n;
      continue;
    }
    ++with_loops;
    ASSERT_FALSE(e.empty()) << "node " << n;
    ASSERT_EQ(loops.size(), probes.size() + 1) << "node " << n;
    ASSERT_EQ(loops.front(), 0) << "node " << n;
    ASSERT_EQ(loops.back(), static_cast<std::int32_t>(e.size())) << "node " << n;
    ASSERT_EQ(chains.front(), 0) << "node " << n;
    ASSERT_EQ(chains.back(), static_cast<std::int32_t>(e.size())) << "node " << n;
    for (std::size_t l = 0; l + 1 < loops.size(); ++l) {
      const auto b = static_cast<std::size_t>(loops[l]);
      const auto end = static_cast<std::size_t>(loops[l + 1]);
      for (std::size_t k = b; k < end; ++k) {
        const std::size_t next = k + 1 < end ? k + 1 : b;
        ASSERT_EQ(e[k].to, e[next].from) << "node " << n << " loop " << l;
        ASSERT_GE(e[k].part, 0);
        ASSERT_LT(e[k].part, 4);
      }
    }
    with_fans += fans.empty() ? 0 : 1;
    for (const ContourFan& f : fans) {
      ASSERT_EQ(e[static_cast<std::size_t>(f.in_edge)].to, f.vertex) << "node " << n;
      ASSERT_EQ(e[static_cast<std::size_t>(f.out_edge)].from, f.vertex) << "node " << n;
    }
  }
  EXPECT_EQ(edges, contours.total_edges());
  EXPECT_EQ(with_loops, contours.status_counts()[static_cast<std::size_t>(ContourStatus::loops)]);
  EXPECT_GT(with_loops, 1000);
  EXPECT_GT(with_fans, 0);
}

}  // namespace
}  // namespace skelcd::culling
