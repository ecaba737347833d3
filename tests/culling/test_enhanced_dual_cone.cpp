// The cone methods against the references: `enhanced-dual-cone` and `normal-cone` find exactly
// what `bvh` (and `brute`, on small cases) finds, DCD and CCD, on every open scene and on the
// cloth-funnel frames; `dual-cone` (FASTCD) demonstrably misses on the pipe and the wrapped sheet.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/candidates.hpp"
#include "culling/cones_method.hpp"
#include "culling/cones_method_base.hpp"
#include "culling/enhanced_dual_cone.hpp"
#include "culling/method.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using test::OpenScene;
using Key = std::tuple<int, std::int32_t, std::int32_t>;

FrameResult run_dcd(
    const std::string& name,
    const OpenScene& s,
    std::size_t frame,
    const MethodOptions& options = {}) {
  auto m = make_method(name, s.mesh, s.topo, options);
  FrameResult out;
  m->detect_dcd(s.frames[frame], out);
  return out;
}

FrameResult run_ccd(
    const std::string& name,
    const OpenScene& s,
    std::size_t from,
    const MethodOptions& options = {}) {
  auto m = make_method(name, s.mesh, s.topo, options);
  FrameResult out;
  m->detect_ccd(s.frames[from], s.frames[from + 1], out);
  return out;
}

std::set<Key> keys(const FrameResult& r) {
  std::set<Key> k;
  for (const auto& c : r.contacts) k.emplace(static_cast<int>(c.kind), c.a, c.b);
  return k;
}

/// True when the exact elementary test says contact `k` does not happen over the interval.
bool exactly_refuted(const OpenScene& s, std::size_t from, const Key& k) {
  const auto& x0 = s.frames[from];
  const auto& x1 = s.frames[from + 1];
  auto p = [](const skinning::Positions& x, std::int32_t w) -> Eigen::Vector3d {
    return x.row(w).transpose();
  };
  const auto [kind, a, b] = k;
  if (kind == 0) {
    const auto f = s.topo.welded_triangles.row(b);
    const ccd::VertexFaceQuery q{
        p(x0, a),
        p(x0, f(0)),
        p(x0, f(1)),
        p(x0, f(2)),
        p(x1, a),
        p(x1, f(0)),
        p(x1, f(1)),
        p(x1, f(2))};
    return !ccd::vertex_face_ccd(q, ccd::Accuracy::exact).hit;
  }
  const auto ea = s.topo.edges.row(a);
  const auto eb = s.topo.edges.row(b);
  const ccd::EdgeEdgeQuery q{
      p(x0, ea(0)),
      p(x0, ea(1)),
      p(x0, eb(0)),
      p(x0, eb(1)),
      p(x1, ea(0)),
      p(x1, ea(1)),
      p(x1, eb(0)),
      p(x1, eb(1))};
  return !ccd::edge_edge_ccd(q, ccd::Accuracy::exact).hit;
}

/// CCD of a culling method against the reference's contacts (conservative elementary tests):
/// nothing the method reports is missing from the reference, and whatever the reference reports
/// beyond it is a false positive of the conservative test, refuted in exact arithmetic.
::testing::AssertionResult same_ccd_contacts(
    const OpenScene& s, std::size_t from, const FrameResult& method, const FrameResult& reference) {
  const auto got = keys(method);
  const auto want = keys(reference);
  for (const Key& k : got) {
    if (!want.count(k)) {
      return ::testing::AssertionFailure()
             << "contact (" << std::get<0>(k) << ", " << std::get<1>(k) << ", " << std::get<2>(k)
             << ") is not in the reference";
    }
  }
  for (const Key& k : want) {
    if (!got.count(k) && !exactly_refuted(s, from, k)) {
      return ::testing::AssertionFailure()
             << "missed contact (" << std::get<0>(k) << ", " << std::get<1>(k) << ", "
             << std::get<2>(k) << ") of " << want.size();
    }
  }
  return ::testing::AssertionSuccess();
}

