// Topology on meshes whose answers are known by construction: cube, seamed cube, sheet,
// non-manifold fan, degenerate triangles.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "skinning/detail/exact_collinear.hpp"
#include "skinning/errors.hpp"
#include "skinning/topology.hpp"
#include "tests/skinning/mini_meshes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

using test::make_mesh;

// Every edge lists its faces, every face side its edge, and the two agree; the edges are
// (smaller, larger) pairs in increasing order (what ghost caps' edge merge relies on).
void expect_consistent(const Mesh& mesh, const Topology& topo) {
  ASSERT_EQ(topo.face_edges.rows(), mesh.num_triangles());
  for (std::int32_t e = 0; e < topo.num_edges(); ++e) {
    EXPECT_LT(topo.edges(e, 0), topo.edges(e, 1)) << "edge " << e;
    if (e > 0) {
      EXPECT_LT(
          std::make_pair(topo.edges(e - 1, 0), topo.edges(e - 1, 1)),
          std::make_pair(topo.edges(e, 0), topo.edges(e, 1)))
          << "edge " << e;
    }
  }
  for (Eigen::Index f = 0; f < mesh.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto e = topo.face_edges(f, k);
      const auto a = topo.welded_triangles(f, k);
      const auto b = topo.welded_triangles(f, (k + 1) % 3);
      if (a == b) {
        EXPECT_EQ(e, -1);
        continue;
      }
      ASSERT_GE(e, 0);
      EXPECT_EQ(topo.edges(e, 0), std::min(a, b));
      EXPECT_EQ(topo.edges(e, 1), std::max(a, b));
      bool listed = false;
      for (auto i = topo.edge_face_offsets[std::size_t(e)]; i < topo.edge_face_offsets[std::size_t(e) + 1]; ++i) {
        listed |= topo.edge_faces[std::size_t(i)] == f;
      }
      EXPECT_TRUE(listed) << "face " << f << " not listed on edge " << e;
    }
  }
  for (std::size_t v = 0; v < topo.welded_of_vertex.size(); ++v) {
    const auto w = topo.welded_of_vertex[v];
    EXPECT_EQ(mesh.rest_positions.row(Eigen::Index(v)),
              mesh.rest_positions.row(topo.representative_vertex[std::size_t(w)]));
  }
}

TEST(Topology, CubeIsClosedWithTwelveFacesAndEighteenEdges) {
  const auto cube = test::shared_cube();
  const auto topo = build_topology(cube);
  expect_consistent(cube, topo);
  EXPECT_EQ(topo.welded_triangles.rows(), 12);
  EXPECT_EQ(topo.num_edges(), 18);
  EXPECT_EQ(topo.num_welded_vertices(), 8);
  EXPECT_TRUE(topo.boundary_edges.empty());
  EXPECT_TRUE(topo.boundary_loops.empty());
  EXPECT_TRUE(topo.non_manifold_edges.empty());
  EXPECT_TRUE(topo.degenerate_triangles.empty());
  ASSERT_EQ(topo.components.size(), 1u);
  EXPECT_TRUE(topo.components[0].closed);
  EXPECT_EQ(topo.components[0].faces.size(), 12u);
  // Each face has three neighbours, and adjacency is symmetric.
  for (Eigen::Index f = 0; f < 12; ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto g = topo.face_adjacency(f, k);
      ASSERT_GE(g, 0);
      EXPECT_TRUE((topo.face_adjacency.row(g).array() == std::int32_t(f)).any());
    }
  }
}

