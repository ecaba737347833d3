// brute, bvh and kdop on every generator's rig (skinning/generators.hpp) around its known first
// contact: the three report the same DCD pairs and (exact accuracy) the same CCD contacts, and
// both queries agree with the generator's own answer — the last free frame has no intersecting
// pair, the first intersecting frame has one, and the interval between them has a CCD contact (two
// vertex-disjoint triangles that are apart at one end and intersect at the other must touch in
// between, under any continuous motion).
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>

#include "culling/method.hpp"
#include "skinning/generators.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/method_agreement.hpp"

namespace skelcd::culling {
namespace {

using agreement::expect_same_dcd;
using agreement::same_pairs_subset;

class GeneratedRigs : public ::testing::TestWithParam<std::string> {};

TEST_P(GeneratedRigs, BruteBvhAndKdopAgreeAroundTheKnownFirstContact) {
  const auto generated = skinning::generate(skinning::parse_generator_spec(GetParam()));
  const skinning::Mesh& mesh = generated.rig.mesh;
  const auto& answer = generated.answer;
  const int first_hit = answer.first_intersecting_frame;
  ASSERT_GE(answer.last_free_frame, 1) << GetParam();
  ASSERT_EQ(first_hit, answer.last_free_frame + 1) << GetParam() << ": an undecided frame";
  const skinning::Topology topo = skinning::build_topology(mesh);

  // Welded positions of samples first_hit - 2 … first_hit + 1 (the clip keys are the frames).
  std::vector<skinning::Positions> x;
  skinning::Positions file_positions, welded;
  const skinning::RigMotion motion(
      std::make_shared<const skinning::Rig>(generated.rig), {.clip = 0});
  const int first = first_hit - 2, last = std::min(first_hit + 1, motion.num_samples() - 1);
  for (int f = first; f <= last; ++f) {
    motion.positions(f, file_positions);
    skinning::gather_welded(topo, file_positions, welded);
    x.push_back(welded);
  }

  for (const ccd::Accuracy acc : {ccd::Accuracy::conservative, ccd::Accuracy::exact}) {
    const MethodOptions options{.accuracy = acc};
    auto brute = make_method("brute", mesh, topo, options);
    auto bvh = make_method("bvh", mesh, topo, options);
    auto kdop = make_method("kdop", mesh, topo, options);
    for (std::size_t i = 0; i + 1 < x.size(); ++i) {
      const int f0 = first + static_cast<int>(i);
      const std::string what = GetParam() + " " + std::string(ccd::to_string(acc)) + " interval " +
                               std::to_string(f0) + "-" + std::to_string(f0 + 1);
      FrameResult rb, rv, rk;
      brute->detect_ccd(x[i], x[i + 1], rb);
      bvh->detect_ccd(x[i], x[i + 1], rv);
      kdop->detect_ccd(x[i], x[i + 1], rk);
      EXPECT_EQ(rv.contacts, rb.contacts) << what;
      if (acc == ccd::Accuracy::exact) {
        EXPECT_EQ(rk.contacts, rb.contacts) << what;
      } else {
        // The 16-DOP rejects some feature pairs that only the conservative error bound keeps.
        EXPECT_TRUE(same_pairs_subset(rk.contacts, rb.contacts)) << what;
      }
      if (f0 + 1 == first_hit) {
        EXPECT_FALSE(rb.contacts.empty()) << what << ": apart at " << f0 << ", intersecting at "
                                          << first_hit << ", so something touched in between";
      }

      const FrameResult db = expect_same_dcd(*brute, *bvh, *kdop, x[i + 1], what);
      if (f0 + 1 <= answer.last_free_frame) {
        EXPECT_TRUE(db.dcd_pairs.empty()) << what << ": frame " << f0 + 1 << " is known free";
      } else {
        EXPECT_FALSE(db.dcd_pairs.empty())
            << what << ": frame " << f0 + 1 << " is known to intersect";
      }
    }
    if (acc == ccd::Accuracy::exact) break;
  }
}

// Small sizes so that brute force and the exact accuracy stay quick; one spec per generator.
INSTANTIATE_TEST_SUITE_P(
    EveryGenerator,
    GeneratedRigs,
    ::testing::Values(
        "gen:rope?triangles=1000&frames=60",
        "gen:octopus?triangles=1000&frames=60",
        "gen:hand?triangles=1000&frames=60",
        "gen:pipe?triangles=1000&frames=60",
        "gen:cloth?triangles=1000&frames=60",
        "gen:panda?frames=60"),
    [](const ::testing::TestParamInfo<std::string>& param_info) {
      return param_info.param.substr(4, param_info.param.find('?') - 4);
    });

}  // namespace
}  // namespace skelcd::culling