const ConeCullingStats& stats_of(const CullingMethod& m) {
  const ConeStatistics* cs = m.cone_statistics();
  EXPECT_NE(cs, nullptr) << m.name();
  static const ConeCullingStats kNone{};
  return cs != nullptr ? cs->cone_stats() : kNone;
}

std::vector<OpenScene> small_open_scenes() {
  std::vector<OpenScene> out;
  out.push_back(test::pipe_scene(12, 72, {0.5, 0.7}));
  out.push_back(test::wrap_sheet_scene(8, 90, {0.30, 0.36}));
  out.push_back(test::crumpled_tube_scene(12, 56, {0.55, 0.6}));
  out.push_back(test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5}));
  return out;
}

const std::vector<std::string> kExactMethods = {"enhanced-dual-cone", "normal-cone"};

TEST(ConeMethods, FactoryBuildsThemByName) {
  const auto s = test::wrap_sheet_scene(3, 12, {0.3});
  for (const std::string name : {"enhanced-dual-cone", "normal-cone", "dual-cone"}) {
    const auto m = make_method(name, s.mesh, s.topo);
    EXPECT_EQ(m->name(), name);
    EXPECT_NE(m->cone_statistics(), nullptr);
  }
}

TEST(ConeMethods, EveryOpenSceneCollidesAndMatchesBruteForce) {
  for (const OpenScene& s : small_open_scenes()) {
    SCOPED_TRACE(s.name);
    for (std::size_t f = 0; f < s.frames.size(); ++f) {
      const FrameResult brute = run_dcd("brute", s, f);
      EXPECT_FALSE(brute.dcd_pairs.empty()) << "scene must self-intersect at frame " << f;
      for (const auto& name : kExactMethods) {
        EXPECT_EQ(run_dcd(name, s, f).dcd_pairs, brute.dcd_pairs) << name << " frame " << f;
      }
    }
    for (std::size_t f = 0; f + 1 < s.frames.size(); ++f) {
      const FrameResult brute = run_ccd("brute", s, f);
      EXPECT_FALSE(brute.contacts.empty());
      for (const auto& name : kExactMethods) {
        EXPECT_TRUE(same_ccd_contacts(s, f, run_ccd(name, s, f), brute))
            << name << " interval " << f;
      }
    }
  }
}

TEST(ConeMethods, EnhancedCullsWhatItCanAndReportsWhy) {
  const auto s = test::wrap_sheet_scene(8, 90, {0.30, 0.36});
  auto m = make_method("enhanced-dual-cone", s.mesh, s.topo);
  FrameResult out;
  m->detect_dcd(s.frames[0], out);
  const ConeCullingStats& st = stats_of(*m);
  EXPECT_GT(st.nodes_culled, 0);
  EXPECT_EQ(
      st.nodes_tested,
      st.nodes_culled + st.failed_normal_cone + st.failed_topology + st.failed_dual_cone +
          st.failed_contour);
  // Nodes holding both crossing layers have two loops whose projections cross or nest.
  EXPECT_GT(st.failed_contour, 0);
  EXPECT_GT(st.contour.chain_tests, 0);
  EXPECT_GT(st.contour.nesting_tests, 0);
  // Fewer candidate pairs than the plain hierarchy, the same answer.
  const FrameResult bvh = run_dcd("bvh", s, 0);
  EXPECT_LT(out.counters.candidate_pairs, bvh.counters.candidate_pairs);
  EXPECT_EQ(out.dcd_pairs, bvh.dcd_pairs);
}

