// `kdop`'s relative pairs, and `auto`'s (culling/relative_aabb.hpp, RelativePairTrial;
// docs/culling.md "Relative boxes in `kdop`"): a CCD query keeps the relative AABB filter only when
// a trial on its first pairs shows that it removes enough of them, and its contacts are those of
// the same hierarchy without the filter, and of `bvh`, either way.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/detail/method_base.hpp"
#include "culling/feature_topology.hpp"
#include "culling/method.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/routed_method.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/welded_character.hpp"

namespace skelcd::culling {
namespace {

struct Outcome {
  std::vector<CcdContact> contacts;
  std::int64_t candidate_pairs = 0;
};

Outcome ccd(CullingMethod& method, const skinning::Positions& x0, const skinning::Positions& x1) {
  FrameResult r;
  method.detect_ccd(x0, x1, r);
  return {r.contacts, r.counters.candidate_pairs};
}

using Model = test::WeldedCharacter;

// A body carried along rigidly, far over one interval: the swept boxes of every pair overlap its
// neighbours' along the whole path, the relative boxes are the body's own. With a contact
// distance (the filter's case since the feature stage tests the triangles at both ends without
// one) the trial keeps the filter, which removes most pairs; the contacts stay exactly those of
// the same 16-DOP hierarchy without it and of `bvh` (none: the body is the rest pose, carried),
// and the counters are the same with blocks of 64 pairs (the trial then spans many
// installments) as in one piece. Without a contact distance the feature stage culls as many.
TEST(RelativePairs, ABodyCarriedFarKeepsTheFilterAndTheContacts) {
  const Model m("CesiumMan.glb");
  skinning::Positions far = m.rest;
  far.col(0).array() += 3.0;
  far.col(2).array() -= 1.0;
  std::int64_t one_piece = -1;
  for (const std::size_t block : {std::size_t{1} << 15, std::size_t{64}}) {
    const MethodOptions options{.min_separation = 1e-3, .block_pairs = block};
    auto kdop = make_method("kdop", *m.loaded.mesh, m.topology, options);
    auto plain = detail::make_bvh_method<8>("kdop", *m.loaded.mesh, m.topology, options, false);
    auto bvh = make_method("bvh", *m.loaded.mesh, m.topology, options);
    const Outcome a = ccd(*kdop, m.rest, far);
    const Outcome b = ccd(*plain, m.rest, far);
    const Outcome c = ccd(*bvh, m.rest, far);
    EXPECT_EQ(a.contacts, b.contacts) << block;
    EXPECT_EQ(a.contacts, c.contacts) << block;
    EXPECT_LT(a.candidate_pairs * 4, b.candidate_pairs) << block << ": most pairs removed";
    if (one_piece < 0) one_piece = a.candidate_pairs;
    EXPECT_EQ(a.candidate_pairs, one_piece) << block;
    auto at_zero =
        make_method("kdop", *m.loaded.mesh, m.topology, MethodOptions{.block_pairs = block});
    const Outcome d = ccd(*at_zero, m.rest, far);
    EXPECT_EQ(d.contacts, a.contacts) << block;
    EXPECT_LT(d.candidate_pairs * 4, b.candidate_pairs) << block << ": culled at both ends";
  }
}

/// The triangle pairs whose swept AABBs over x0 → x1 overlap, as `bvh`'s traversal finds them.
std::vector<TrianglePair> swept_pairs(
    const FeatureTopology& ft, const skinning::Positions& x0, const skinning::Positions& x1) {
  Bvh<3> bvh(ft.welded_triangles(), x0);
  FeatureBounds<3> bounds;
  swept_vertex_bounds<3>(x0, x1, 0.0, bounds.vertices);
  bounds.derive(ft, /*with_edges=*/false);
  bvh.refit(bounds.triangles);
  TraversalScratch scratch;
  std::vector<TrianglePair> pairs;
  std::int64_t tests = 0;
  self_traverse<3>(bvh, bounds.triangles, scratch, pairs, tests);
  return pairs;
}

/// Feeds `pairs` to a trial in installments of `step`, as a traversal would; returns the pairs
/// kept and checks that the trial decides exactly when it has seen `trial` pairs.
std::vector<TrianglePair> feed(
    RelativePairTrial& t,
    const FeatureTopology& ft,
    const skinning::Positions& x0,
    const skinning::Positions& x1,
    const std::vector<TrianglePair>& pairs,
    std::size_t trial,
    std::size_t step) {
  t.start(trial);
  std::vector<TrianglePair> kept;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < pairs.size(); i += step) {
    EXPECT_EQ(t.in_trial(), seen < trial) << "after " << seen << " pairs";
    const std::size_t first = kept.size();
    const std::size_t end = std::min(pairs.size(), i + step);
    kept.insert(
        kept.end(),
        pairs.begin() + static_cast<std::ptrdiff_t>(i),
        pairs.begin() + static_cast<std::ptrdiff_t>(end));
    t.filter(ft, x0, x1, 0.0, kept, first);
    seen += end - i;
  }
  return kept;
}

// The decision: carried far, the trial's pairs lose well over a quarter and the filter is kept
// for every later pair, removing what the prepared filter removes; at rest nothing is removed (the
// relative boxes are the swept ones) and the filter is dropped, every later pair kept as it is.
TEST(RelativePairs, TheTrialKeepsTheFilterOnlyWhenItRemovesAQuarterOfItsPairs) {
  const Model m("CesiumMan.glb");
  const FeatureTopology ft(*m.loaded.mesh, m.topology);
  skinning::Positions far = m.rest;
  far.col(0).array() += 3.0;
  const std::size_t trial = RelativePairTrial::trial_pairs(ft.num_triangles());
  EXPECT_EQ(trial, static_cast<std::size_t>(ft.num_triangles()));
  EXPECT_EQ(RelativePairTrial::trial_pairs(100'000), RelativePairTrial::kMaxTrial);
  EXPECT_EQ(RelativePairTrial::trial_pairs(0), 1u);

  RelativePairTrial t;
  const auto moving = swept_pairs(ft, m.rest, far);
  ASSERT_GT(moving.size(), 2 * trial);
  const auto kept = feed(t, ft, m.rest, far, moving, trial, 1000);
  EXPECT_TRUE(t.kept());
  std::vector<TrianglePair> reference = moving;
  relative_aabb_filter(ft, m.rest, far, 0.0, reference);
  EXPECT_EQ(kept, reference) << "every pair filtered, in the trial and after it";
  EXPECT_LT(kept.size() * 2, moving.size());

  const auto still = swept_pairs(ft, m.rest, m.rest);
  ASSERT_GT(still.size(), 2 * trial);
  const auto unfiltered = feed(t, ft, m.rest, m.rest, still, trial, 1000);
  EXPECT_FALSE(t.kept());
  EXPECT_FALSE(t.in_trial());
  EXPECT_EQ(unfiltered, still);
  // Dropped: pairs the filter would remove pass untouched until the next start.
  std::vector<TrianglePair> apart = moving;
  EXPECT_EQ(t.filter(ft, m.rest, far, 0.0, apart, 0), 0);
  EXPECT_EQ(apart, moving);
}

// A clip with motion of its own: every interval of RobotExpressive's first clip and of the
// stormtrooper's, same contacts with and without the filter, and the filter kept on some.
/// Calls visit(x0, x1, k) on intervals of about n/parts samples each of the model's first clip
/// (welded positions at samples k and k + step).
template <typename Visit>
void for_clip_intervals(const Model& m, int parts, Visit&& visit) {
  const auto motion = m.loaded.motion();
  skinning::Positions posed, x0, x1;
  const int n = motion->num_samples();
  const int step = std::max(1, n / parts);
  for (int k = 0; k + step < n; k += step) {
    motion->positions(k, posed);
    skinning::gather_welded(m.topology, posed, x0);
    motion->positions(k + step, posed);
    skinning::gather_welded(m.topology, posed, x1);
    visit(x0, x1, k);
  }
}

TEST(RelativePairs, RealClipsHaveTheSameContactsWithAndWithoutTheFilter) {
  // With a contact distance: the filter's case (without one the feature stage culls those pairs).
  const MethodOptions options{.min_separation = 1e-4};
  for (const std::string file : {"RobotExpressive.glb", "stormtrooper/stormtrooper.dae"}) {
    const Model m(file);
    auto kdop = make_method("kdop", *m.loaded.mesh, m.topology, options);
    auto plain = detail::make_bvh_method<8>("kdop", *m.loaded.mesh, m.topology, options, false);
    std::int64_t with = 0, without = 0;
    std::size_t contacts = 0;
    for_clip_intervals(
        m, 12, [&](const skinning::Positions& x0, const skinning::Positions& x1, int k) {
          const Outcome a = ccd(*kdop, x0, x1);
          const Outcome b = ccd(*plain, x0, x1);
          ASSERT_EQ(a.contacts, b.contacts) << file << " interval from " << k;
          with += a.candidate_pairs;
          without += b.candidate_pairs;
          contacts += a.contacts.size();
        });
    EXPECT_GT(contacts, 0u) << file;
    EXPECT_LT(with, without) << file << ": the filter was kept on some intervals";
  }
}

// `auto`'s pairs that it traverses itself. Without a contact distance its feature stage tests
// the two triangles' boxes at both ends before their features (candidates.hpp, IntervalEnds:
// the relative filter's test, on the positions), so no trial filter runs; with one, the trial
// filter culls them as `kdop`'s does. Either way the contacts are `bvh`'s. Both characters are
// closed or small throughout, which `auto` would hand whole to `bvh` (RoutingOptions::
// all_closed_method): its own traversal is asked for here, their small open parts a group of their
// own (min_open_triangles 1), both groups named `bvh`.
TEST(RelativePairs, AutoCullsThePairsItTraversesAndKeepsTheContacts) {
  RoutingOptions traverse_here;
  traverse_here.open_method = "bvh";
  traverse_here.closed_method = "bvh";
  traverse_here.min_open_triangles = 1;
  {
    const Model m("RobotExpressive.glb");
    skinning::Positions far = m.rest;
    far.col(0).array() += 3.0;
    far.col(2).array() -= 1.0;
    const FeatureTopology ft(*m.loaded.mesh, m.topology);
    const auto swept = static_cast<std::int64_t>(swept_pairs(ft, m.rest, far).size());
    auto routed = make_routed_method(*m.loaded.mesh, m.topology, {}, traverse_here);
    EXPECT_EQ(routed_structures(*routed).own_hierarchies, 2);  // traversed here
    auto bvh = make_method("bvh", *m.loaded.mesh, m.topology);
    const Outcome a = ccd(*routed, m.rest, far);
    const Outcome b = ccd(*bvh, m.rest, far);
    EXPECT_EQ(a.contacts, b.contacts);
    EXPECT_LT(a.candidate_pairs * 2, swept) << "most pairs culled at both ends";
    const MethodOptions apart{.min_separation = 1e-3};
    auto routed_apart = make_routed_method(*m.loaded.mesh, m.topology, apart, traverse_here);
    auto bvh_apart = make_method("bvh", *m.loaded.mesh, m.topology, apart);
    const Outcome c = ccd(*routed_apart, m.rest, far);
    const Outcome d = ccd(*bvh_apart, m.rest, far);
    EXPECT_EQ(c.contacts, d.contacts);
    EXPECT_LT(c.candidate_pairs * 2, d.candidate_pairs) << "most pairs removed by the filter";
  }
  const Model m("stormtrooper/stormtrooper.dae");
  auto routed = make_routed_method(*m.loaded.mesh, m.topology, {}, traverse_here);
  auto bvh = make_method("bvh", *m.loaded.mesh, m.topology);
  std::size_t contacts = 0;
  for_clip_intervals(
      m, 8, [&](const skinning::Positions& x0, const skinning::Positions& x1, int k) {
        const Outcome a = ccd(*routed, x0, x1);
        const Outcome b = ccd(*bvh, x0, x1);
        ASSERT_EQ(a.contacts, b.contacts) << "interval from " << k;
        contacts += a.contacts.size();
      });
  EXPECT_GT(contacts, 0u);
}

}  // namespace
}  // namespace skelcd::culling
