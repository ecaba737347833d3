// PairChecker (object A against object B) against brute force over every cross pair, and on
// placements with known answers: apart, face to face, overlapping, passing through.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include "ccd/edge_edge.hpp"
#include "ccd/triangle_triangle.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/pair_checker.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using skinning::Mesh;
using skinning::Positions;

/// An axis-aligned box [lo, hi] (closed, 12 triangles, wound outwards).
Mesh box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Mesh m;
  m.rest_positions.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.rest_positions.row(i) << ((i & 1) ? hi.x() : lo.x()), ((i & 2) ? hi.y() : lo.y()),
        ((i & 4) ? hi.z() : lo.z());
  }
  m.triangles.resize(12, 3);
  m.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2,
      4, 6, 1, 3, 5, 3, 7, 5;
  m.face_part.assign(12, 0);
  m.face_index_in_part.resize(12);
  for (int f = 0; f < 12; ++f) m.face_index_in_part[static_cast<std::size_t>(f)] = f;
  m.vertex_part.assign(8, 0);
  m.vertex_index_in_part.resize(8);
  for (int v = 0; v < 8; ++v) m.vertex_index_in_part[static_cast<std::size_t>(v)] = v;
  m.part_names = {"box"};
  return m;
}

/// An n × n grid sheet in the plane z = z0 over [x0, x0 + size] × [0, size].
Mesh sheet(int n, double x0, double z0, double size) {
  Mesh m;
  const int side = n + 1;
  m.rest_positions.resize(side * side, 3);
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      m.rest_positions.row(j * side + i) << x0 + size * i / n, size * j / n, z0;
    }
  }
  m.triangles.resize(2 * n * n, 3);
  int f = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int v = j * side + i;
      m.triangles.row(f++) << v, v + 1, v + side + 1;
      m.triangles.row(f++) << v, v + side + 1, v + side;
    }
  }
  m.face_part.assign(static_cast<std::size_t>(f), 0);
  m.face_index_in_part.resize(static_cast<std::size_t>(f));
  for (int k = 0; k < f; ++k) m.face_index_in_part[static_cast<std::size_t>(k)] = k;
  m.vertex_part.assign(static_cast<std::size_t>(side * side), 0);
  m.vertex_index_in_part.resize(static_cast<std::size_t>(side * side));
  for (int k = 0; k < side * side; ++k) m.vertex_index_in_part[static_cast<std::size_t>(k)] = k;
  m.part_names = {"sheet"};
  return m;
}

Positions welded(const skinning::Topology& t, const Positions& x) {
  Positions w;
  skinning::gather_welded(t, x, w);
  return w;
}

Positions translated(const Positions& x, const Eigen::Vector3d& d) {
  Positions y = x;
  for (Eigen::Index i = 0; i < y.rows(); ++i) y.row(i) += d.transpose();
  return y;
}

Positions jittered(const Positions& x, double amount, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-amount, amount);
  Positions y = x;
  for (Eigen::Index i = 0; i < y.rows(); ++i) {
    for (int k = 0; k < 3; ++k) y(i, k) += u(rng);
  }
  return y;
}

Eigen::Vector3d row(const Positions& x, std::int32_t i) { return x.row(i).transpose(); }

using DcdSet = std::set<std::pair<std::int32_t, std::int32_t>>;
using CcdSet =
    std::set<std::tuple<int, int, std::int32_t, std::int32_t>>;  // kind, vertex_of_b, a, b

/// Every cross triangle pair through the exact triangle test.
DcdSet brute_dcd(
    const FeatureTopology& a, const Positions& xa, const FeatureTopology& b, const Positions& xb) {
  DcdSet out;
  for (std::int32_t i = 0; i < a.num_triangles(); ++i) {
    for (std::int32_t j = 0; j < b.num_triangles(); ++j) {
      const auto& ta = a.triangle(i);
      const auto& tb = b.triangle(j);
      const ccd::TriangleTriangleQuery q{
          row(xa, ta[0]),
          row(xa, ta[1]),
          row(xa, ta[2]),
          row(xb, tb[0]),
          row(xb, tb[1]),
          row(xb, tb[2])};
      if (ccd::triangles_intersect(q)) out.insert({i, j});
    }
  }
  return out;
}

