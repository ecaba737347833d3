// brute, bvh and kdop on real rigged characters (assets/characters, see assets/SOURCES.md): the
// bind pose against posed frames of their clips (large motions) and consecutive samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "culling/elementary.hpp"
#include "culling/method.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/method_agreement.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using agreement::expect_same_dcd;
using agreement::same_pairs_subset;

struct Character {
  std::string file;
  std::string clip;
  double rate_hz;  // 0: the clip's frame rate, else 30
  bool exact_too;  // also compare under the (slow, GMP) exact accuracy
};

class Characters : public ::testing::TestWithParam<Character> {};

TEST_P(Characters, BruteBvhAndKdopAgree) {
  const Character& c = GetParam();
  const auto model = skinning::load_model(test::asset("characters/" + c.file));
  const skinning::Mesh& mesh = *model.mesh;
  const skinning::Topology topo = skinning::build_topology(mesh);
  const auto motion = model.motion({.clip = c.clip, .rate_hz = c.rate_hz});
  ASSERT_GE(motion->num_samples(), 4);

  // Welded positions: the bind pose, then three samples spread over the clip.
  std::vector<skinning::Positions> x;
  skinning::Positions file_positions, welded;
  skinning::gather_welded(topo, mesh.rest_positions, welded);
  x.push_back(welded);
  const int n = motion->num_samples();
  for (const int i : {n / 3, n / 3 + 1, (2 * n) / 3}) {
    motion->positions(i, file_positions);
    skinning::gather_welded(topo, file_positions, welded);
    x.push_back(welded);
  }

  std::int64_t contacts = 0, dcd = 0, bvh_tests = 0, brute_tests = 0;
  std::vector<ccd::Accuracy> accuracies{ccd::Accuracy::conservative};
  if (c.exact_too) accuracies.push_back(ccd::Accuracy::exact);
  for (const ccd::Accuracy acc : accuracies) {
    const MethodOptions options{.accuracy = acc};
    auto brute = make_method("brute", mesh, topo, options);
    auto bvh = make_method("bvh", mesh, topo, options);
    auto kdop = make_method("kdop", mesh, topo, options);
    for (std::size_t i = 0; i + 1 < x.size(); ++i) {
      const std::string what =
          c.file + " " + std::string(ccd::to_string(acc)) + " interval " + std::to_string(i);
      FrameResult rb, rv, rk;
      brute->detect_ccd(x[i], x[i + 1], rb);
      bvh->detect_ccd(x[i], x[i + 1], rv);
      kdop->detect_ccd(x[i], x[i + 1], rk);
      EXPECT_EQ(rv.contacts, rb.contacts) << what;
      EXPECT_EQ(rv.counters.vf_tests, rb.counters.vf_tests) << what;
      EXPECT_EQ(rv.counters.ee_tests, rb.counters.ee_tests) << what;
      if (acc == ccd::Accuracy::exact) {
        EXPECT_EQ(rk.contacts, rb.contacts) << what;
      } else {
        EXPECT_TRUE(same_pairs_subset(rk.contacts, rb.contacts)) << what;
      }
      contacts += static_cast<std::int64_t>(rb.contacts.size());
      bvh_tests += rv.counters.bv_tests + rv.counters.feature_bv_tests;
      brute_tests += rb.counters.feature_bv_tests;

      const FrameResult db = expect_same_dcd(*brute, *bvh, *kdop, x[i + 1], what);
      dcd += static_cast<std::int64_t>(db.dcd_pairs.size());
    }
  }
  // The bind-pose-to-frame interval moves a lot: something must reach the elementary tests, and
  // the hierarchy must do fewer volume tests than brute force.
  EXPECT_LT(bvh_tests, brute_tests) << c.file;
  RecordProperty("ccd_contacts", static_cast<int>(contacts));
  RecordProperty("dcd_pairs", static_cast<int>(dcd));
}

TEST(ElementaryThreads, SplittingTheTestsChangesNothing) {
  // The bind pose against a mid-clip frame of CesiumMan: thousands of candidates, so the split
  // path (kParallelElementaryThreshold) runs. Contacts, pairs and counters must be identical.
  const auto model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  const skinning::Mesh& mesh = *model.mesh;
  const skinning::Topology topo = skinning::build_topology(mesh);
  const auto motion = model.motion({});
  skinning::Positions file_positions, x0, x1;
  skinning::gather_welded(topo, mesh.rest_positions, x0);
  motion->positions(motion->num_samples() / 2, file_positions);
  skinning::gather_welded(topo, file_positions, x1);
  for (const char* name : {"bvh", "kdop", "brute"}) {
    MethodOptions serial;
    MethodOptions split;
    split.elementary.threads = 2;
    auto a = make_method(name, mesh, topo, serial);
    auto b = make_method(name, mesh, topo, split);
    FrameResult ra, rb, da, db;
    a->detect_ccd(x0, x1, ra);
    b->detect_ccd(x0, x1, rb);
    ASSERT_GE(static_cast<std::size_t>(ra.counters.ee_tests), kParallelElementaryThreshold) << name;
    EXPECT_GT(ra.contacts.size(), 0u) << name;
    EXPECT_EQ(rb.contacts, ra.contacts) << name;
    EXPECT_EQ(rb.counters.vf_tests, ra.counters.vf_tests) << name;
    EXPECT_EQ(rb.counters.ee_tests, ra.counters.ee_tests) << name;
    EXPECT_EQ(rb.counters.vf_contacts, ra.counters.vf_contacts) << name;
    EXPECT_EQ(rb.counters.ee_contacts, ra.counters.ee_contacts) << name;
    a->detect_dcd(x1, da);
    b->detect_dcd(x1, db);
    ASSERT_GE(static_cast<std::size_t>(da.counters.tt_tests), kParallelElementaryThreshold) << name;
    EXPECT_GT(da.dcd_pairs.size(), 0u) << name;
    EXPECT_EQ(db.dcd_pairs, da.dcd_pairs) << name;
    EXPECT_EQ(db.counters.tt_tests, da.counters.tt_tests) << name;
    EXPECT_EQ(db.counters.dcd_pairs, da.counters.dcd_pairs) << name;
    // Again on the same objects: the reused per-thread buffers hold nothing of the last call.
    FrameResult again;
    b->detect_ccd(x0, x1, again);
    EXPECT_EQ(again.contacts, ra.contacts) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Assets,
    Characters,
    ::testing::Values(
        Character{"RiggedFigure.glb", "", 10.0, true},
        Character{"Fox.glb", "Run", 0.0, false},
        Character{"RobotExpressive.glb", "Dance", 0.0, false},
        Character{"CesiumMan.glb", "", 0.0, false}),
    [](const ::testing::TestParamInfo<Character>& p) {
      return p.param.file.substr(0, p.param.file.find('.'));
    });

}  // namespace
}  // namespace skelcd::culling
