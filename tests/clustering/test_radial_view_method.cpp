// `rvbc` and `dynamic` report exactly the contacts of `bvh` (and of `brute` on small meshes) on
// generated clips that collide (coiling rope, touching tentacles and fingers) and on real
// characters, BCN_Epileptic among them (its rest pose interpenetrates). Plus the interface:
// names through the registry, errors, counters of paper Table 3.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "clustering/radial_view_method.hpp"
#include "clustering/radial_view_methods.hpp"
#include "culling/method_registry.hpp"
#include "culling/rigid_rows.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "tests/clustering/radial_view_fixture.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::clustering {
namespace {

using test::ClipRun;
using test::RadialViewScene;
using test::run_clip;

std::shared_ptr<const skinning::Rig> generated(const std::string& spec) {
  auto g = skinning::generate(skinning::parse_generator_spec(spec));
  return std::make_shared<const skinning::Rig>(std::move(g.rig));
}

std::shared_ptr<const skinning::Rig> loaded(const std::filesystem::path& path) {
  auto model = skinning::load_model(path);
  return model.rig;
}

/// Runs bvh, rvbc and dynamic over [first, last) and expects identical contacts; returns the
/// three runs.
struct Comparison {
  ClipRun bvh, rvbc, dynamic;
};
Comparison compare(RadialViewScene& scene, std::int32_t first, std::int32_t last,
                   test::DcdQueries with_dcd = test::DcdQueries::none) {
  Comparison c;
  auto bvh = scene.method("bvh");
  auto rvbc = scene.method("rvbc");
  auto dynamic = scene.method("dynamic");
  c.bvh = run_clip(scene, *bvh, first, last, with_dcd);
  c.rvbc = run_clip(scene, *rvbc, first, last, with_dcd);
  c.dynamic = run_clip(scene, *dynamic, first, last, with_dcd);
  EXPECT_EQ(c.rvbc.contacts, c.bvh.contacts) << "rvbc";
  EXPECT_EQ(c.dynamic.contacts, c.bvh.contacts) << "dynamic";
  return c;
}

std::int64_t total(const ClipRun& run, std::int64_t culling::Counters::*field) {
  std::int64_t s = 0;
  for (const auto& f : run.frames) s += f.counters.*field;
  return s;
}

TEST(RadialViewMethod, RopeCoilsIntoItself) {
  auto rig = generated("gen:rope?triangles=4000&frames=40");
  RadialViewScene scene(rig);
  // Intervals 18 … 30: the coil closes (the first contact) and stays in contact.
  const auto c = compare(scene, 18, 30);
  EXPECT_GT(c.bvh.contacts.size(), 0u);  // the clip does collide
  // Culling happened: fewer candidate pairs than the hierarchy alone.
  EXPECT_LT(total(c.dynamic, &culling::Counters::candidate_pairs),
            total(c.bvh, &culling::Counters::candidate_pairs));
  std::int32_t escalated = 0;
  for (const auto& st : c.dynamic.stats) escalated += st.components_escalated;
  EXPECT_EQ(escalated, 1);  // once, at the first contact; then the component stays intersecting
}

/// One interval's findings of a radial-view method: the DCD at its start (when asked) and its CCD.
struct BlockedInterval {
  culling::FrameResult dcd, ccd;
  RadialViewStats stats;
};

std::vector<BlockedInterval> run_blocked(
    RadialViewScene& scene,
    const std::string& name,
    std::size_t block_pairs,
    std::int32_t first,
    std::int32_t last,
    bool with_dcd) {
  auto m = scene.method(name, {}, culling::MethodOptions{.block_pairs = block_pairs});
  const auto& rv = dynamic_cast<const RadialViewMethod&>(*m);
  std::vector<BlockedInterval> run;
  skinning::Positions x0, x1;
  scene.welded(first, x1);
  for (std::int32_t i = first; i < last; ++i) {
    std::swap(x0, x1);
    scene.welded(i + 1, x1);
    BlockedInterval r;
    if (with_dcd) {
      scene.poses->select_samples(i, i);
      m->detect_dcd(x0, r.dcd);
    }
    scene.poses->select_samples(i, i + 1);
    m->detect_ccd(x0, x1, r.ccd);
    r.stats = rv.last_stats();
    run.push_back(std::move(r));
  }
  return run;
}

void expect_same_counters(const culling::Counters& got, const culling::Counters& want) {
#define SKELCD_EXPECT_COUNTER(name, meaning) EXPECT_EQ(got.name, want.name) << #name;
  SKELCD_COUNTERS(SKELCD_EXPECT_COUNTER)
#undef SKELCD_EXPECT_COUNTER
}

TEST(RadialViewMethod, SmallBlocksFindExactlyWhatOnePieceFinds) {
  // Bounded memory (docs/culling.md): the cluster traversals, the relative AABB filter, the
  // escalation pass and the precondition DCD pass stream their pairs in blocks of
  // MethodOptions::block_pairs. The coiling
  // rope closes its coil in these intervals: pairs are skipped, then re-tested on escalation.
  constexpr std::size_t kSmallBlock = 16;
  constexpr std::size_t kOnePiece = std::numeric_limits<std::size_t>::max();
  RadialViewScene scene(generated("gen:rope?triangles=4000&frames=40"));
  for (const char* name : {"rvbc", "dynamic"}) {
    for (const bool with_dcd : {false, true}) {
      SCOPED_TRACE(std::string(name) + (with_dcd ? ", DCD and CCD" : ", CCD only"));
      const auto whole = run_blocked(scene, name, kOnePiece, 18, 30, with_dcd);
      const auto blocked = run_blocked(scene, name, kSmallBlock, 18, 30, with_dcd);
      ASSERT_EQ(blocked.size(), whole.size());
      std::int64_t contacts = 0, escalation_blocks = 0, most_blocks = 0, dcd_pass_pairs = 0;
      for (std::size_t i = 0; i < whole.size(); ++i) {
        SCOPED_TRACE("interval " + std::to_string(18 + i));
        const auto& w = whole[i];
        const auto& b = blocked[i];
        EXPECT_EQ(b.ccd.contacts, w.ccd.contacts);  // kind, ids and times of impact, in order
        EXPECT_EQ(b.dcd.dcd_pairs, w.dcd.dcd_pairs);
        expect_same_counters(b.ccd.counters, w.ccd.counters);
        expect_same_counters(b.dcd.counters, w.dcd.counters);
        EXPECT_EQ(b.stats.components_culled, w.stats.components_culled);
        EXPECT_EQ(b.stats.components_dcd, w.stats.components_dcd);
        EXPECT_EQ(b.stats.dcd_pass_pairs, w.stats.dcd_pass_pairs);
        EXPECT_EQ(b.stats.components_dirty, w.stats.components_dirty);
        EXPECT_EQ(b.stats.triangles_cut, w.stats.triangles_cut);
        EXPECT_EQ(b.stats.patches_classified, w.stats.patches_classified);
        EXPECT_EQ(b.stats.triangles_kept_out, w.stats.triangles_kept_out);
        EXPECT_EQ(b.stats.triangles_escalated, w.stats.triangles_escalated);
        EXPECT_EQ(b.stats.escalation_rounds, w.stats.escalation_rounds);
        EXPECT_EQ(b.stats.components_escalated, w.stats.components_escalated);
        EXPECT_EQ(b.stats.relative_aabb_culled, w.stats.relative_aabb_culled);
        EXPECT_EQ(b.stats.skipped_pairs_retested, w.stats.skipped_pairs_retested);
        EXPECT_EQ(b.stats.escalation_contacts, w.stats.escalation_contacts);
        EXPECT_LE(w.stats.blocks, 1 + w.stats.escalation_rounds);  // one piece: one block per pass
        contacts += static_cast<std::int64_t>(w.ccd.contacts.size());
        most_blocks = std::max(most_blocks, b.stats.blocks);
        dcd_pass_pairs = std::max(dcd_pass_pairs, b.stats.dcd_pass_pairs);
        if (b.stats.components_escalated > 0) {
          escalation_blocks = b.stats.blocks;
          // The escalation pass itself spans blocks: more re-tested pairs than one block holds.
          EXPECT_GT(b.stats.skipped_pairs_retested, static_cast<std::int64_t>(8 * kSmallBlock));
        }
      }
      EXPECT_GT(contacts, 0);  // the coil does close
      EXPECT_GT(most_blocks, 8);
      EXPECT_GT(escalation_blocks, 8);  // some interval escalated, in many blocks
      // Without a DCD at the start, the first interval proves its components clean by a DCD pass
      // of its own, which streams its pairs in blocks too (counters compared above).
      if (!with_dcd) {
        EXPECT_GT(dcd_pass_pairs, static_cast<std::int64_t>(8 * kSmallBlock));
      }
    }
  }
}

TEST(RadialViewMethod, FingersAndTentaclesTouch) {
  for (const char* spec : {"gen:hand?triangles=2000&frames=30", "gen:octopus?triangles=3000&frames=30"}) {
    SCOPED_TRACE(spec);
    auto rig = generated(spec);
    RadialViewScene scene(rig);
    const auto c = compare(scene, 10, 22);
    EXPECT_GT(c.bvh.contacts.size(), 0u);
  }
}

TEST(RadialViewMethod, PandaFoldsItsHandOntoItsBase) {
  // The bundled Franka Panda: rigid links (one closed component each, excluded neighbour pairs),
  // the whole trajectory, with the hand reaching links 0-2 near its end.
  auto g = skinning::generate(skinning::parse_generator_spec("gen:panda"));
  const std::int32_t first_hit = g.answer.first_intersecting_frame;
  RadialViewScene scene(std::make_shared<const skinning::Rig>(std::move(g.rig)));
  const std::int32_t samples = scene.motion->num_samples();
  ASSERT_GT(first_hit, 0);
  ASSERT_LT(first_hit, samples);
  const auto c = compare(scene, 0, samples - 1);
  EXPECT_GT(c.bvh.contacts.size(), 0u);
  for (const auto& st : c.dynamic.stats) EXPECT_GT(st.components_culled, 0);
}

TEST(RadialViewMethod, SmallHolesAreCappedLongHemsStayOpen) {
  // The pipe's two ends are small loops: ghost caps close it and its pairs may be skipped. The
  // cloth's one boundary is its whole hem, too long to cap: nothing is skipped. Contacts are bvh's
  // (compare) either way.
  {
    RadialViewScene scene(generated("gen:pipe?triangles=2000&frames=30"));
    const auto c = compare(scene, 14, 24);
    EXPECT_GT(c.bvh.contacts.size(), 0u);
    for (const auto& st : c.dynamic.stats) {
      EXPECT_EQ(st.ghost_loops, 2);
      EXPECT_EQ(st.components_open, 0);
      EXPECT_EQ(st.components_culled, 1);
    }
    EXPECT_LT(
        total(c.dynamic, &culling::Counters::candidate_pairs),
        total(c.bvh, &culling::Counters::candidate_pairs));
  }
  {
    RadialViewScene scene(generated("gen:cloth?triangles=2000&frames=30"));
    const auto c = compare(scene, 14, 24);
    EXPECT_GT(c.bvh.contacts.size(), 0u);
    for (const auto& st : c.dynamic.stats) {
      EXPECT_EQ(st.ghost_loops, 0);
      EXPECT_EQ(st.components_open, st.components);
      EXPECT_EQ(st.components_culled, 0);
    }
  }
}

TEST(RadialViewMethod, SmallClipsAgreeWithBruteForce) {
  auto rig = generated("gen:hand?triangles=600&frames=24");
  RadialViewScene scene(rig);
  auto brute = scene.method("brute");
  const ClipRun reference = run_clip(scene, *brute, 6, 20);
  ASSERT_GT(reference.contacts.size(), 0u);
  for (const char* name : {"rvbc", "dynamic"}) {
    auto m = scene.method(name);
    EXPECT_EQ(run_clip(scene, *m, 6, 20).contacts, reference.contacts) << name;
  }
  // With the exact elementary tests as well.
  culling::MethodOptions exact;
  exact.accuracy = ccd::Accuracy::exact;
  auto brute_exact = scene.method("brute", {}, exact);
  auto dynamic_exact = scene.method("dynamic", {}, exact);
  EXPECT_EQ(run_clip(scene, *dynamic_exact, 12, 16).contacts,
            run_clip(scene, *brute_exact, 12, 16).contacts);
}

TEST(RadialViewMethod, RealCharacters) {
  // CesiumMan, Fox and BCN_Epileptic interpenetrate in their rest pose (BCN_Epileptic is also
  // open: all of it goes to the hierarchy); RiggedFigure and RobotExpressive (rigid parts hanging
  // from nodes) do not. A few intervals each; bench/clustering runs the full clips.
  struct Case {
    std::filesystem::path path;
    std::int32_t clip;
    std::int32_t first;
    std::int32_t last;
  };
  const std::vector<Case> cases = {
      {test::asset("characters/CesiumMan.glb"), 0, 10, 16},
      {test::asset("characters/Fox.glb"), 2, 4, 10},
      {test::asset("characters/RiggedFigure.glb"), 0, 0, 1},
      {test::asset("characters/RobotExpressive.glb"), 0, 20, 26},
      {test::assimp_model("X/BCN_Epileptic.X"), 0, 30, 34},
  };
  for (const auto& k : cases) {
    SCOPED_TRACE(k.path.string());
    RadialViewScene scene(loaded(k.path), k.clip);
    const auto c = compare(scene, k.first, k.last, test::DcdQueries::every);
    for (const auto& f : c.dynamic.frames) EXPECT_GT(f.counters.atomic_clusters, 0);
  }
}

/// `method` over intervals [first, last) of the scene's clip with the bone transforms the runner
/// gives every interval (the rigid rows are certified from them).
ClipRun run_with_transforms(
    RadialViewScene& scene, culling::CullingMethod& method, std::int32_t first, std::int32_t last) {
  return run_clip(scene, method, first, last, test::DcdQueries::none, test::Transforms::motion);
}

std::shared_ptr<const culling::RigidRows> rows_of(const RadialViewScene& scene) {
  const skinning::SkinWeights& w = *scene.motion->skin_weights();
  return std::make_shared<const culling::RigidRows>(culling::build_rigid_rows(
      scene.rig->mesh, scene.topology, w, static_cast<std::int32_t>(w.cols())));
}

TEST(RadialViewMethod, RigidRowsDropTheirPairsAndEveryContactStays) {
  // docs/radial-view.md "Rigid rows": the pairs of two triangles of one row an interval certifies
  // are dropped from the walks and re-tests, the row's rest pairs tested instead. The ninja's
  // shells touch at rest within one row (the rest pairs carry those contacts), the robot's parts
  // hang rigidly from nodes, Testwuson walks.
  struct Case {
    std::filesystem::path path;
    std::int32_t first;
    std::int32_t last;
  };
  const std::vector<Case> cases = {
      {test::asset("characters/ninja/ninja.mesh"), 0, 30},
      {test::asset("characters/RobotExpressive.glb"), 20, 32},
      {test::assimp_model("X/Testwuson.X"), 0, 10},
  };
  for (const auto& k : cases) {
    SCOPED_TRACE(k.path.string());
    RadialViewScene scene(loaded(k.path), 0);
    const auto rows = rows_of(scene);
    ASSERT_GT(rows->num_rows(), 0);
    auto bvh = scene.method("bvh");
    const ClipRun reference = run_with_transforms(scene, *bvh, k.first, k.last);
    ASSERT_FALSE(reference.contacts.empty());
    for (const char* name : {"rvbc", "dynamic"}) {
      SCOPED_TRACE(name);
      auto plain = scene.method(name);
      auto skipping = scene.method(name, {}, culling::MethodOptions{.rigid_rows = rows});
      const ClipRun without = run_with_transforms(scene, *plain, k.first, k.last);
      const ClipRun with = run_with_transforms(scene, *skipping, k.first, k.last);
      EXPECT_EQ(without.contacts, reference.contacts);
      EXPECT_EQ(with.contacts, reference.contacts);
      std::int64_t skipped = 0;
      std::int64_t walks_skipped = 0;  // clusters (or two) of one certified row, not walked
      std::int32_t certified = 0;
      for (const auto& st : with.stats) {
        skipped += st.rigid_pairs_skipped;
        walks_skipped += st.rigid_walks_skipped;
        certified += st.rows_certified;
      }
      for (const auto& st : without.stats) EXPECT_EQ(st.rigid_pairs_skipped, 0);
      // The local guard's re-tests drop them too (its rounds re-test fewer pairs).
      std::int64_t retested_with = 0;
      std::int64_t retested_without = 0;
      for (const auto& st : with.stats) retested_with += st.skipped_pairs_retested;
      for (const auto& st : without.stats) retested_without += st.skipped_pairs_retested;
      EXPECT_LT(retested_with, retested_without);
      EXPECT_GT(certified, 0);
      EXPECT_GT(skipped, 0);
      EXPECT_GT(walks_skipped, 0);
      // Fewer pairs reach the feature stage: a tenth fewer at least on these rigs.
      EXPECT_LT(
          10 * total(with, &culling::Counters::candidate_pairs),
          9 * total(without, &culling::Counters::candidate_pairs));
    }
  }
}

TEST(RadialViewMethod, WithoutItsRestPairsDynamicWouldLoseTheNinjasContacts) {
  // The rest pairs are what keeps the contacts of shells that touch at rest within one row: the
  // same drop without them loses some (so the test above could fail).
  RadialViewScene scene(loaded(test::asset("characters/ninja/ninja.mesh")), 0);
  auto rows = std::make_shared<culling::RigidRows>(*rows_of(scene));
  ASSERT_FALSE(rows->rest_pairs.empty());
  rows->rest_pairs.clear();
  auto plain = scene.method("dynamic");
  auto skipping = scene.method("dynamic", {}, culling::MethodOptions{.rigid_rows = rows});
  EXPECT_LT(
      run_with_transforms(scene, *skipping, 0, 30).contacts.size(),
      run_with_transforms(scene, *plain, 0, 30).contacts.size());
}

TEST(RadialViewMethod, CesiumMansWalkIntersectsItselfAndTheLocalGuardStillFindsWhatBvhFinds) {
  // CesiumMan is one closed component that intersects itself at every sample of its walk, which
  // breaks the radial-view precondition where it intersects. The local guard (docs/radial-view.md)
  // keeps out the cut triangles and every patch whose front winding number is not the skin's, skips
  // pairs among the rest, and re-tests around every contact: the contacts stay bvh's (compare).
  RadialViewScene scene(loaded(test::asset("characters/CesiumMan.glb")), 0);
  const auto c = compare(scene, 0, 12, test::DcdQueries::every);
  ASSERT_GT(c.bvh.contacts.size(), 0u);
  const auto num_triangles = static_cast<std::int64_t>(scene.rig->mesh.num_triangles());
  for (const ClipRun* run : {&c.rvbc, &c.dynamic}) {
    ASSERT_EQ(run->stats.size(), 12u);
    std::int64_t escalated = 0;
    for (const auto& st : run->stats) {
      EXPECT_EQ(st.components, 1);
      EXPECT_EQ(st.components_open, 0);
      EXPECT_EQ(st.components_dirty, 1);
      EXPECT_EQ(st.components_culled, 1);
      EXPECT_GT(st.triangles_cut, 0);
      EXPECT_GT(st.patches_classified, 0);
      // Cut and off-value triangles are kept out, most of the skin is not.
      EXPECT_GE(st.triangles_kept_out, st.triangles_cut);
      EXPECT_LT(2 * st.triangles_kept_out, num_triangles);
      escalated += st.triangles_escalated;
    }
    EXPECT_GT(escalated, 0);  // the walk's contacts touch skippable triangles
  }
  // Without the DCD at each start (CCD only after the first), the start pairs are carried from
  // one interval to the next (updated from its contacts): the same patches, the same contacts.
  const auto ccd_only = compare(scene, 0, 12, test::DcdQueries::first);
  ASSERT_EQ(ccd_only.dynamic.stats.size(), c.dynamic.stats.size());
  for (std::size_t i = 0; i < c.dynamic.stats.size(); ++i) {
    EXPECT_EQ(ccd_only.dynamic.stats[i].triangles_cut, c.dynamic.stats[i].triangles_cut);
    EXPECT_EQ(ccd_only.dynamic.stats[i].triangles_kept_out, c.dynamic.stats[i].triangles_kept_out);
  }
}

TEST(RadialViewMethod, BcnEpilepticIsOpenAndItsRestPoseInterpenetrates) {
  RadialViewScene scene(loaded(test::assimp_model("X/BCN_Epileptic.X")));
  auto bvh = scene.method("bvh");
  skinning::Positions x;
  scene.welded(0, x);
  culling::FrameResult dcd;
  bvh->detect_dcd(x, dcd);
  EXPECT_GT(dcd.dcd_pairs.size(), 0u);  // the rest pose interpenetrates
  // Every part is open, but most holes are small (wrists, neck, …): capped, the parts are closed
  // and their pairs may be skipped, with bvh's contacts (compare).
  const auto c = compare(scene, 0, 6, test::DcdQueries::every);
  for (const ClipRun* run : {&c.rvbc, &c.dynamic}) {
    for (const auto& st : run->stats) {
      EXPECT_GE(st.ghost_loops, 4);
      EXPECT_LT(st.components_open, st.components);
      EXPECT_GT(st.components_culled, 0);
    }
  }
}

TEST(RadialViewMethod, GhostPairsAreNotTestedAndALonePatchNeedsNoRay) {
  // BCN_Epileptic, capped everywhere: ghosts are always cut, so every capped part is classified at
  // every interval; a part whose real triangles form the only patch large enough to classify needs
  // no ray (its value is the part's). Pairs of two ghosts are never tested. Contacts: bvh's, also
  // when the start pairs are carried from interval to interval (where ghost pairs go stale).
  RadialViewScene scene(loaded(test::assimp_model("X/BCN_Epileptic.X")));
  for (const auto dcd : {test::DcdQueries::every, test::DcdQueries::first}) {
    const auto c = compare(scene, 0, 8, dcd);
    std::int64_t ghost_pairs = 0, rays = 0, classified = 0;
    for (const auto& st : c.dynamic.stats) {
      EXPECT_EQ(st.components_dirty, st.components_culled);  // every culled part has caps
      ghost_pairs += st.ghost_pairs_skipped;
      rays += st.rays;
      classified += st.patches_classified;
    }
    EXPECT_GT(ghost_pairs, 1000);
    EXPECT_GT(classified, 0);
    EXPECT_LT(rays, classified);
  }
}

TEST(RadialViewMethod, RimFeaturesOwnedFromOneSideLeaveMorePairsSkipped) {
  // A feature on a rim between two atomic clusters (or two rest classes) is impure whenever the
  // two sides get different labels, and its owner is then tested as Hᵘ. Owned from one side of
  // each rim (RadialViewOptions::rims_first), fewer triangles are Hᵘ: fewer candidate pairs, the
  // same contacts.
  for (const auto& path :
       {test::asset("characters/CesiumMan.glb"), test::assimp_model("X/BCN_Epileptic.X")}) {
    SCOPED_TRACE(path.string());
    RadialViewScene scene(loaded(path), 0);
    std::vector<ClipRun> runs;
    for (const bool rims_first : {true, false}) {
      RadialViewOptions o;
      o.rims_first = rims_first;
      RadialViewMethod m(
          "dynamic",
          scene.rig->mesh,
          scene.topology,
          scene.segmentation,
          scene.poses,
          scene.rig->skeleton.num_bones(),
          scene.options(),
          o);
      runs.push_back(run_clip(scene, m, 0, 8, test::DcdQueries::first));
    }
    auto bvh = scene.method("bvh");
    EXPECT_EQ(runs[0].contacts, run_clip(scene, *bvh, 0, 8).contacts);
    EXPECT_EQ(runs[1].contacts, runs[0].contacts);
    EXPECT_LT(
        total(runs[0], &culling::Counters::candidate_pairs),
        total(runs[1], &culling::Counters::candidate_pairs));
  }
}

TEST(RadialViewMethod, ContactDistanceTurnsTheSkippingOff) {
  // The radial-view argument is about touching; with a contact distance nothing is skipped and
  // the contacts stay those of bvh.
  auto rig = generated("gen:hand?triangles=600&frames=24");
  RadialViewScene scene(rig);
  culling::MethodOptions o;
  o.min_separation = 0.01;
  auto bvh = scene.method("bvh", {}, o);
  auto dynamic = scene.method("dynamic", {}, o);
  const ClipRun a = run_clip(scene, *bvh, 8, 20);
  const ClipRun b = run_clip(scene, *dynamic, 8, 20);
  EXPECT_EQ(b.contacts, a.contacts);
  EXPECT_GT(a.contacts.size(), 0u);
  for (const auto& st : b.stats) EXPECT_EQ(st.components_culled, 0);
}

TEST(RadialViewMethod, StartDcdThroughItsOwnTreesFindsBvhsPairsAndBuildsNoOtherTree) {
  // An interval whose start pairs no DCD and no previous interval left: the method finds them
  // through its own hierarchies (start_dcd) and builds no whole-mesh tree; a detect_dcd builds
  // one (`bvh`'s, over the rest positions) and keeps it. CesiumMan (closed, intersecting itself
  // at every sample): the start pairs are `bvh`'s DCD pairs. BCN_Epileptic (capped: ghost
  // triangles too): the start pairs are those detect_dcd records, ghosts included.
  for (const auto& path :
       {test::asset("characters/CesiumMan.glb"), test::assimp_model("X/BCN_Epileptic.X")}) {
    SCOPED_TRACE(path.string());
    RadialViewScene scene(loaded(path));
    const bool capped = path.string().find("BCN") != std::string::npos;
    const auto ccd = [&](culling::CullingMethod& m, std::int32_t i) {
      skinning::Positions x0, x1;
      scene.welded(i, x0);
      scene.welded(i + 1, x1);
      culling::FrameResult out;
      test::interval_ccd(scene, m, i, x0, x1, out);
      return out;
    };
    const auto rv = [](const culling::CullingMethod& m) -> const RadialViewMethod& {
      return dynamic_cast<const RadialViewMethod&>(m);
    };
    const auto keys = [](const culling::FrameResult& r) {
      std::vector<std::tuple<int, std::int32_t, std::int32_t>> k;
      for (const auto& c : r.contacts) k.emplace_back(static_cast<int>(c.kind), c.a, c.b);
      return k;
    };

    auto m = scene.method("dynamic");
    auto asked = scene.method("dynamic");
    auto bvh = scene.method("bvh");
    for (const std::int32_t i : {0, 5}) {  // 5 does not continue 0: a start DCD again
      SCOPED_TRACE(i);
      const auto own = ccd(*m, i);
      EXPECT_FALSE(rv(*m).holds_dcd());
      skinning::Positions x;
      scene.welded(i, x);
      scene.poses->select_samples(i, i);
      culling::FrameResult recorded, bvh_pairs;
      asked->detect_dcd(x, recorded);
      EXPECT_TRUE(rv(*asked).holds_dcd());
      bvh->detect_dcd(x, bvh_pairs);
      ASSERT_FALSE(bvh_pairs.dcd_pairs.empty());
      EXPECT_EQ(recorded.dcd_pairs, bvh_pairs.dcd_pairs);
      const auto after_dcd = ccd(*asked, i);
      EXPECT_EQ(rv(*m).start_pairs(), rv(*asked).start_pairs());
      if (!capped) {
        EXPECT_EQ(rv(*m).start_pairs(), bvh_pairs.dcd_pairs);
      }
      EXPECT_EQ(keys(own), keys(after_dcd));
      // The start DCD's tests are counted in the interval.
      EXPECT_GT(own.counters.tt_tests, after_dcd.counters.tt_tests);
    }
  }
}

TEST(RadialViewMethod, NamesErrorsAndCounters) {
  auto rig = generated("gen:hand?triangles=600&frames=8");
  RadialViewScene scene(rig);
  const auto options = scene.options();
  // Registered by this module itself: listed, with what they need, and `dynamic` is auto's choice
  // for closed parts once a segmentation and bones are there.
  const auto names = culling::method_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "rvbc"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "dynamic"), names.end());
  EXPECT_TRUE(culling::method_needs("dynamic").bone_poses);
  EXPECT_TRUE(culling::method_needs("dynamic").segmentation);
  EXPECT_EQ(culling::auto_group_methods(options).back(), "dynamic");
  EXPECT_EQ(culling::auto_group_methods({}).back(), "bvh");
  EXPECT_EQ(scene.method("rvbc")->name(), "rvbc");
  EXPECT_EQ(scene.method("dynamic")->name(), "dynamic");
  // Through the registry without a segmentation: the DCD-only method, which refuses CCD.
  auto dcd_only = culling::make_method("dynamic", rig->mesh, scene.topology);
  skinning::Positions x0, x1;
  scene.welded(0, x0);
  scene.welded(1, x1);
  culling::FrameResult out;
  EXPECT_THROW_MESSAGE(dcd_only->detect_ccd(x0, x1, out), InvalidInput, "built for DCD only");
  EXPECT_THROW_MESSAGE((void)scene.method("octree"), InvalidInput, "rvbc, dynamic");
  EXPECT_THROW_MESSAGE((void)scene.method("dynamic", {.gamma = 1.5}), InvalidInput, "gamma");
  // Bad method options are refused as for every method.
  culling::MethodOptions bad;
  bad.min_separation = -1;
  EXPECT_THROW_MESSAGE((void)scene.method("dynamic", {}, bad), InvalidInput, "min_separation");
  // A segmentation of another mesh.
  auto other = std::make_shared<segmentation::Segmentation>(*scene.segmentation);
  other->triangle_cluster.pop_back();
  culling::MethodOptions with_other = options;
  with_other.segmentation = other;
  EXPECT_THROW_MESSAGE((void)culling::make_method("rvbc", rig->mesh, scene.topology, with_other),
                       InvalidInput, "the segmentation has");
  // No bone transforms in the interval, none selected; wrong row counts.
  auto m = culling::make_method("dynamic", rig->mesh, scene.topology, options);
  EXPECT_THROW_MESSAGE(m->detect_ccd(x0, x1, out), InvalidInput, "carries no bone transforms");
  std::vector<skinning::BoneTransform> t0, t1;
  scene.motion->bone_transforms(0, t0);
  scene.motion->bone_transforms(1, t1);
  const skinning::Positions few(3, 3);
  EXPECT_THROW_MESSAGE(
      m->detect_ccd(
          culling::Interval{.x_t0 = x0, .x_t1 = few, .bones_t0 = t0, .bones_t1 = t1}, out),
      InvalidInput,
      "x_t1 has 3 rows");
  const culling::Interval interval{
      .x_t0 = x0, .x_t1 = x1, .bones_t0 = t0, .bones_t1 = t1, .sample_t0 = 0, .sample_t1 = 1};
  // Table 3 counters of one interval.
  m->detect_ccd(interval, out);
  EXPECT_EQ(out.counters.atomic_clusters,
            static_cast<std::int64_t>(scene.segmentation->clusters.size()));
  EXPECT_GE(out.counters.mega_clusters, 1);
  EXPECT_LE(out.counters.mega_clusters, out.counters.atomic_clusters);
  EXPECT_GT(out.counters.bv_tests, 0);
  EXPECT_GT(out.times.classify_us, 0.0);
  const auto* rv = dynamic_cast<const RadialViewMethod*>(m.get());
  ASSERT_NE(rv, nullptr);
  EXPECT_EQ(out.counters.h_minus + out.counters.h_uncertain,
            static_cast<std::int64_t>(std::count_if(
                rv->last_classes().triangle_class.begin(), rv->last_classes().triangle_class.end(),
                [](OrientationClass c) { return c != OrientationClass::positive; })));
}

}  // namespace
}  // namespace skelcd::clustering
