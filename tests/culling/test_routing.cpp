// `auto`: open components go to enhanced-dual-cone, closed ones to the best registered closed-part
// method whose needs are met (`dynamic` on a rig's clip) or the `bvh` fallback, pairs across groups
// through a BVH pair traversal — and the answer is exactly `bvh`'s.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "culling/method.hpp"
#include "culling/method_registry.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using test::OpenScene;

std::set<std::tuple<int, std::int32_t, std::int32_t>> keys(const FrameResult& r) {
  std::set<std::tuple<int, std::int32_t, std::int32_t>> k;
  for (const auto& c : r.contacts) k.emplace(static_cast<int>(c.kind), c.a, c.b);
  return k;
}

FrameResult dcd(CullingMethod& m, const skinning::Positions& x) {
  FrameResult out;
  m.detect_dcd(x, out);
  return out;
}

FrameResult ccd(CullingMethod& m, const skinning::Positions& x0, const skinning::Positions& x1) {
  FrameResult out;
  m.detect_ccd(x0, x1, out);
  return out;
}

/// A closed-part method declared by this file alone (as a module above culling/ declares
/// `dynamic`): a `bvh` over the mesh it is given (with that mesh's part exclusions), counting how
/// often it was built. It needs bone poses, so `auto` chooses it only for options that announce
/// bones — which no other test of this executable does.
int fake_built = 0;

class NamedAsTest final : public CullingMethod {
 public:
  explicit NamedAsTest(std::unique_ptr<CullingMethod> bvh) : bvh_(std::move(bvh)) {}
  [[nodiscard]] std::string_view name() const override { return "test-closed"; }

 protected:
  void dcd(const Instant& at, FrameResult& out) override { bvh_->detect_dcd(at, out); }
  void ccd(const Interval& interval, FrameResult& out) override { bvh_->detect_ccd(interval, out); }

 private:
  std::unique_ptr<CullingMethod> bvh_;
};

[[maybe_unused]] const bool fake_registered = register_method(
    {.name = "test-closed",
     .description = "a bvh declared by tests/culling/test_routing.cpp",
     .needs = {.bone_poses = true},
     .route = RouteKind::closed,
     .route_priority = 100,
     .order = 5000,
     .make = [](const skinning::Mesh& mesh,
                const skinning::Topology& topology,
                const MethodOptions& options) {
       ++fake_built;
       return std::make_unique<NamedAsTest>(make_method("bvh", mesh, topology, options));
     }});

TEST(Routing, SkirtGoesToEnhancedDualConeAndTheBodyToTheFallback) {
  const OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  const auto routes = route_components(s.topo);
  ASSERT_EQ(routes.size(), 2u);
  for (const auto& r : routes) {
    EXPECT_EQ(r.method, r.closed ? std::string(kClosedFallbackMethod) : "enhanced-dual-cone");
  }
  EXPECT_TRUE(routes[0].closed);   // the body comes first
  EXPECT_FALSE(routes[1].closed);  // the skirt
  EXPECT_EQ(routes[0].num_triangles + routes[1].num_triangles, s.mesh.num_triangles());
  auto m = make_method("auto", s.mesh, s.topo);
  EXPECT_EQ(m->name(), "auto");
  const auto used = routes_of(*m);
  ASSERT_EQ(used.size(), 2u);
  EXPECT_EQ(used[1].method, "enhanced-dual-cone");
  EXPECT_EQ(used[1].part, 1);  // the skirt's part
  // A forced method has no routes.
  EXPECT_TRUE(routes_of(*make_method("bvh", s.mesh, s.topo)).empty());
}

