// Ghost caps (clustering/ghost_caps.hpp): small boundary loops closed by fans around their mean,
// consistently oriented, the real mesh's ids kept; loops that are too long or pinched stay open.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <vector>

#include "clustering/ghost_caps.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::clustering {
namespace {

using V3 = Eigen::Vector3d;

skinning::Mesh make_mesh(const std::vector<V3>& vs, const std::vector<Eigen::Vector3i>& fs) {
  skinning::Positions x(static_cast<Eigen::Index>(vs.size()), 3);
  for (std::size_t i = 0; i < vs.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = vs[i];
  skinning::Triangles t(static_cast<Eigen::Index>(fs.size()), 3);
  for (std::size_t f = 0; f < fs.size(); ++f) t.row(static_cast<Eigen::Index>(f)) = fs[f];
  return test::single_part_mesh(std::move(x), std::move(t));
}

/// An open tube along x: `rings` rings of `sides` vertices, outward faces, both ends open.
skinning::Mesh open_tube(int rings, int sides, double radius = 0.5) {
  std::vector<V3> vs;
  std::vector<Eigen::Vector3i> fs;
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < sides; ++s) {
      const double a = 2.0 * std::numbers::pi * s / sides;
      vs.emplace_back(0.3 * r, radius * std::cos(a), radius * std::sin(a));
    }
  }
  const auto id = [&](int r, int s) { return r * sides + (s % sides); };
  for (int r = 0; r + 1 < rings; ++r) {
    for (int s = 0; s < sides; ++s) {
      fs.emplace_back(id(r, s), id(r, s + 1), id(r + 1, s + 1));
      fs.emplace_back(id(r, s), id(r + 1, s + 1), id(r + 1, s));
    }
  }
  return make_mesh(vs, fs);
}

segmentation::Segmentation two_clusters(const skinning::Mesh& m) {
  segmentation::Segmentation seg;
  const auto nf = static_cast<std::size_t>(m.num_triangles());
  seg.clusters.resize(2);
  for (std::size_t f = 0; f < nf; ++f) {
    const int c = f < nf / 2 ? 0 : 1;
    seg.triangle_cluster.push_back(c);
    seg.clusters[static_cast<std::size_t>(c)].triangles.push_back(static_cast<std::int32_t>(f));
  }
  return seg;
}