TEST(ConeMethods, FlatSheetIsCulledAtTheRoot) {
  const auto mesh = test::sheet(16, 16);
  const auto topo = skinning::build_topology(mesh);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  for (const std::string name : {"enhanced-dual-cone", "normal-cone"}) {
    auto m = make_method(name, mesh, topo);
    FrameResult out;
    m->detect_dcd(x, out);
    EXPECT_EQ(stats_of(*m).nodes_tested, 1) << name;
    EXPECT_EQ(stats_of(*m).nodes_culled, 1) << name;
    EXPECT_EQ(out.counters.tt_tests, 0) << name;
    FrameResult ccd;
    m->detect_ccd(x, test::translated(x, Eigen::Vector3d(0.01, 0.02, 0.03)), ccd);
    EXPECT_EQ(stats_of(*m).nodes_culled, 1) << name;
    EXPECT_EQ(ccd.counters.vf_tests + ccd.counters.ee_tests, 0) << name;
  }
  // FASTCD's root BNC holds the binormals of the whole boundary, pointing every way in the
  // plane: it fails at the root and culls lower down.
  auto m = make_method("dual-cone", mesh, topo);
  FrameResult out;
  m->detect_dcd(x, out);
  EXPECT_EQ(stats_of(*m).failed_dual_cone, stats_of(*m).nodes_tested - stats_of(*m).nodes_culled);
  EXPECT_GT(stats_of(*m).failed_dual_cone, 0);
  EXPECT_GT(stats_of(*m).nodes_culled, 0);
  EXPECT_TRUE(out.dcd_pairs.empty());
}

TEST(ConeMethods, ChainsThatTurnBackAreCutIntoMonotoneRunsAndTheFlatSheetIsStillCulled) {
  // A flat U-shaped sheet (a slot cut into one side): along the slot the boundary turns back on
  // itself, so the chains there span more than π and fail the dual-cone test; cut into monotone
  // runs and tested against each other they prove the contour simple all the same.
  const auto full = test::sheet(12, 12);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index t = 0; t < full.triangles.rows(); ++t) {
    const Eigen::Vector3d c = (full.rest_positions.row(full.triangles(t, 0)) +
                               full.rest_positions.row(full.triangles(t, 1)) +
                               full.rest_positions.row(full.triangles(t, 2)))
                                  .transpose() /
                              3.0;
    if (c.x() > 0.4 && c.x() < 0.6 && c.y() > 0.25) continue;  // the slot
    kept.push_back(t);
  }
  skinning::Triangles f(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t k = 0; k < kept.size(); ++k)
    f.row(static_cast<Eigen::Index>(k)) = full.triangles.row(kept[k]);
  const auto mesh = test::single_part_mesh(full.rest_positions, f);
  const auto topo = skinning::build_topology(mesh);
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  auto m = make_method("enhanced-dual-cone", mesh, topo);
  FrameResult out;
  m->detect_dcd(x, out);
  EXPECT_EQ(stats_of(*m).nodes_culled, 1);
  EXPECT_EQ(stats_of(*m).nodes_tested, 1);
  EXPECT_GT(stats_of(*m).contour.chain_cuts, 0);
  EXPECT_GT(
      stats_of(*m).ten_results_failed[0] + stats_of(*m).ten_results_failed[1] +
          stats_of(*m).ten_results_failed[2] + stats_of(*m).ten_results_failed[3],
      0);
  FrameResult c;
  m->detect_ccd(x, test::translated(x, Eigen::Vector3d(0.0, 0.01, 0.02)), c);
  EXPECT_EQ(stats_of(*m).nodes_culled, 1);
}

TEST(ConeMethods, BothTraversalSchemesFindWhatBvhFinds) {
  // Algorithm 3 (straight to the sub-surfaces) and the simple top-down scheme.
  for (const OpenScene& s :
       {test::pipe_scene(12, 72, {0.5, 0.7}), test::crumpled_tube_scene(12, 56, {0.55, 0.6})}) {
    const FrameResult bvh = run_dcd("bvh", s, 0);
    const FrameResult bvh_ccd = run_ccd("bvh", s, 0);
    for (const bool grand : {true, false}) {
      auto m = make_enhanced_dual_cone_method(
          s.mesh, s.topo, {}, {.grandchildren_descent = grand, .triangles = {}});
      FrameResult d;
      m->detect_dcd(s.frames[0], d);
      EXPECT_EQ(d.dcd_pairs, bvh.dcd_pairs) << s.name << " " << grand;
      FrameResult c;
      m->detect_ccd(s.frames[0], s.frames[1], c);
      EXPECT_TRUE(same_ccd_contacts(s, 0, c, bvh_ccd)) << s.name << " " << grand;
      EXPECT_GT(stats_of(*m).nodes_culled, 0);
    }
  }
}