TEST(Routing, AutoFindsExactlyWhatBvhAndBruteFind) {
  const OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  auto a = make_method("auto", s.mesh, s.topo);
  auto b = make_method("bvh", s.mesh, s.topo);
  auto r = make_method("brute", s.mesh, s.topo);
  for (const auto& x : s.frames) {
    const FrameResult want = dcd(*r, x);
    EXPECT_FALSE(want.dcd_pairs.empty());
    EXPECT_EQ(dcd(*a, x).dcd_pairs, want.dcd_pairs);
    EXPECT_EQ(dcd(*b, x).dcd_pairs, want.dcd_pairs);
  }
  const FrameResult got = ccd(*a, s.frames[0], s.frames[1]);
  const FrameResult want = ccd(*b, s.frames[0], s.frames[1]);
  EXPECT_FALSE(want.contacts.empty());
  EXPECT_EQ(keys(got), keys(want));
  EXPECT_EQ(
      got.counters.vf_contacts + got.counters.ee_contacts,
      static_cast<std::int64_t>(got.contacts.size()));
  // Skirt against body: some contacts join the two groups (found by the pair traversal).
  std::int32_t body_faces = 0;
  for (const auto& c : s.topo.components)
    body_faces += c.closed ? static_cast<std::int32_t>(c.faces.size()) : 0;
  bool across = false;
  for (const auto& p : dcd(*a, s.frames[1]).dcd_pairs)
    across |= (p.a < body_faces) != (p.b < body_faces);
  EXPECT_TRUE(across);
}

// A cone group's DCD and CCD take the traversals chosen at rest (docs/dual-cone.md "`auto`'s
// DCD"): the plain ones of `bvh` on the group's hierarchy (the DCD's sieved) — which test (and
// settle) exactly what `bvh` does, at most (the CCD pairs that the feature stage culls at both
// ends are counted by neither; with a contact distance `auto`'s relative filter, RelativePairTrial,
// removes some) — on the cloth funnel, whose cone traversal produces 3/4 of the
// pairs whose volumes overlap at rest; the cones on the skirt, whose cone traversal produces none
// there — fewer tests than `bvh` — unless dcd_cone_share and ccd_cone_share are 0. The pairs and
// contacts are `bvh`'s every time, and a query repeated gives the same counters.
TEST(Routing, ConeGroupsTakeTheTraversalsChosenAtRest) {
  const OpenScene funnel = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  const OpenScene skirt = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  RoutingOptions never;
  never.dcd_cone_share = 0;
  never.ccd_cone_share = 0;
  RoutingOptions ccd_only;
  ccd_only.dcd_cone_share = 0;
  // {scene, routing, DCD by the cones, CCD by the cones}. A cone group whose cones pay for
  // neither query is a `bvh` group (drop_idle_cones): the funnel's sheets (cones cull too little
  // at rest), the skirt told never to use them — and, the other group being `bvh` too, the whole
  // mesh goes to the `bvh` method, every counter its own.
  for (const auto& [s, routing, dcd_cones, ccd_cones] :
       {std::tuple{&funnel, RoutingOptions{}, false, false},
        std::tuple{&skirt, RoutingOptions{}, true, true},
        std::tuple{&skirt, ccd_only, false, true},
        std::tuple{&skirt, never, false, false}}) {
    auto a = make_routed_method(s->mesh, s->topo, {}, routing);
    auto b = make_method("bvh", s->mesh, s->topo);
    const bool whole = !dcd_cones && !ccd_cones;
    int cone_groups = 0;
    for (const auto& r : routes_of(*a)) {
      cone_groups += r.method == "enhanced-dual-cone" ? 1 : 0;
      if (whole) {
        EXPECT_EQ(r.method, "bvh");
      }
    }
    EXPECT_EQ(cone_groups, whole ? 0 : 1);
    for (const auto& x : s->frames) {
      const FrameResult want = dcd(*b, x);
      EXPECT_FALSE(want.dcd_pairs.empty());
      const FrameResult first = dcd(*a, x);
      for (const FrameResult& got : {first, dcd(*a, x)}) {
        EXPECT_EQ(got.dcd_pairs, want.dcd_pairs);
        EXPECT_EQ(got.counters.dcd_pairs, want.counters.dcd_pairs);
        EXPECT_EQ(got.counters.bv_tests, first.counters.bv_tests);
        if (dcd_cones) {
          EXPECT_LT(got.counters.tt_tests, want.counters.tt_tests);
        } else {
          EXPECT_EQ(got.counters.tt_tests, want.counters.tt_tests);
          EXPECT_EQ(got.counters.candidate_pairs, want.counters.candidate_pairs);
        }
        if (whole) {
          EXPECT_EQ(got.counters.bv_tests, want.counters.bv_tests);
        }
      }
    }
    const FrameResult want = ccd(*b, s->frames.front(), s->frames.back());
    EXPECT_FALSE(want.contacts.empty());
    const FrameResult first = ccd(*a, s->frames.front(), s->frames.back());
    for (const FrameResult& got : {first, ccd(*a, s->frames.front(), s->frames.back())}) {
      EXPECT_EQ(keys(got), keys(want));
      EXPECT_EQ(got.counters.bv_tests, first.counters.bv_tests);
      if (ccd_cones) {
        EXPECT_LT(got.counters.candidate_pairs, want.counters.candidate_pairs);
      } else {
        EXPECT_EQ(got.counters.candidate_pairs, want.counters.candidate_pairs);
        EXPECT_EQ(got.counters.bv_tests, want.counters.bv_tests);
        EXPECT_EQ(
            got.counters.vf_tests + got.counters.ee_tests,
            want.counters.vf_tests + want.counters.ee_tests);
      }
    }
  }
  for (const auto& [dcd_share, ccd_share] : {std::pair{-1, 2}, std::pair{8, -1}}) {
    RoutingOptions bad;
    bad.dcd_cone_share = dcd_share;
    bad.ccd_cone_share = ccd_share;
    EXPECT_THROW((void)make_routed_method(skirt.mesh, skirt.topo, {}, bad), InvalidInput);
  }
}

