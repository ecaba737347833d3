// The DCD's fan sieve (culling/traversal.hpp, FanSieve): a self traversal with it emits exactly
// the pairs of the plain traversal that share no certified vertex (or three vertices, or have a
// degenerate triangle), and counts exactly the others that are not part-excluded — against a
// reference written here from the triangles' corners, on a real character with its own fans and
// with random certificates, and on a mesh with exclusions, a degenerate and a duplicate face.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "culling/candidates.hpp"
#include "culling/feature_topology.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "culling/vertex_fans.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

struct Expected {
  std::vector<TrianglePair> emitted;
  std::int64_t settled = 0;
  std::int64_t near = 0;  ///< settled pairs within SlotAdjacency::kReach slots of each other
  std::int64_t far = 0;   ///< settled pairs farther apart (the sieve's pair-by-pair path)
};

/// From the plain traversal's pairs: which the sieve must let through, and how many it counts.
Expected reference(
    const FeatureTopology& ft,
    const Bvh<3>& bvh,
    const std::vector<TrianglePair>& all,
    const std::vector<std::uint8_t>& certified) {
  std::vector<std::int32_t> slot(static_cast<std::size_t>(ft.num_triangles()), -1);
  const auto order = bvh.triangle_order();
  for (std::size_t s = 0; s < order.size(); ++s) {
    slot[static_cast<std::size_t>(order[s])] = static_cast<std::int32_t>(s);
  }
  Expected e;
  for (const TrianglePair& p : all) {
    const auto& a = ft.triangle(p.a);
    const auto& b = ft.triangle(p.b);
    const auto degenerate = [](const std::array<std::int32_t, 3>& t) {
      return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    };
    int shared = 0;
    bool any_certified = false;
    for (const std::int32_t v : a) {
      if (std::find(b.begin(), b.end(), v) == b.end()) continue;
      ++shared;
      any_certified = any_certified || certified[static_cast<std::size_t>(v)] != 0;
    }
    const bool settles =
        !degenerate(a) && !degenerate(b) && shared > 0 && shared < 3 && any_certified;
    if (!settles) {
      e.emitted.push_back(p);
      continue;
    }
    if (ft.triangles_excluded(p.a, p.b)) continue;
    ++e.settled;
    const std::int32_t gap =
        std::abs(slot[static_cast<std::size_t>(p.a)] - slot[static_cast<std::size_t>(p.b)]);
    ++(gap < SlotAdjacency::kReach ? e.near : e.far);
  }
  std::sort(e.emitted.begin(), e.emitted.end());
  return e;
}

/// Plain and sieved traversals of the DCD volumes at x, in installments of `max_pairs`.
void check(
    const std::string& name,
    const FeatureTopology& ft,
    const skinning::Positions& x,
    const std::vector<std::uint8_t>& certified,
    std::size_t max_pairs,
    bool expect_far) {
  SCOPED_TRACE(name);
  const Bvh<3> built(ft.welded_triangles(), x);
  Bvh<3> bvh = built;
  FeatureBounds<3> bounds;
  static_vertex_bounds<3>(x, bounds.vertices);
  bounds.derive(ft, /*with_edges=*/false);
  bvh.refit(bounds.triangles);
  TraversalScratch scratch;
  std::vector<TrianglePair> all;
  std::int64_t plain_tests = 0;
  self_traverse<3>(bvh, bounds.triangles, scratch, all, plain_tests);
  const Expected e = reference(ft, bvh, all, certified);
  ASSERT_GT(e.near, 0) << "the window path is exercised";
  if (expect_far) {
    ASSERT_GT(e.far, 0) << "the pair-by-pair path is exercised";
  }

  const SlotAdjacency slots(ft, bvh.triangle_order());
  std::vector<std::uint8_t> full;
  certified_slots(slots, certified, full);
  FanSieve sieve{.slots = &slots, .certified = certified, .full = full, .topology = &ft};
  start_self_traversal<3>(bvh, scratch);
  std::vector<TrianglePair> emitted;
  std::vector<TrianglePair> block;
  std::int64_t sieved_tests = 0;
  for (bool done = false; !done;) {
    done = self_traverse_some<3>(
        bvh, bounds.triangles, scratch, block, sieved_tests, max_pairs, &sieve);
    emitted.insert(emitted.end(), block.begin(), block.end());
    block.clear();
  }
  std::sort(emitted.begin(), emitted.end());
  EXPECT_EQ(emitted, e.emitted);
  EXPECT_EQ(sieve.settled, e.settled);
  EXPECT_EQ(sieved_tests, plain_tests) << "the sieve changes no volume test";
}

