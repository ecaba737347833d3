// MethodOptions::features: the runner builds one FeatureTopology and its methods and DCD updaters
// take it instead of building their own — but only one built from the very mesh and topology they
// are given. A mesh with the same triangles and other part exclusions (what `auto` hands its
// closed group) must not take it: its findings would follow the other mesh's exclusions.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "culling/detail/method_base.hpp"
#include "culling/incremental_dcd.hpp"
#include "culling/method.hpp"
#include "culling/pair_blocks.hpp"
#include "culling/sieved_dcd.hpp"
#include "culling/traversal.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::culling {
namespace {

/// Two parts: a sheet in z = 0 and a sheet standing across it (the plane y = 1.03), which cut
/// each other along a line.
skinning::Mesh crossing_sheets() {
  const skinning::Mesh flat = test::sheet(6, 6, 2.0, 2.0);
  skinning::Mesh standing = test::sheet(6, 6, 2.0, 2.0);
  for (Eigen::Index v = 0; v < standing.rest_positions.rows(); ++v) {
    const double x = standing.rest_positions(v, 0);
    const double y = standing.rest_positions(v, 1);
    standing.rest_positions.row(v) << x + 0.1, 1.03, y - 0.97;
  }
  return test::combine(flat, standing);
}

/// The sheets' rest positions with the standing sheet (part 1) 0.4 higher.
skinning::Positions standing_sheet_raised(const skinning::Mesh& mesh) {
  skinning::Positions raised = mesh.rest_positions;
  for (Eigen::Index v = 0; v < raised.rows(); ++v) {
    if (mesh.vertex_part[static_cast<std::size_t>(v)] == 1) raised(v, 2) += 0.4;
  }
  return raised;
}

/// The triangles last to first: an owner order other than triangle order.
std::vector<std::int32_t> reversed_triangles(const skinning::Topology& topology) {
  std::vector<std::int32_t> reversed;
  for (auto f = static_cast<std::int32_t>(topology.welded_triangles.rows()) - 1; f >= 0; --f) {
    reversed.push_back(f);
  }
  return reversed;
}

const FeatureTopology* features_of(const CullingMethod& m) {
  const auto* base = dynamic_cast<const detail::MethodBase*>(&m);
  return base == nullptr ? nullptr : base->shared_features().get();
}

TEST(SharedFeatures, MethodsTakeTheOptionsFeaturesOnlyWhenBuiltFromTheirMeshAndTopology) {
  const skinning::Mesh mesh = crossing_sheets();
  skinning::Mesh excluded = mesh;  // the same triangles; the two parts may not collide
  excluded.excluded_part_pairs = {{0, 1}};
  const auto topology = test::simple_topology(mesh);
  const auto x = test::welded(topology, mesh.rest_positions);
  const auto x_t0 = test::welded(topology, standing_sheet_raised(mesh));

  MethodOptions options;
  options.features = std::make_shared<const FeatureTopology>(mesh, topology);
  ASSERT_TRUE(options.features->built_from(mesh, topology));
  EXPECT_FALSE(options.features->built_from(excluded, topology));
  skinning::Topology copy = topology;
  EXPECT_FALSE(options.features->built_from(mesh, copy));
  // A topology moved into its owner after the build (what a serial check does) is still the one.
  const auto of_copy = std::make_shared<const FeatureTopology>(mesh, copy);
  const skinning::Topology moved = std::move(copy);
  EXPECT_TRUE(of_copy->built_from(mesh, moved));
  EXPECT_FALSE(of_copy->built_from(mesh, topology));
  const std::vector<std::int32_t> reversed = reversed_triangles(topology);
  const auto in_reverse = std::make_shared<const FeatureTopology>(mesh, topology, reversed);
  EXPECT_FALSE(in_reverse->built_from(mesh, topology));
  // Another owner order is still these objects' features: what a user that reads no ownership
  // (the DCD) may take, and a method may not.
  EXPECT_TRUE(in_reverse->describes(mesh, topology));
  EXPECT_FALSE(in_reverse->describes(excluded, topology));
  EXPECT_NE(shared_or_built(in_reverse, mesh, topology), in_reverse);
  EXPECT_EQ(shared_or_built(in_reverse, mesh, topology, OwnerOrder::any), in_reverse);
  EXPECT_NE(shared_or_built(in_reverse, excluded, topology, OwnerOrder::any), in_reverse);
  EXPECT_EQ(shared_or_built(options.features, mesh, topology), options.features);
  const auto built = shared_or_built(options.features, excluded, topology);
  ASSERT_NE(built, nullptr);
  EXPECT_NE(built, options.features);
  EXPECT_TRUE(built->built_from(excluded, topology));
  EXPECT_TRUE(shared_or_built(nullptr, mesh, topology)->built_from(mesh, topology));

  for (const std::string name : {"brute", "bvh", "kdop", "auto"}) {
    SCOPED_TRACE(name);
    const auto own = make_method(name, mesh, topology);
    const auto shared = make_method(name, mesh, topology, options);
    const auto other = make_method(name, excluded, topology, options);
    EXPECT_EQ(features_of(*shared), options.features.get());
    EXPECT_NE(features_of(*own), options.features.get());
    EXPECT_NE(features_of(*other), options.features.get());

    FrameResult a, b, c;
    own->detect_dcd(x, a);
    shared->detect_dcd(x, b);
    other->detect_dcd(x, c);
    EXPECT_FALSE(a.dcd_pairs.empty());  // the sheets cut each other
    EXPECT_EQ(b.dcd_pairs, a.dcd_pairs);
    EXPECT_TRUE(c.dcd_pairs.empty());  // the excluded mesh's rule, not the shared topology's

    // The standing sheet's motion down through the flat one: contacts, none where excluded.
    FrameResult ca, cb, cc;
    own->detect_ccd(x_t0, x, ca);
    shared->detect_ccd(x_t0, x, cb);
    other->detect_ccd(x_t0, x, cc);
    EXPECT_FALSE(ca.contacts.empty());
    EXPECT_EQ(cb.contacts.size(), ca.contacts.size());
    EXPECT_LT(cc.contacts.size(), ca.contacts.size());
  }
}

TEST(SharedFeatures, DcdUpdaterTakesTheFeaturesOnlyWhenBuiltFromItsMeshAndTopology) {
  const skinning::Mesh mesh = crossing_sheets();
  skinning::Mesh excluded = mesh;
  excluded.excluded_part_pairs = {{0, 1}};
  const auto topology = test::simple_topology(mesh);
  const auto features = std::make_shared<const FeatureTopology>(mesh, topology);

  const DcdUpdater shared(mesh, topology, features);
  EXPECT_EQ(shared.shared_features(), features);
  const DcdUpdater other(excluded, topology, features);
  EXPECT_NE(other.shared_features(), features);
  // Any owner order (the updater reads no ownership): `dynamic` lends its rim-first features.
  const std::vector<std::int32_t> reversed = reversed_triangles(topology);
  const auto in_reverse = std::make_shared<const FeatureTopology>(mesh, topology, reversed);
  const DcdUpdater reversed_order(mesh, topology, in_reverse);
  EXPECT_EQ(reversed_order.shared_features(), in_reverse);
  // Every pair of one triangle of each sheet, as the updater's rules see it.
  std::vector<CcdContact> contacts;
  CcdContact c;
  c.kind = CcdContact::Kind::vf;
  c.a = topology.welded_triangles(0, 0);
  c.b = static_cast<std::int32_t>(topology.welded_triangles.rows()) - 1;
  contacts.push_back(c);
  std::vector<TrianglePair> with_shared, with_other;
  shared.affected_pairs(contacts, with_shared);
  other.affected_pairs(contacts, with_other);
  EXPECT_FALSE(with_shared.empty());
  EXPECT_TRUE(with_other.empty());  // the excluded mesh's rule
  std::vector<TrianglePair> with_reversed;
  reversed_order.affected_pairs(contacts, with_reversed);
  EXPECT_EQ(with_reversed, with_shared);
}

TEST(SharedFeatures, SievedDcdOverFeaturesOfAnyOwnerOrderFindsBvhsPairsAndCounts) {
  // `dynamic`'s detect_dcd: `bvh`'s tree and fan-sieved traversal over features of its own
  // (rim-first) owner order, into its own volumes and blocks. The DCD reads no ownership: over
  // reversed features it finds `bvh`'s pairs with `bvh`'s counts, the tree built over the rest
  // positions as `bvh` builds its own.
  const skinning::Mesh mesh = crossing_sheets();
  const auto topology = test::simple_topology(mesh);
  const auto rest = test::welded(topology, mesh.rest_positions);
  const auto x = test::welded(topology, standing_sheet_raised(mesh));
  const std::vector<std::int32_t> reversed = reversed_triangles(topology);
  const FeatureTopology in_reverse(mesh, topology, reversed);
  ASSERT_TRUE(in_reverse.describes(mesh, topology));
  ASSERT_FALSE(in_reverse.built_from(mesh, topology));
  const auto bvh = make_method("bvh", mesh, topology);
  AabbBvh tree(in_reverse.welded_triangles(), rest, BvhOptions{.node_volumes = false});
  const SlotAdjacency slots(in_reverse, tree.triangle_order());
  std::vector<std::uint8_t> full_slots;
  FeatureBounds<3> bounds;
  TraversalScratch scratch;
  scratch.reserve_self(tree);
  PairBlocks<3> blocks;
  const ElementaryTests tests = with_ccd_defaults({});
  for (const auto* at : {&rest, &x}) {
    FrameResult a, b;
    bvh->detect_dcd(*at, a);
    bounds.static_triangles(in_reverse, *at);
    tree.refit(bounds.triangles);
    blocks.start_dcd(in_reverse, *at, tests, b);
    sieved_self_dcd<3>(tree, bounds.triangles, in_reverse, slots, full_slots, scratch, blocks, b);
    blocks.finish();
    EXPECT_EQ(b.dcd_pairs, a.dcd_pairs);
    EXPECT_EQ(b.counters.bv_tests, a.counters.bv_tests);
    EXPECT_EQ(b.counters.tt_tests, a.counters.tt_tests);
    EXPECT_EQ(b.counters.candidate_pairs, a.counters.candidate_pairs);
  }
  FrameResult rest_pairs;
  bvh->detect_dcd(rest, rest_pairs);
  EXPECT_FALSE(rest_pairs.dcd_pairs.empty());  // the sheets cut each other at rest
}

}  // namespace
}  // namespace skelcd::culling