TEST(Routing, ClothFunnelRoutesThreeClothPartsAndTheFunnelAndMatchesBvh) {
  const OpenScene s = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  auto a = make_method("auto", s.mesh, s.topo);
  const auto routes = routes_of(*a);
  ASSERT_EQ(routes.size(), 4u);
  int open = 0, small = 0;
  const RoutingOptions routing;
  for (const auto& r : routes) {
    open += r.closed ? 0 : 1;
    // Open parts under RoutingOptions::min_open_triangles go with the closed ones.
    EXPECT_EQ(r.small, !r.closed && r.num_triangles < routing.min_open_triangles);
    small += r.small ? 1 : 0;
    // The sheets' cones cull too little at rest to pay for either query: the sheets are a `bvh`
    // group, and with the funnel's `bvh` group the whole mesh goes to `bvh`.
    EXPECT_EQ(r.method, "bvh");
  }
  EXPECT_EQ(open, 3);
  EXPECT_EQ(small, 1);  // the 200-triangle piece of cloth
  // Without the cones' choice at rest (shares of 1: any cull pays) the sheets keep their method.
  RoutingOptions eager;
  eager.dcd_cone_share = 1;
  eager.ccd_cone_share = 1;
  const auto with_cones = make_routed_method(s.mesh, s.topo, {}, eager);
  for (const auto& r : routes_of(*with_cones)) {
    EXPECT_EQ(r.method, r.closed || r.small ? "bvh" : "enhanced-dual-cone");
  }
  auto b = make_method("bvh", s.mesh, s.topo);
  EXPECT_EQ(dcd(*a, s.frames[1]).dcd_pairs, dcd(*b, s.frames[1]).dcd_pairs);
  EXPECT_EQ(keys(ccd(*a, s.frames[0], s.frames[1])), keys(ccd(*b, s.frames[0], s.frames[1])));
}

/// CesiumMan's mesh, welded, and the welded positions of one interval of its walk (samples 0 and
/// 6): one closed component whose interval has contacts.
struct CesiumInterval {
  skinning::LoadedModel model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  const skinning::Mesh& mesh = *model.mesh;
  skinning::Topology topo = skinning::build_topology(mesh);
  skinning::Positions x0, x1;
  CesiumInterval() {
    const auto motion = model.motion({});
    skinning::Positions p0, p1;
    motion->positions(0, p0);
    motion->positions(std::min(6, motion->num_samples() - 1), p1);
    x0 = test::welded(topo, p0);
    x1 = test::welded(topo, p1);
  }
};