std::vector<std::uint8_t> random_flags(std::int32_t n, std::uint32_t seed, double p) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution coin(p);
  std::vector<std::uint8_t> out(static_cast<std::size_t>(n));
  for (auto& f : out) f = coin(rng) ? 1 : 0;
  return out;
}

/// A tube with a duplicate of face 0 (reversed) and a degenerate face on an edge of face 1, its
/// faces in two parts never checked against each other: face i in part 1 when every_other, else
/// when i % 3 == 0 (so that some neighbours share a part and some do not).
skinning::Mesh tube_with_parts(bool every_other) {
  skinning::Mesh m = test::tube(12, 16, 0.5, 3.0);
  const auto f = static_cast<Eigen::Index>(m.triangles.rows());
  m.triangles.conservativeResize(f + 2, 3);
  m.triangles.row(f) << m.triangles(0, 0), m.triangles(0, 2), m.triangles(0, 1);
  m.triangles.row(f + 1) << m.triangles(1, 0), m.triangles(1, 1), m.triangles(1, 1);
  m.part_names = {"first", "second"};
  m.face_part.resize(static_cast<std::size_t>(f + 2));
  m.face_index_in_part.resize(static_cast<std::size_t>(f + 2));
  std::array<std::int32_t, 2> in_part{0, 0};
  for (Eigen::Index i = 0; i < f + 2; ++i) {
    const std::int32_t part = every_other ? static_cast<std::int32_t>(i % 2) : (i % 3 == 0 ? 1 : 0);
    m.face_part[static_cast<std::size_t>(i)] = part;
    m.face_index_in_part[static_cast<std::size_t>(i)] = in_part[static_cast<std::size_t>(part)]++;
  }
  m.excluded_part_pairs = {{0, 1}};
  return m;
}

/// SlotAdjacency's corners and windows against their definition, slot pair by slot pair: bit d of
/// window[s] set exactly when slot o = s + d − kReach (o ≠ s) holds a triangle sharing one or two
/// vertices with slot s's, neither degenerate, their parts not excluded.
void check_windows(const std::string& name, const FeatureTopology& ft, const Bvh<3>& bvh) {
  SCOPED_TRACE(name);
  const auto order = bvh.triangle_order();
  const SlotAdjacency slots(ft, order);
  ASSERT_EQ(slots.corners.size(), order.size());
  ASSERT_EQ(slots.window.size(), order.size());
  const auto degenerate = [](const std::array<std::int32_t, 3>& t) {
    return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
  };
  const auto n = static_cast<std::int32_t>(order.size());
  std::int64_t bits = 0;
  for (std::int32_t s = 0; s < n; ++s) {
    const auto& a = ft.triangle(order[static_cast<std::size_t>(s)]);
    const std::array<std::int32_t, 4> corners =
        degenerate(a) ? std::array<std::int32_t, 4>{-1, -1, -1, -1}
                      : std::array<std::int32_t, 4>{a[0], a[1], a[2], -1};
    ASSERT_EQ(slots.corners[static_cast<std::size_t>(s)], corners) << "slot " << s;
    std::uint64_t expected = 0;
    for (std::int32_t d = 0; d < 2 * SlotAdjacency::kReach; ++d) {
      const std::int32_t o = s + d - SlotAdjacency::kReach;
      if (o == s || o < 0 || o >= n) continue;
      const auto& b = ft.triangle(order[static_cast<std::size_t>(o)]);
      if (degenerate(a) || degenerate(b)) continue;
      const auto shared = std::count_if(a.begin(), a.end(), [&](std::int32_t v) {
        return std::find(b.begin(), b.end(), v) != b.end();
      });
      if (shared == 0 || shared == 3) continue;
      if (ft.triangles_excluded(
              order[static_cast<std::size_t>(s)], order[static_cast<std::size_t>(o)])) {
        continue;
      }
      expected |= std::uint64_t{1} << d;
    }
    ASSERT_EQ(slots.window[static_cast<std::size_t>(s)], expected) << "slot " << s;
    bits += std::popcount(expected);
  }
  EXPECT_GT(bits, n) << "most slots have neighbours in their window";
}