double volume(const skinning::Positions& x, const skinning::Triangles& t) {
  double v = 0.0;
  for (Eigen::Index f = 0; f < t.rows(); ++f) {
    const V3 a = x.row(t(f, 0)), b = x.row(t(f, 1)), c = x.row(t(f, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

TEST(GhostCaps, AnOpenTubeIsClosedConsistentlyAndKeepsItsIds) {
  const skinning::Mesh mesh = open_tube(6, 12);
  const skinning::Topology topology = skinning::build_topology(mesh);
  ASSERT_EQ(topology.boundary_loops.size(), 2u);
  const auto seg = two_clusters(mesh);
  const auto caps = cap_small_loops(mesh, topology, seg, 64, 0);
  ASSERT_NE(caps, nullptr);
  EXPECT_EQ(caps->num_loops(), 2);
  const auto& t = caps->topology;
  EXPECT_TRUE(t.boundary_edges.empty());
  EXPECT_TRUE(t.non_manifold_edges.empty());
  ASSERT_EQ(t.components.size(), 1u);
  EXPECT_TRUE(t.components[0].closed);
  // Every edge is traversed once each way by its two faces: consistently oriented.
  std::map<std::pair<std::int32_t, std::int32_t>, int> directed;
  for (Eigen::Index f = 0; f < t.welded_triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      ++directed[{t.welded_triangles(f, k), t.welded_triangles(f, (k + 1) % 3)}];
    }
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
  // Outward: the capped volume is the prism of the 12-gon (both caps are flat, centred).
  skinning::Positions x;
  skinning::gather_welded(t, caps->mesh.rest_positions, x);
  const double polygon = 0.5 * 12 * 0.25 * std::sin(2.0 * std::numbers::pi / 12);
  EXPECT_NEAR(volume(x, t.welded_triangles), polygon * 1.5, 1e-12);
  // The real triangles and vertices keep their welded ids; the edge map finds the real edges.
  for (Eigen::Index f = 0; f < topology.welded_triangles.rows(); ++f) {
    EXPECT_EQ(t.welded_triangles.row(f), topology.welded_triangles.row(f));
  }
  int spokes = 0;
  for (std::int32_t e = 0; e < t.num_edges(); ++e) {
    const std::int32_t r = caps->real_edge[static_cast<std::size_t>(e)];
    if (r < 0) {
      ++spokes;
      continue;
    }
    EXPECT_EQ(
        std::minmax(t.edges(e, 0), t.edges(e, 1)),
        std::minmax(topology.edges(r, 0), topology.edges(r, 1)));
  }
  EXPECT_EQ(spokes, 24);
  // Each ghost is in the cluster of the real triangle across its loop edge.
  ASSERT_EQ(
      caps->segmentation->triangle_cluster.size(),
      static_cast<std::size_t>(mesh.num_triangles() + 24));
  for (Eigen::Index g = mesh.num_triangles(); g < t.welded_triangles.rows(); ++g) {
    const auto e = t.face_edges(g, 0);  // (to, from): the loop edge
    std::int32_t real_face = -1;
    for (auto i = t.edge_face_offsets[static_cast<std::size_t>(e)];
         i < t.edge_face_offsets[static_cast<std::size_t>(e) + 1];
         ++i) {
      const auto f = t.edge_faces[static_cast<std::size_t>(i)];
      if (f < mesh.num_triangles()) real_face = f;
    }
    ASSERT_GE(real_face, 0);
    EXPECT_EQ(
        caps->segmentation->triangle_cluster[static_cast<std::size_t>(g)],
        seg.triangle_cluster[static_cast<std::size_t>(real_face)]);
  }
  // The centres follow the loops: the mean of the moved loop.
  skinning::Positions real_x;
  skinning::gather_welded(topology, mesh.rest_positions, real_x);
  real_x.col(1) *= 2.0;
  skinning::Positions capped;
  place_ghost_centres(*caps, real_x, capped);
  ASSERT_EQ(capped.rows(), real_x.rows() + 2);
  EXPECT_EQ(capped.topRows(real_x.rows()), real_x);
  const double end_a = capped(real_x.rows(), 0), end_b = capped(real_x.rows() + 1, 0);
  EXPECT_NEAR(std::min(end_a, end_b), 0.0, 1e-12);  // one cap at each end of the tube
  EXPECT_NEAR(std::max(end_a, end_b), 1.5, 1e-12);
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(capped(real_x.rows() + j, 1), 0.0, 1e-12);
    EXPECT_NEAR(capped(real_x.rows() + j, 2), 0.0, 1e-12);
  }
}

TEST(GhostCaps, LongLoopsStayOpenPinchedOnesAreSplit) {
  const skinning::Mesh tube = open_tube(4, 40);
  const skinning::Topology tube_topology = skinning::build_topology(tube);
  EXPECT_EQ(cap_small_loops(tube, tube_topology, two_clusters(tube), 39, 0), nullptr);
  const auto caps = cap_small_loops(tube, tube_topology, two_clusters(tube), 40, 0);
  ASSERT_NE(caps, nullptr);
  EXPECT_EQ(caps->num_loops(), 2);
  // Two open tubes sharing one vertex of their end rings: the boundary passes that vertex twice.
  // Split there, each ring gets its own fan (one spoke per fan at the shared vertex), and the
  // capped surface has no boundary and no non-manifold edge.
  skinning::Mesh pinched = open_tube(3, 8);
  {
    const skinning::Mesh other = open_tube(3, 8);
    const auto nv = static_cast<std::int32_t>(pinched.num_vertices());
    const auto nf = pinched.num_triangles();
    skinning::Positions v(2 * nv, 3);
    v << pinched.rest_positions, other.rest_positions;
    // The second tube mirrored beyond x = 0, its ring 0 touching the first's at vertex 0 only.
    for (Eigen::Index i = nv; i < 2 * nv; ++i) {
      v(i, 0) = -v(i, 0);
      v(i, 1) = -v(i, 1) + 2.0 * v(0, 1);
      v(i, 2) = -v(i, 2) + 2.0 * v(0, 2);
    }
    skinning::Triangles t(2 * nf, 3);
    t.topRows(nf) = pinched.triangles;
    t.bottomRows(nf) = other.triangles.array() + nv;
    for (Eigen::Index f = nf; f < 2 * nf; ++f) std::swap(t(f, 1), t(f, 2));  // mirrored: flip
    std::vector<V3> vs;
    for (Eigen::Index i = 0; i < v.rows(); ++i) vs.emplace_back(v.row(i).transpose());
    std::vector<Eigen::Vector3i> fs;
    for (Eigen::Index f = 0; f < t.rows(); ++f) fs.emplace_back(t.row(f).transpose());
    pinched = make_mesh(vs, fs);
  }
  const skinning::Topology pinched_topology = skinning::build_topology(pinched);
  ASSERT_EQ(pinched_topology.components.size(), 2u);  // edge-connected: two, sharing a vertex
  const auto split = cap_small_loops(pinched, pinched_topology, two_clusters(pinched), 64, 0);
  ASSERT_NE(split, nullptr);
  EXPECT_EQ(split->num_loops(), 4);  // the two far rings, and the pinched pair split in two
  EXPECT_TRUE(split->topology.boundary_edges.empty());
  EXPECT_TRUE(split->topology.non_manifold_edges.empty());
  // A segmentation that does not fit: no caps (the method reports the mismatch).
  segmentation::Segmentation short_seg = two_clusters(tube);
  short_seg.triangle_cluster.pop_back();
  EXPECT_EQ(cap_small_loops(tube, tube_topology, short_seg, 64, 0), nullptr);
}

TEST(GhostCaps, APartIsCappedWholeAndOnlyWhenLargeEnough) {
  // 6 rings of 12 sides: 120 triangles, two end loops of 12 sides (24 ghosts).
  const skinning::Mesh tube = open_tube(6, 12);
  const skinning::Topology topology = skinning::build_topology(tube);
  const auto seg = two_clusters(tube);
  const auto triangles = tube.num_triangles();
  const auto per_side = static_cast<std::int32_t>(triangles / 24);
  ASSERT_EQ(triangles % 24, 0);
  ASSERT_NE(cap_small_loops(tube, topology, seg, 64, per_side), nullptr);
  EXPECT_EQ(cap_small_loops(tube, topology, seg, 64, per_side + 1), nullptr);
  EXPECT_EQ(skinning::closing_loops(topology, 64, per_side).size(), 2u);
  EXPECT_TRUE(skinning::closing_loops(topology, 64, per_side + 1).empty());
  // A triangle taken out of its side makes a third hole, of 3 sides. With loops of up to 11
  // sides only that hole could be closed, which would leave the part open: nothing is capped.
  // Up to 12, all three: capped.
  std::vector<V3> vs;
  for (Eigen::Index i = 0; i < tube.rest_positions.rows(); ++i) {
    vs.emplace_back(tube.rest_positions.row(i).transpose());
  }
  std::vector<Eigen::Vector3i> fs;
  for (Eigen::Index f = 0; f < tube.triangles.rows(); ++f) {
    if (f != 30) fs.emplace_back(tube.triangles.row(f).transpose());
  }
  const skinning::Mesh holed = make_mesh(vs, fs);
  const skinning::Topology holed_topology = skinning::build_topology(holed);
  ASSERT_EQ(skinning::small_simple_loops(holed_topology, 11).size(), 1u);
  EXPECT_TRUE(skinning::closing_loops(holed_topology, 11, 0).empty());
  EXPECT_EQ(cap_small_loops(holed, holed_topology, two_clusters(holed), 11, 0), nullptr);
  const auto all = cap_small_loops(holed, holed_topology, two_clusters(holed), 12, 0);
  ASSERT_NE(all, nullptr);
  EXPECT_EQ(all->num_loops(), 3);
  EXPECT_TRUE(all->topology.boundary_edges.empty());
}

}  // namespace
}  // namespace skelcd::clustering