TEST(Routing, AMeshClosedThroughoutGoesWholeToBvh) {
  // CesiumMan: one closed component. With bones announced the closed-part method would be
  // test-closed; a mesh closed throughout goes whole to RoutingOptions::all_closed_method (`bvh`)
  // instead, which answers itself: bvh's pairs, and every counter bvh's.
  const CesiumInterval cesium;
  const skinning::Mesh& mesh = cesium.mesh;
  const skinning::Topology& topo = cesium.topo;
  const skinning::Positions& x0 = cesium.x0;
  const skinning::Positions& x1 = cesium.x1;
  MethodOptions options;
  options.num_bones = 1;
  EXPECT_TRUE(routes_whole_mesh_to_all_closed_method(topo));
  const int before = fake_built;
  auto a = make_method("auto", mesh, topo, options);
  EXPECT_EQ(fake_built, before);
  ASSERT_FALSE(routes_of(*a).empty());
  for (const auto& r : routes_of(*a)) EXPECT_EQ(r.method, "bvh");
  // The `bvh` method it hands the mesh to is built on auto's own FeatureTopology.
  EXPECT_EQ(routed_structures(*a).feature_topologies, 1);
  auto b = make_method("bvh", mesh, topo, options);
  const FrameResult want = ccd(*b, x0, x1);
  const FrameResult got = ccd(*a, x0, x1);
  EXPECT_GT(want.counters.candidate_pairs, 0);
  EXPECT_EQ(got.contacts, want.contacts);
  EXPECT_EQ(got.counters.bv_tests, want.counters.bv_tests);
  EXPECT_EQ(got.counters.candidate_pairs, want.counters.candidate_pairs);
  EXPECT_EQ(got.counters.vf_tests, want.counters.vf_tests);
  EXPECT_EQ(got.counters.ee_tests, want.counters.ee_tests);
  const FrameResult want_dcd = dcd(*b, x1);
  const FrameResult got_dcd = dcd(*a, x1);
  EXPECT_EQ(got_dcd.dcd_pairs, want_dcd.dcd_pairs);
  EXPECT_EQ(got_dcd.counters.tt_tests, want_dcd.counters.tt_tests);
  // Without the rule the closed-part method takes it, with the same answer.
  RoutingOptions keep;
  keep.all_closed_method.clear();
  EXPECT_FALSE(routes_whole_mesh_to_all_closed_method(topo, keep));
  auto c = make_routed_method(mesh, topo, options, keep);
  EXPECT_EQ(fake_built, before + 1);
  for (const auto& r : routes_of(*c)) EXPECT_EQ(r.method, "test-closed");
  EXPECT_EQ(ccd(*c, x0, x1).contacts, want.contacts);
  // The rule's method must need nothing beyond the mesh.
  RoutingOptions needy;
  needy.all_closed_method = "test-closed";
  EXPECT_THROW_MESSAGE(
      (void)make_routed_method(mesh, topo, options, needy),
      InvalidInput,
      "needs more than the mesh");
  // A mesh with a large open part is not closed throughout: the skirt scene keeps its groups.
  const OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  EXPECT_FALSE(routes_whole_mesh_to_all_closed_method(s.topo));
}

