// FeatureTopology's owner order (clustering::RadialViewMethod takes the cluster rims first): any
// permutation gives every vertex and edge exactly one owner — its first incident triangle in that
// order — and the CCD feature stage then yields every feature pair exactly once, as with the
// default order. A list that is not a permutation is rejected.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "culling/candidates.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::culling {
namespace {

std::vector<skinning::Mesh> meshes() {
  std::vector<skinning::Mesh> out;
  out.push_back(test::tube(9, 7, 0.5, 2.0));
  out.push_back(test::sheet(7, 5, 2.0, 1.0));
  auto collapsed = test::sheet(6, 4, 2.0, 1.0);  // welding collapses some sides to -1
  collapsed.rest_positions.row(9) = collapsed.rest_positions.row(8);
  out.push_back(collapsed);
  return out;
}

std::vector<std::vector<std::int32_t>> orders(std::int32_t n, std::mt19937& rng) {
  std::vector<std::int32_t> id(static_cast<std::size_t>(n));
  std::iota(id.begin(), id.end(), 0);
  std::vector<std::vector<std::int32_t>> out{id, {id.rbegin(), id.rend()}};
  for (int i = 0; i < 3; ++i) {
    std::shuffle(id.begin(), id.end(), rng);
    out.push_back(id);
  }
  return out;
}

TEST(FeatureTopology, AnyOwnerOrderGivesEachFeatureItsFirstIncidentTriangle) {
  std::mt19937 rng(3);
  for (const auto& mesh : meshes()) {
    const auto topology = test::simple_topology(mesh);
    const auto n = static_cast<std::int32_t>(topology.welded_triangles.rows());
    for (const auto& order : orders(n, rng)) {
      const FeatureTopology t(mesh, topology, order);
      std::vector<std::int32_t> position(static_cast<std::size_t>(n));
      for (std::size_t i = 0; i < order.size(); ++i) {
        position[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
      }
      // The first incident triangle in the order, for every vertex and edge.
      std::map<std::int32_t, std::int32_t> first_vertex, first_edge;
      const auto earlier =
          [&](std::map<std::int32_t, std::int32_t>& first, std::int32_t key, std::int32_t f) {
            const auto [it, added] = first.try_emplace(key, f);
            if (!added && position[static_cast<std::size_t>(f)] <
                              position[static_cast<std::size_t>(it->second)]) {
              it->second = f;
            }
          };
      for (std::int32_t f = 0; f < n; ++f) {
        for (int k = 0; k < 3; ++k) {
          earlier(first_vertex, t.triangle(f)[static_cast<std::size_t>(k)], f);
          if (t.face_edge(f, k) >= 0) earlier(first_edge, t.face_edge(f, k), f);
        }
      }
      std::vector<int> vertex_owned(static_cast<std::size_t>(t.num_vertices()), 0);
      std::vector<int> edge_owned(static_cast<std::size_t>(t.num_edges()), 0);
      for (std::int32_t f = 0; f < n; ++f) {
        const auto& o = t.owned_features(f);
        for (std::size_t i = 0; i < o.num_vertices; ++i) {
          ++vertex_owned[static_cast<std::size_t>(o.vertices[i])];
          EXPECT_EQ(first_vertex.at(o.vertices[i]), f);
          EXPECT_EQ(t.vertex_owner(o.vertices[i]), f);
        }
        for (std::size_t i = 0; i < o.num_edges; ++i) {
          ++edge_owned[static_cast<std::size_t>(o.edges[i])];
          EXPECT_EQ(first_edge.at(o.edges[i]), f);
          EXPECT_EQ(t.edge_owner(o.edges[i]), f);
        }
      }
      for (const auto& [v, f] : first_vertex) {
        EXPECT_EQ(vertex_owned[static_cast<std::size_t>(v)], 1) << "vertex " << v;
      }
      for (const int c : edge_owned) EXPECT_EQ(c, 1);
    }
  }
}

TEST(FeatureTopology, AnyOwnerOrderYieldsEveryFeaturePairOnce) {
  // All triangle pairs through the feature stage against brute force's feature pairs: the same
  // set, nothing twice, whatever the order (the boxes are huge: every pair overlaps).
  std::mt19937 rng(9);
  for (const auto& mesh : meshes()) {
    const auto topology = test::simple_topology(mesh);
    const auto n = static_cast<std::int32_t>(topology.welded_triangles.rows());
    const auto x = test::welded(topology, mesh.rest_positions);
    for (const auto& order : orders(n, rng)) {
      const FeatureTopology t(mesh, topology, order);
      FeatureBounds<3> bounds;
      swept_vertex_bounds<3>(x, x, 1e3, bounds.vertices);
      bounds.derive(t);
      std::vector<TrianglePair> pairs;
      for (std::int32_t a = 0; a < n; ++a) {
        for (std::int32_t b = a + 1; b < n; ++b) pairs.push_back({a, b});
      }
      FeatureCandidates got, want;
      Counters c1, c2;
      ccd_candidates_from_triangle_pairs<3>(t, pairs, bounds, got, c1);
      ccd_candidates_brute_force<3>(t, bounds, want, c2);
      ASSERT_GT(want.vf.size(), 0u);
      ASSERT_GT(want.ee.size(), 0u);
      for (auto* c : {&got, &want}) {
        std::sort(c->vf.begin(), c->vf.end());
        std::sort(c->ee.begin(), c->ee.end());
      }
      EXPECT_EQ(std::adjacent_find(got.vf.begin(), got.vf.end()), got.vf.end());
      EXPECT_EQ(std::adjacent_find(got.ee.begin(), got.ee.end()), got.ee.end());
      EXPECT_EQ(got.vf, want.vf);
      EXPECT_EQ(got.ee, want.ee);
    }
  }
}

TEST(FeatureTopology, RejectsAnOwnerOrderThatIsNotAPermutation) {
  const auto mesh = test::tube(6, 4, 0.5, 2.0);
  const auto topology = test::simple_topology(mesh);
  const auto n = static_cast<std::int32_t>(topology.welded_triangles.rows());
  std::vector<std::int32_t> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  auto short_one = order;
  short_one.pop_back();
  auto repeated = order;
  repeated[1] = repeated[0];
  auto outside = order;
  outside[2] = n;
  for (const auto& bad : {short_one, repeated, outside}) {
    EXPECT_THROW(FeatureTopology(mesh, topology, bad), InvalidInput);
  }
  EXPECT_NO_THROW(FeatureTopology(mesh, topology, order));
}

}  // namespace
}  // namespace skelcd::culling