/// Every cross VF (both ways) and EE pair through the exact CCD tests.
CcdSet brute_ccd(
    const FeatureTopology& a,
    const Positions& a0,
    const Positions& a1,
    const FeatureTopology& b,
    const Positions& b0,
    const Positions& b1) {
  CcdSet out;
  const auto vf = [&](bool vertex_of_b,
                      const FeatureTopology& tv,
                      const Positions& v0,
                      const Positions& v1,
                      const FeatureTopology& tf,
                      const Positions& f0,
                      const Positions& f1) {
    for (std::int32_t v = 0; v < tv.num_vertices(); ++v) {
      if (tv.vertex_owner(v) < 0) continue;
      for (std::int32_t f = 0; f < tf.num_triangles(); ++f) {
        const auto& t = tf.triangle(f);
        const ccd::VertexFaceQuery q{
            row(v0, v),
            row(f0, t[0]),
            row(f0, t[1]),
            row(f0, t[2]),
            row(v1, v),
            row(f1, t[0]),
            row(f1, t[1]),
            row(f1, t[2])};
        if (ccd::vertex_face_ccd(q, ccd::Accuracy::exact).hit) {
          out.insert({0, vertex_of_b ? 1 : 0, v, f});
        }
      }
    }
  };
  vf(false, a, a0, a1, b, b0, b1);
  vf(true, b, b0, b1, a, a0, a1);
  for (std::int32_t ea = 0; ea < a.num_edges(); ++ea) {
    for (std::int32_t eb = 0; eb < b.num_edges(); ++eb) {
      const auto& e = a.edge(ea);
      const auto& g = b.edge(eb);
      const ccd::EdgeEdgeQuery q{
          row(a0, e[0]),
          row(a0, e[1]),
          row(b0, g[0]),
          row(b0, g[1]),
          row(a1, e[0]),
          row(a1, e[1]),
          row(b1, g[0]),
          row(b1, g[1])};
      if (ccd::edge_edge_ccd(q, ccd::Accuracy::exact).hit) out.insert({1, 0, ea, eb});
    }
  }
  return out;
}

DcdSet as_set(const std::vector<TrianglePair>& pairs) {
  DcdSet s;
  for (const auto& p : pairs) s.insert({p.a, p.b});
  return s;
}

CcdSet as_set(const std::vector<PairContact>& contacts) {
  CcdSet s;
  for (const auto& c : contacts) {
    s.insert({static_cast<int>(c.kind), c.vertex_of_b ? 1 : 0, c.a, c.b});
  }
  return s;
}

struct Objects {
  Mesh mesh_a, mesh_b;
  skinning::Topology topo_a, topo_b;
  Objects(Mesh a, Mesh b) : mesh_a(std::move(a)), mesh_b(std::move(b)) {
    topo_a = skinning::build_topology(mesh_a);
    topo_b = skinning::build_topology(mesh_b);
  }
};

TEST(PairChecker, BoxesApartTouchingAndOverlappingHaveTheKnownDcdAnswer) {
  const Eigen::Vector3d zero(0, 0, 0), one(1, 1, 1);
  // Apart: B starts at x = 1.5. Face to face: B's face x = 1 lies on A's face x = 1.
  // Overlapping: B = [0.5, 1.5]³ ∩ … crosses A's faces.
  struct Case {
    double shift;
    bool expect_pairs;
  };
  for (const Case c :
       {Case{1.5, false}, Case{1.0, true}, Case{0.5, true}, Case{1.0 + 1e-9, false}}) {
    Objects o(
        box(zero, one),
        box(zero + Eigen::Vector3d(c.shift, 0.25, 0.25),
            one + Eigen::Vector3d(c.shift, 0.25, 0.25)));
    PairChecker checker(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {.accuracy = ccd::Accuracy::exact});
    const Positions xa = welded(o.topo_a, o.mesh_a.rest_positions);
    const Positions xb = welded(o.topo_b, o.mesh_b.rest_positions);
    PairFrameResult r;
    checker.detect_dcd(xa, xb, r);
    EXPECT_EQ(!r.dcd_pairs.empty(), c.expect_pairs) << "shift " << c.shift;
    EXPECT_EQ(as_set(r.dcd_pairs), brute_dcd(checker.topology_a(), xa, checker.topology_b(), xb))
        << "shift " << c.shift;
    EXPECT_EQ(r.counters.dcd_pairs, static_cast<std::int64_t>(r.dcd_pairs.size()));
    EXPECT_EQ(r.counters.vf_tests + r.counters.ee_tests, 0);
    if (c.shift == 1.5) {
      EXPECT_EQ(r.counters.candidate_pairs, 0);
    }
  }
}