TEST(Routing, AMeshClosedThroughoutFromTheRulesSizeOnGoesToTheClosedPartMethod) {
  // RoutingOptions::all_closed_below_triangles: the rule sends a mesh closed throughout to `bvh`
  // only below it. CesiumMan (4,672 triangles) with the limit set at its size goes to the
  // closed-part method (test-closed, as `dynamic` on a rig): that method on the whole mesh,
  // answering as `auto` with its routes, and finding what `bvh` finds.
  const CesiumInterval cesium;
  const skinning::Mesh& mesh = cesium.mesh;
  const skinning::Topology& topo = cesium.topo;
  const skinning::Positions& x0 = cesium.x0;
  const skinning::Positions& x1 = cesium.x1;
  const auto n = static_cast<std::int64_t>(mesh.num_triangles());
  RoutingOptions limit;
  limit.all_closed_below_triangles = n + 1;
  EXPECT_TRUE(routes_whole_mesh_to_all_closed_method(topo, limit));
  limit.all_closed_below_triangles = 0;  // no limit
  EXPECT_TRUE(routes_whole_mesh_to_all_closed_method(topo, limit));
  limit.all_closed_below_triangles = n;
  EXPECT_FALSE(routes_whole_mesh_to_all_closed_method(topo, limit));
  MethodOptions options;
  options.num_bones = 1;
  const int before = fake_built;
  auto a = make_routed_method(mesh, topo, options, limit);
  EXPECT_EQ(fake_built, before + 1);
  EXPECT_EQ(a->name(), "auto");
  ASSERT_FALSE(routes_of(*a).empty());
  for (const auto& r : routes_of(*a)) {
    EXPECT_EQ(r.method, "test-closed");
    EXPECT_TRUE(r.closed);
    EXPECT_EQ(r.part, 0);
  }
  // Nothing of its own beside the one method (not one of culling/'s here: no feature topology).
  EXPECT_EQ(routed_structures(*a).feature_topologies, 0);
  EXPECT_EQ(routed_structures(*a).own_hierarchies, 0);
  auto b = make_method("bvh", mesh, topo, options);
  const FrameResult want = ccd(*b, x0, x1);
  EXPECT_FALSE(want.contacts.empty()) << "no contacts: the interval proves nothing";
  EXPECT_EQ(ccd(*a, x0, x1).contacts, want.contacts);
  EXPECT_EQ(dcd(*a, x1).dcd_pairs, dcd(*b, x1).dcd_pairs);
  // Without bones the closed-part method's needs are not met: `bvh` takes it all the same.
  auto c = make_routed_method(mesh, topo, MethodOptions{}, limit);
  EXPECT_EQ(fake_built, before + 1);
  for (const auto& r : routes_of(*c)) EXPECT_EQ(r.method, "bvh");
  EXPECT_EQ(ccd(*c, x0, x1).contacts, want.contacts);
  // By default the limit keeps CesiumMan with `bvh` and sends its 28,032-triangle subdivision
  // (assets/characters/CesiumMan-dense.glb) on.
  EXPECT_TRUE(routes_whole_mesh_to_all_closed_method(topo));
  const auto dense = skinning::load_model(test::asset("characters/CesiumMan-dense.glb"));
  EXPECT_FALSE(routes_whole_mesh_to_all_closed_method(skinning::build_topology(*dense.mesh)));
}

TEST(Routing, RobotExpressiveCharacterRoutesItsOpenAndClosedPartsAndMatchesBvh) {
  // A real skinned character with open parts (SOURCES.md): each component goes where it fits,
  // and over a clip interval the routed answer is bvh's.
  const auto model = skinning::load_model(test::asset("characters/RobotExpressive.glb"));
  const auto motion = model.motion({});
  const skinning::Mesh& mesh = *model.mesh;
  const auto topo = skinning::build_topology(mesh);
  auto a = make_method("auto", mesh, topo);
  int open = 0;
  int closed = 0;
  const RoutingOptions routing;
  for (const auto& r : routes_of(*a)) {
    (r.closed ? closed : open) += 1;
    // Its open parts are small (at most 54 triangles): with the closed ones, where `bvh` (no rig
    // given here, so no caps) tests them.
    EXPECT_EQ(r.small, !r.closed && r.num_triangles < routing.min_open_triangles);
    EXPECT_EQ(r.method, r.closed || r.small ? "bvh" : "enhanced-dual-cone");
  }
  EXPECT_GT(open, 0);
  EXPECT_GT(closed, 0);
  auto b = make_method("bvh", mesh, topo);
  skinning::Positions p0, p1;
  motion->positions(0, p0);
  motion->positions(std::min(3, motion->num_samples() - 1), p1);
  const skinning::Positions x0 = test::welded(topo, p0);
  const skinning::Positions x1 = test::welded(topo, p1);
  EXPECT_EQ(dcd(*a, x1).dcd_pairs, dcd(*b, x1).dcd_pairs);
  EXPECT_EQ(keys(ccd(*a, x0, x1)), keys(ccd(*b, x0, x1)));
}