TEST(FanSieve, SlotWindowsHoldExactlyTheNeighboursSharingOneOrTwoVertices) {
  for (const char* asset :
       {"characters/CesiumMan.glb", "characters/stormtrooper/stormtrooper.dae"}) {
    const auto model = skinning::load_model(test::asset(asset));
    const skinning::Topology topo = skinning::build_topology(*model.mesh);
    const FeatureTopology ft(*model.mesh, topo);
    const skinning::Positions x = test::welded(topo, model.mesh->rest_positions);
    check_windows(asset, ft, Bvh<3>(ft.welded_triangles(), x));
  }
  // Parts never checked against each other, a duplicate face and a degenerate one.
  const skinning::Mesh m = tube_with_parts(/*every_other=*/false);
  const skinning::Topology topo = test::simple_topology(m);
  const FeatureTopology ft(m, topo);
  check_windows(
      "tube with parts", ft, Bvh<3>(ft.welded_triangles(), test::welded(topo, m.rest_positions)));
}

TEST(FanSieve, SettlesExactlyThePairsSharingACertifiedVertexOnARealCharacter) {
  const auto model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  const skinning::Mesh& mesh = *model.mesh;
  const skinning::Topology topo = skinning::build_topology(mesh);
  const FeatureTopology ft(mesh, topo);
  const auto motion = model.motion();
  skinning::Positions posed, x;
  motion->positions(motion->num_samples() / 2, posed);
  skinning::gather_welded(topo, posed, x);
  std::vector<std::uint8_t> fans;
  ft.fans().certify(x, fans);
  const auto certified_count = std::count(fans.begin(), fans.end(), 1);
  ASSERT_GT(certified_count, 0);
  ASSERT_LT(certified_count, static_cast<std::ptrdiff_t>(fans.size())) << "some fans refuse";
  check("CesiumMan, its fans", ft, x, fans, 4096, true);
  check("CesiumMan, its fans, installments of 1", ft, x, fans, 1, true);
  // Random certificates: slots with every corner certified and slots without, side by side.
  for (const double p : {0.3, 0.9}) {
    check(
        "CesiumMan, random certificates p = " + std::to_string(p),
        ft,
        x,
        random_flags(ft.num_vertices(), 7, p),
        4096,
        true);
  }
}

TEST(FanSieve, LeavesExcludedDegenerateAndDuplicatePairsToTheFilter) {
  // Two parts, every other face, never checked against each other.
  const skinning::Mesh m = tube_with_parts(/*every_other=*/true);
  const skinning::Topology topo = test::simple_topology(m);
  const FeatureTopology ft(m, topo);
  const skinning::Positions x = test::welded(topo, m.rest_positions);
  ASSERT_TRUE(ft.triangles_excluded(0, 1));
  for (const double p : {0.5, 1.0}) {
    check(
        "tube with parts, p = " + std::to_string(p),
        ft,
        x,
        random_flags(ft.num_vertices(), 11, p),
        64,
        false);
  }
}

}  // namespace
}  // namespace skelcd::culling