TEST(PairChecker, SheetPassingThroughABoxHasContactsOnlyWhenItCrosses) {
  // A box [0,1]³; a sheet above it at z = 1.5 moves down to z = 0.5 (crosses the top face) or
  // to z = 1.2 (stays clear).
  Objects o(box({0, 0, 0}, {1, 1, 1}), sheet(4, -0.5, 1.5, 2.0));
  PairChecker checker(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {.accuracy = ccd::Accuracy::exact});
  const Positions xa = welded(o.topo_a, o.mesh_a.rest_positions);
  const Positions xb0 = welded(o.topo_b, o.mesh_b.rest_positions);
  for (const double dz : {-1.0, -0.3}) {
    const Positions xb1 = translated(xb0, {0, 0, dz});
    PairFrameResult r;
    checker.detect_ccd(xa, xa, xb0, xb1, r);
    const auto expected = brute_ccd(checker.topology_a(), xa, xa, checker.topology_b(), xb0, xb1);
    EXPECT_EQ(as_set(r.contacts), expected) << "dz " << dz;
    EXPECT_EQ(!r.contacts.empty(), dz == -1.0) << "dz " << dz;
    EXPECT_EQ(
        r.counters.vf_contacts + r.counters.ee_contacts,
        static_cast<std::int64_t>(r.contacts.size()));
    EXPECT_TRUE(std::is_sorted(
        r.contacts.begin(), r.contacts.end(), [](const PairContact& x, const PairContact& y) {
          return x.before(y);
        }));
  }
}

TEST(PairChecker, RandomMotionsEqualBruteForceOverAllCrossPairs) {
  // Two crumpled sheets interleaved, jittered at both ends of the interval: many near contacts,
  // both VF directions and EE. Exact accuracy: sets must be equal; conservative: a superset.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 6; ++trial) {
    Objects o(sheet(5, 0.0, 0.0, 1.0), sheet(4, 0.1, 0.05, 0.9));
    const Positions a0 = jittered(welded(o.topo_a, o.mesh_a.rest_positions), 0.08, rng);
    const Positions a1 = jittered(a0, 0.08, rng);
    const Positions b0 = jittered(welded(o.topo_b, o.mesh_b.rest_positions), 0.08, rng);
    const Positions b1 = jittered(b0, 0.08, rng);
    PairChecker exact(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {.accuracy = ccd::Accuracy::exact});
    PairFrameResult r;
    exact.detect_ccd(a0, a1, b0, b1, r);
    const auto expected = brute_ccd(exact.topology_a(), a0, a1, exact.topology_b(), b0, b1);
    EXPECT_EQ(as_set(r.contacts), expected) << "trial " << trial;
    EXPECT_GT(expected.size(), 0u);
    // Each feature pair tested at most once: tests never exceed the cross pairs that exist.
    std::set<std::tuple<int, int, std::int32_t, std::int32_t>> unique(as_set(r.contacts));
    EXPECT_EQ(unique.size(), r.contacts.size());

    PairChecker conservative(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {});
    PairFrameResult rc;
    conservative.detect_ccd(a0, a1, b0, b1, rc);
    const auto found = as_set(rc.contacts);
    for (const auto& e : expected) EXPECT_EQ(found.count(e), 1u) << "trial " << trial;

    PairFrameResult rd;
    exact.detect_dcd(a1, b1, rd);
    EXPECT_EQ(as_set(rd.dcd_pairs), brute_dcd(exact.topology_a(), a1, exact.topology_b(), b1));
  }
}