TEST(Routing, ClosedPartsGoToTheRegisteredClosedPartMethodWhoseNeedsAreMet) {
  const OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  // Without bones its needs are not met: the fallback.
  EXPECT_EQ(route_components(s.topo)[0].method, std::string(kClosedFallbackMethod));
  MethodOptions options;
  options.num_bones = 1;
  const int before = fake_built;
  auto a = make_method("auto", s.mesh, s.topo, options);
  EXPECT_EQ(fake_built, before + 1);
  const auto routes = routes_of(*a);
  EXPECT_EQ(routes[0].method, "test-closed");
  EXPECT_EQ(routes[1].method, "enhanced-dual-cone");
  EXPECT_EQ(
      auto_group_methods(options), (std::vector<std::string>{"enhanced-dual-cone", "test-closed"}));
  // The whole-mesh method is told to skip every pair with an open triangle: the merged answer is
  // still bvh's, each contact once.
  auto b = make_method("bvh", s.mesh, s.topo);
  EXPECT_EQ(dcd(*a, s.frames[1]).dcd_pairs, dcd(*b, s.frames[1]).dcd_pairs);
  const FrameResult got = ccd(*a, s.frames[0], s.frames[1]);
  EXPECT_EQ(keys(got), keys(ccd(*b, s.frames[0], s.frames[1])));
  EXPECT_EQ(keys(got).size(), got.contacts.size());
  // Registered once: a second registration of the name is refused; it is listed by name.
  EXPECT_THROW_MESSAGE(
      (void)register_method({.name = "test-closed", .make = find_method("bvh")->make}),
      InvalidInput,
      "registered twice");
  const auto names = method_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "test-closed"), names.end());
}

TEST(Routing, OptionsChooseOtherGroupMethodsAndRejectUnknownOnes) {
  const OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  auto b = make_method("bvh", s.mesh, s.topo);
  const auto want = keys(ccd(*b, s.frames[0], s.frames[1]));
  for (const auto& [open, closed] : std::vector<std::pair<std::string, std::string>>{
           {"normal-cone", "bvh"},
           {"bvh", "enhanced-dual-cone"},
           {"enhanced-dual-cone", "normal-cone"}}) {
    auto m = make_routed_method(s.mesh, s.topo, {}, {.open_method = open, .closed_method = closed});
    EXPECT_EQ(keys(ccd(*m, s.frames[0], s.frames[1])), want) << open << " / " << closed;
    EXPECT_EQ(routes_of(*m)[0].method, closed);
  }
  EXPECT_THROW_MESSAGE(
      (void)make_routed_method(s.mesh, s.topo, {}, {.open_method = "octree", .closed_method = ""}),
      InvalidInput,
      "'octree' cannot take the open components");
  EXPECT_THROW_MESSAGE(
      (void)make_routed_method(
          s.mesh, s.topo, {}, {.open_method = "enhanced-dual-cone", .closed_method = "dynamic"}),
      InvalidInput,
      "'dynamic' cannot take the closed components");
}