TEST(ConeMethods, LargerLeavesAndExactElementaryTestsGiveTheSameAnswer) {
  const OpenScene s = test::crumpled_tube_scene(8, 32, {0.55, 0.6});
  const FrameResult brute = run_dcd("brute", s, 1);
  const FrameResult brute_ccd = run_ccd("brute", s, 0, {.accuracy = ccd::Accuracy::exact});
  ASSERT_FALSE(brute.dcd_pairs.empty());
  ASSERT_FALSE(brute_ccd.contacts.empty());
  for (const auto& name : kExactMethods) {
    for (const int leaf : {1, 3, 8}) {
      const MethodOptions opts{.bvh = {.leaf_size = leaf}};
      EXPECT_EQ(run_dcd(name, s, 1, opts).dcd_pairs, brute.dcd_pairs) << name << " leaf " << leaf;
    }
    // With the exact (rational) elementary tests the contact sets are equal, not just equivalent.
    EXPECT_EQ(keys(run_ccd(name, s, 0, {.accuracy = ccd::Accuracy::exact})), keys(brute_ccd))
        << name;
  }
}

TEST(ConeMethods, ContactDistanceTurnsCullingOffAndMatchesBvh) {
  const auto s = test::wrap_sheet_scene(6, 60, {0.30, 0.36});
  const MethodOptions opts{.min_separation = 1e-3};
  const FrameResult bvh = run_ccd("bvh", s, 0, opts);
  for (const auto& name : kExactMethods) {
    auto m = make_method(name, s.mesh, s.topo, opts);
    FrameResult out;
    m->detect_ccd(s.frames[0], s.frames[1], out);
    EXPECT_TRUE(stats_of(*m).culling_disabled);
    EXPECT_EQ(keys(out), keys(bvh)) << name;
  }
}

TEST(DualCone, MissesCollisionsInsideThePipeAndTheWrappedSheetWhereEnhancedDoesNot) {
  // Paper 000 Fig. 1/3/4: nodes away from the original boundary, holding two layers with
  // similar normals, pass FASTCD's test and are culled although the layers intersect.
  for (const OpenScene& s :
       {test::pipe_scene(16, 96, {0.6, 0.9}), test::wrap_sheet_scene(10, 120, {0.30, 0.36})}) {
    SCOPED_TRACE(s.name);
    const FrameResult bvh = run_dcd("bvh", s, 0);
    const FrameResult dual = run_dcd("dual-cone", s, 0);
    const FrameResult enhanced = run_dcd("enhanced-dual-cone", s, 0);
    ASSERT_FALSE(bvh.dcd_pairs.empty());
    EXPECT_EQ(enhanced.dcd_pairs, bvh.dcd_pairs);
    // dual-cone: a strict subset (it only culls; its elementary tests are the same).
    EXPECT_LT(dual.dcd_pairs.size(), bvh.dcd_pairs.size());
    EXPECT_TRUE(std::includes(
        bvh.dcd_pairs.begin(), bvh.dcd_pairs.end(), dual.dcd_pairs.begin(), dual.dcd_pairs.end()));
    // CCD likewise.
    const FrameResult bvh_ccd = run_ccd("bvh", s, 0);
    const FrameResult dual_ccd = run_ccd("dual-cone", s, 0);
    EXPECT_TRUE(same_ccd_contacts(s, 0, run_ccd("enhanced-dual-cone", s, 0), bvh_ccd));
    EXPECT_LT(dual_ccd.contacts.size(), bvh_ccd.contacts.size());
    const auto d = keys(dual_ccd);
    const auto b = keys(bvh_ccd);
    EXPECT_TRUE(std::includes(b.begin(), b.end(), d.begin(), d.end()));
  }
}