TEST(Topology, WeldingRemovesTheSeamsOfAPerFaceCube) {
  const auto cube = test::seamed_cube();
  const auto welded = build_topology(cube);
  expect_consistent(cube, welded);
  EXPECT_EQ(welded.num_welded_vertices(), 8);
  EXPECT_EQ(welded.num_edges(), 18);
  EXPECT_TRUE(welded.boundary_edges.empty());
  ASSERT_EQ(welded.components.size(), 1u);
  EXPECT_TRUE(welded.components[0].closed);
  // Without welding the same file is six open squares, each with one boundary loop of 4.
  const auto raw = build_topology(cube, WeldOptions{.weld = false});
  EXPECT_EQ(raw.num_welded_vertices(), 24);
  EXPECT_EQ(raw.components.size(), 6u);
  EXPECT_EQ(raw.boundary_edges.size(), 24u);
  ASSERT_EQ(raw.boundary_loops.size(), 6u);
  for (const auto& loop : raw.boundary_loops) EXPECT_EQ(loop.size(), 4u);
}

TEST(Topology, OpenSheetHasOneBoundaryLoopAroundItsRim) {
  const int n = 5, m = 3;
  const auto s = test::sheet(n, m);
  const auto topo = build_topology(s);
  expect_consistent(s, topo);
  EXPECT_EQ(topo.welded_triangles.rows(), 2 * n * m);
  // Edges of an n × m grid: horizontal + vertical + one diagonal per quad.
  EXPECT_EQ(topo.num_edges(), n * (m + 1) + m * (n + 1) + n * m);
  EXPECT_EQ(topo.boundary_edges.size(), std::size_t(2 * (n + m)));
  ASSERT_EQ(topo.boundary_loops.size(), 1u);
  const auto& loop = topo.boundary_loops[0];
  EXPECT_EQ(loop.size(), std::size_t(2 * (n + m)));
  // The loop visits each rim vertex once, and consecutive vertices share a boundary edge.
  EXPECT_EQ(std::set<std::int32_t>(loop.begin(), loop.end()).size(), loop.size());
  std::set<std::pair<std::int32_t, std::int32_t>> boundary;
  for (auto e : topo.boundary_edges) boundary.insert({topo.edges(e, 0), topo.edges(e, 1)});
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const auto a = loop[i];
    const auto b = loop[(i + 1) % loop.size()];
    EXPECT_TRUE(boundary.count({std::min(a, b), std::max(a, b)})) << a << "-" << b;
  }
  ASSERT_EQ(topo.components.size(), 1u);
  EXPECT_FALSE(topo.components[0].closed);
}

TEST(Topology, ThreeTrianglesOnOneEdgeMakeANonManifoldEdge) {
  // Edge (0,1) shared by three fins.
  const auto mesh = make_mesh(
      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
      {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  const auto topo = build_topology(mesh);
  expect_consistent(mesh, topo);
  ASSERT_EQ(topo.non_manifold_edges.size(), 1u);
  const auto e = topo.non_manifold_edges[0];
  EXPECT_EQ(topo.edges(e, 0), 0);
  EXPECT_EQ(topo.edges(e, 1), 1);
  EXPECT_EQ(topo.edge_face_offsets[std::size_t(e) + 1] - topo.edge_face_offsets[std::size_t(e)], 3);
  ASSERT_EQ(topo.components.size(), 1u);
  EXPECT_FALSE(topo.components[0].closed);
}

TEST(Topology, TwoSeparateCubesAreTwoClosedComponentsInTheirParts) {
  auto mesh = test::shared_cube();
  auto other = test::shared_cube();
  other.rest_positions.col(0).array() += 3.0;
  test::append_part(mesh, other);
  const auto topo = build_topology(mesh);
  ASSERT_EQ(topo.components.size(), 2u);
  EXPECT_TRUE(topo.components[0].closed);
  EXPECT_TRUE(topo.components[1].closed);
  EXPECT_EQ(topo.components[0].part, 0);
  EXPECT_EQ(topo.components[1].part, 1);
  EXPECT_EQ(topo.face_component[0], 0);
  EXPECT_EQ(topo.face_component[12], 1);
}

TEST(Topology, RepeatedIndexAndZeroAreaTrianglesAreDegenerate) {
  // Triangle 0: fine. 1: repeated index. 2: three distinct, exactly collinear points with
  // non-trivial coordinates (a, a + d, a + 2d, all exact in binary). 3: the same with the last
  // point one ulp off the line: not degenerate. 4: two distinct vertices at the same position.
  const Eigen::Vector3d a(1.5, -2.25, 3.0);
  const Eigen::Vector3d d(0.125, 0.375, -0.5);
  Eigen::Vector3d off = a + 2 * d;
  off.z() = std::nextafter(off.z(), 10.0);
  const auto mesh = make_mesh(
      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, a, a + d, a + 2 * d, off, {0, 1, 0}},
      {{0, 1, 2}, {0, 0, 1}, {3, 4, 5}, {3, 4, 6}, {0, 2, 7}});
  const auto topo = build_topology(mesh);
  expect_consistent(mesh, topo);
  EXPECT_EQ(topo.degenerate_triangles, (std::vector<std::int32_t>{1, 2, 4}));
}

TEST(Topology, VerticesOneUlpApartAreNotWelded) {
  const double x = std::nextafter(1.0, 2.0);
  const auto mesh = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {x, 0, 0}, {1, 1, 0}},
                              {{0, 1, 2}, {3, 4, 2}});
  const auto topo = build_topology(mesh);
  EXPECT_EQ(topo.num_welded_vertices(), 5);
  EXPECT_EQ(topo.components.size(), 2u);
}