TEST(Routing, ReadsItsConeGroupsHierarchyAndVolumesInsteadOfCopyingThem) {
  // Bounded memory (docs/culling.md): a group whose method is a cone method already holds a
  // hierarchy over its triangles and the volumes of every feature, refit by its own query just
  // before `auto` traverses between the groups; `auto` reads those and builds only the hierarchy
  // of a group no method of its own tests. Its cone group methods use its FeatureTopology.
  const OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5});
  auto b = make_method("bvh", s.mesh, s.topo);
  struct Case {
    std::string open, closed;
    RoutedStructures want;
  };
  for (const Case& c : std::vector<Case>{
           {"enhanced-dual-cone", "", {.own_hierarchies = 1, .shared_hierarchies = 1}},
           {"bvh", "enhanced-dual-cone", {.own_hierarchies = 1, .shared_hierarchies = 1}},
           {"enhanced-dual-cone", "normal-cone", {.own_hierarchies = 0, .shared_hierarchies = 2}},
           {"bvh", "bvh", {.own_hierarchies = 2, .own_feature_bounds = true}}}) {
    auto m =
        make_routed_method(s.mesh, s.topo, {}, {.open_method = c.open, .closed_method = c.closed});
    const RoutedStructures got = routed_structures(*m);
    EXPECT_EQ(got.own_hierarchies, c.want.own_hierarchies) << c.open << " / " << c.closed;
    EXPECT_EQ(got.shared_hierarchies, c.want.shared_hierarchies) << c.open << " / " << c.closed;
    EXPECT_EQ(got.own_feature_bounds, c.want.own_feature_bounds) << c.open << " / " << c.closed;
    EXPECT_EQ(got.feature_topologies, 1) << c.open << " / " << c.closed;
    // The shared volumes are those of the query at hand, whatever came before it: CCD, DCD (which
    // refits no edge volumes), CCD again, backwards.
    EXPECT_EQ(keys(ccd(*m, s.frames[0], s.frames[1])), keys(ccd(*b, s.frames[0], s.frames[1])))
        << c.open << " / " << c.closed;
    EXPECT_EQ(dcd(*m, s.frames[1]).dcd_pairs, dcd(*b, s.frames[1]).dcd_pairs);
    EXPECT_EQ(keys(ccd(*m, s.frames[1], s.frames[0])), keys(ccd(*b, s.frames[1], s.frames[0])))
        << c.open << " / " << c.closed;
  }
  // One open part alone: its cone method answers; `auto` traverses and holds nothing itself.
  auto sheet = test::sheet(20, 20, 3.0, 3.0);
  const auto topo = test::simple_topology(sheet);
  auto alone = make_method("auto", sheet, topo);
  const RoutedStructures got = routed_structures(*alone);
  EXPECT_EQ(got.own_hierarchies, 0);
  EXPECT_EQ(got.shared_hierarchies, 0);
  EXPECT_FALSE(got.own_feature_bounds);
  EXPECT_EQ(got.feature_topologies, 1);
  EXPECT_THROW_MESSAGE(
      (void)routed_structures(*b), InvalidInput, "routed_structures: method 'bvh' is not auto");
}

TEST(Routing, ComponentsAreFoundWhenTheTopologyHasNone) {
  // The culling tests' own topology builder fills no components.
  auto sphere = test::uv_sphere(8, 10);
  auto sheet = test::sheet(6, 6, 3.0, 3.0);
  sheet.rest_positions = test::translated(sheet.rest_positions, Eigen::Vector3d(-1.5, -1.5, 0.2));
  const auto mesh = test::combine(sphere, sheet);
  const auto topo = test::simple_topology(mesh);
  ASSERT_TRUE(topo.components.empty());
  const auto routes = route_components(topo);
  ASSERT_EQ(routes.size(), 2u);
  EXPECT_TRUE(routes[0].closed);
  EXPECT_FALSE(routes[1].closed);
  EXPECT_EQ(routes[0].num_triangles, sphere.num_triangles());
  auto a = make_method("auto", mesh, topo);
  auto b = make_method("brute", mesh, topo);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  EXPECT_FALSE(dcd(*b, x).dcd_pairs.empty());  // the sheet cuts through the sphere
  EXPECT_EQ(dcd(*a, x).dcd_pairs, dcd(*b, x).dcd_pairs);
}

}  // namespace
}  // namespace skelcd::culling