// `auto` asks a cone group's count without the contours first (count_dcd_pairs_at_least) and
// frees the method when even that reaches its cap: the bound must never exceed the count, or a
// group whose cones pay would be dropped. It visits a subset of the nodes (every node the contour
// test culls, the normal test alone culls too), so its pairs are a subset.
TEST(ConeMethods, CountWithoutContoursIsALowerBoundOfTheCount) {
  std::vector<OpenScene> scenes = small_open_scenes();
  scenes.push_back(test::cloth_funnel_scene(test::asset("cloth-funnel/frames")));
  constexpr std::int64_t kAll = std::numeric_limits<std::int64_t>::max();
  std::int64_t strictly_lower = 0;
  for (const OpenScene& s : scenes) {
    for (const auto& name : kExactMethods) {
      MethodOptions apart;
      apart.min_separation = 1e-3;  // no culling at all: the two counts agree
      for (const MethodOptions& options : {MethodOptions{}, apart}) {
        auto m = make_method(name, s.mesh, s.topo, options);
        auto* cones = dynamic_cast<detail::ConeMethodBase*>(m.get());
        ASSERT_NE(cones, nullptr) << name;
        for (const auto& x : s.frames) {
          const std::int64_t lower = cones->count_dcd_pairs_at_least(x, kAll);
          const std::int64_t count = cones->count_dcd_pairs(x, kAll);
          EXPECT_LE(lower, count) << name;
          if (options.min_separation > 0.0) {
            EXPECT_GT(count, 0) << name;
            EXPECT_EQ(lower, count) << name;
          }
          strictly_lower += lower < count ? 1 : 0;
          // With a cap, both stop there or below it as they would without.
          const std::int64_t cap = count / 2 + 1;
          EXPECT_EQ(cones->count_dcd_pairs(x, cap) >= cap, count >= cap) << name;
          EXPECT_LE(std::min(cones->count_dcd_pairs_at_least(x, cap), cap), std::min(count, cap));
        }
      }
    }
  }
  // The contour tests cull less than the normal tests alone somewhere (the crossing layers).
  EXPECT_GT(strictly_lower, 0);
}

TEST(ConeMethods, ContoursAreThereBeforeTheFirstQuery) {
  // Built on first need (a query, the count, or this accessor): never an empty set of contours.
  const auto s = test::wrap_sheet_scene(8, 90, {0.30, 0.36});
  for (const auto& name : kExactMethods) {
    auto m = make_method(name, s.mesh, s.topo);
    const auto* cones = dynamic_cast<const detail::ConeMethodBase*>(m.get());
    ASSERT_NE(cones, nullptr) << name;
    std::int64_t nodes = 0;
    for (const std::int64_t n : m->cone_statistics()->contours().status_counts()) nodes += n;
    EXPECT_EQ(nodes, static_cast<std::int64_t>(cones->hierarchy().nodes().size())) << name;
    EXPECT_GT(
        m->cone_statistics()
            ->contours()
            .status_counts()[static_cast<std::size_t>(ContourStatus::loops)],
        0)
        << name;
  }
}

TEST(ConeMethods, ClothFunnelMatchesBvh) {
  const OpenScene s = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  ASSERT_EQ(s.mesh.num_triangles(), 18484);
  const FrameResult bvh_dcd = run_dcd("bvh", s, 1);
  EXPECT_FALSE(bvh_dcd.dcd_pairs.empty());
  for (const auto& name : kExactMethods) {
    EXPECT_EQ(run_dcd(name, s, 1).dcd_pairs, bvh_dcd.dcd_pairs) << name;
  }
  // FASTCD misses intersecting pairs in this real cloth too.
  const FrameResult dual = run_dcd("dual-cone", s, 1);
  EXPECT_LT(dual.dcd_pairs.size(), bvh_dcd.dcd_pairs.size());
  // The step's ground truth (SOURCES.md): 27 VF and 107 EE contacts.
  const FrameResult bvh = run_ccd("bvh", s, 0);
  EXPECT_EQ(bvh.counters.vf_contacts, 27);
  EXPECT_EQ(bvh.counters.ee_contacts, 107);
  // Enough candidates for several CCD blocks (culling/candidates.hpp): the blocks lose nothing.
  EXPECT_GT(bvh.counters.candidate_pairs, static_cast<std::int64_t>(3 * kCcdBlockPairs));
  for (const auto& name : kExactMethods) {
    EXPECT_TRUE(same_ccd_contacts(s, 0, run_ccd(name, s, 0), bvh)) << name;
  }
}

}  // namespace
}  // namespace skelcd::culling