TEST(PairChecker, RealAssetAgainstAMovedCopyOfItselfEqualsBruteForce) {
  // RiggedFigure (256 triangles) against a copy shifted by a tenth of its height: the arms and
  // legs of one pass through the other's.
  const auto model = skinning::load_model(test::asset("characters/RiggedFigure.glb"));
  const Mesh& m = *model.mesh;
  const Eigen::Vector3d extent =
      m.rest_positions.colwise().maxCoeff() - m.rest_positions.colwise().minCoeff();
  Mesh shifted = m;
  shifted.rest_positions =
      translated(m.rest_positions, 0.1 * extent.maxCoeff() * Eigen::Vector3d(1, 0, 0));
  Objects o(m, shifted);
  PairChecker checker(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {.accuracy = ccd::Accuracy::exact});
  const Positions xa = welded(o.topo_a, o.mesh_a.rest_positions);
  const Positions xb0 = welded(o.topo_b, o.mesh_b.rest_positions);
  const Positions xb1 = translated(xb0, 0.05 * extent.maxCoeff() * Eigen::Vector3d(0, 0, 1));
  PairFrameResult r;
  checker.detect_dcd(xa, xb0, r);
  const auto expected_dcd = brute_dcd(checker.topology_a(), xa, checker.topology_b(), xb0);
  EXPECT_GT(expected_dcd.size(), 0u);
  EXPECT_EQ(as_set(r.dcd_pairs), expected_dcd);
  EXPECT_LT(
      r.counters.candidate_pairs, static_cast<std::int64_t>(m.num_triangles() * m.num_triangles()));
  PairFrameResult c;
  checker.detect_ccd(xa, xa, xb0, xb1, c);
  const auto expected_ccd = brute_ccd(checker.topology_a(), xa, xa, checker.topology_b(), xb0, xb1);
  EXPECT_GT(expected_ccd.size(), 0u);
  EXPECT_EQ(as_set(c.contacts), expected_ccd);
}

TEST(PairChecker, RefusesBadOptionsAndWrongRowCounts) {
  Objects o(box({0, 0, 0}, {1, 1, 1}), box({2, 0, 0}, {3, 1, 1}));
  EXPECT_THROW(
      PairChecker(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {.min_separation = -1.0}), InvalidInput);
  EXPECT_THROW(
      PairChecker(
          o.mesh_a,
          o.topo_a,
          o.mesh_b,
          o.topo_b,
          {.accuracy = ccd::Accuracy::exact, .min_separation = 0.1}),
      InvalidInput);
  PairChecker checker(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b);
  PairFrameResult r;
  const Positions xa = welded(o.topo_a, o.mesh_a.rest_positions);
  EXPECT_THROW(checker.detect_dcd(xa, Positions(3, 3), r), InvalidInput);
}

TEST(PairChecker, ContactDistanceFindsBoxesCloserThanIt) {
  Objects o(box({0, 0, 0}, {1, 1, 1}), box({1.05, 0, 0}, {2.05, 1, 1}));
  const Positions xa = welded(o.topo_a, o.mesh_a.rest_positions);
  const Positions xb = welded(o.topo_b, o.mesh_b.rest_positions);
  PairChecker near(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {.min_separation = 0.1});
  PairChecker touching(o.mesh_a, o.topo_a, o.mesh_b, o.topo_b, {});
  PairFrameResult r_near, r_touch;
  near.detect_ccd(xa, xa, xb, xb, r_near);
  touching.detect_ccd(xa, xa, xb, xb, r_touch);
  EXPECT_GT(r_near.contacts.size(), 0u);
  EXPECT_EQ(r_touch.contacts.size(), 0u);
}

}  // namespace
}  // namespace skelcd::culling