TEST(Topology, NegativeZeroWeldsWithZero) {
  const auto mesh = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-0.0, 0, 0}}, {{0, 1, 2}, {3, 2, 1}});
  const auto topo = build_topology(mesh);
  EXPECT_EQ(topo.num_welded_vertices(), 3);
  EXPECT_EQ(topo.welded_of_vertex[3], 0);
}

TEST(Topology, GatherWeldedTakesTheRepresentatives) {
  const auto cube = test::seamed_cube();
  const auto topo = build_topology(cube);
  Positions moved = cube.rest_positions * 2.0;
  Positions welded;
  gather_welded(topo, moved, welded);
  ASSERT_EQ(welded.rows(), 8);
  for (Eigen::Index w = 0; w < 8; ++w) {
    EXPECT_EQ(welded.row(w), moved.row(topo.representative_vertex[std::size_t(w)]));
  }
}

TEST(Topology, RefusesNonFinitePositions) {
  auto cube = test::shared_cube();
  cube.rest_positions(3, 1) = std::numeric_limits<double>::infinity();
  EXPECT_THROW_MESSAGE((void)build_topology(cube), InvalidInput, "vertex 3");
}

TEST(ExactCollinear, DecidesCasesTheFilterCannot) {
  using detail::exactly_collinear;
  // Exactly collinear along a direction with no zero component (scalings by 2 are exact).
  const Eigen::Vector3d a(0.1, 0.2, 0.3);
  EXPECT_TRUE(exactly_collinear(a, 2 * a, 4 * a));
  Eigen::Vector3d bent = 4 * a;
  bent.y() = std::nextafter(bent.y(), 1.0);
  EXPECT_FALSE(exactly_collinear(a, 2 * a, bent));
  // Tiny coordinates: every product underflows to zero in floating point, so a naive test
  // calls all of these degenerate; only the first is.
  const Eigen::Vector3d o(0, 0, 0);
  const Eigen::Vector3d b(1e-200, 3e-200, 0);
  EXPECT_TRUE(exactly_collinear(o, b, 2 * b));
  Eigen::Vector3d c = 2 * b;
  c.y() = std::nextafter(c.y(), 1.0);
  EXPECT_FALSE(exactly_collinear(o, b, c));
  // Coincident points.
  EXPECT_TRUE(exactly_collinear({5, 5, 5}, {5, 5, 5}, {1, 2, 3}));
  EXPECT_FALSE(exactly_collinear({0, 0, 0}, {1, 0, 0}, {0, 0, 1}));
}

}  // namespace
}  // namespace skelcd::skinning
