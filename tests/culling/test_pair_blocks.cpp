// Bounded memory: every method with a traversal tests its triangle pairs in blocks of
// MethodOptions::block_pairs (culling/pair_blocks.hpp). Cut into many small blocks, a query finds
// exactly what it finds in one piece: the same contacts with the same times, the same DCD pairs,
// the same work counters.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "culling/method.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"

namespace skelcd::culling {
namespace {

using test::OpenScene;

constexpr std::size_t kSmallBlock = 16;
constexpr std::size_t kOnePiece = std::numeric_limits<std::size_t>::max();

/// Every method that traverses (brute force has no blocks; rvbc/dynamic need a rig).
const std::vector<std::string> kBlockedMethods = {
    "bvh", "kdop", "normal-cone", "dual-cone", "enhanced-dual-cone", "auto"};

FrameResult run(
    const std::string& method,
    const OpenScene& s,
    std::size_t block_pairs,
    bool continuous,
    std::size_t sample) {
  auto m = make_method(method, s.mesh, s.topo, MethodOptions{.block_pairs = block_pairs});
  FrameResult out;
  if (continuous) {
    m->detect_ccd(s.frames[sample], s.frames[sample + 1], out);
  } else {
    m->detect_dcd(s.frames[sample], out);
  }
  return out;
}

void expect_same_counters(const Counters& got, const Counters& want) {
#define SKELCD_EXPECT_COUNTER(name, meaning) EXPECT_EQ(got.name, want.name) << #name;
  SKELCD_COUNTERS(SKELCD_EXPECT_COUNTER)
#undef SKELCD_EXPECT_COUNTER
}

void expect_blocks_change_nothing(const OpenScene& s) {
  for (const auto& method : kBlockedMethods) {
    for (const bool continuous : {false, true}) {
      SCOPED_TRACE(s.name + ", " + method + (continuous ? ", CCD" : ", DCD"));
      const FrameResult whole = run(method, s, kOnePiece, continuous, 0);
      const FrameResult blocked = run(method, s, kSmallBlock, continuous, 0);
      // Many blocks: a block holds at most kSmallBlock pairs plus one bucket pair's (16).
      EXPECT_GT(whole.counters.candidate_pairs, static_cast<std::int64_t>(8 * kSmallBlock));
      if (method != "dual-cone") {  // dual-cone may miss them all (it is kept to show that)
        EXPECT_FALSE(continuous ? whole.contacts.empty() : whole.dcd_pairs.empty());
      }
      EXPECT_EQ(blocked.contacts, whole.contacts);  // kind, ids and times of impact, in order
      EXPECT_EQ(blocked.dcd_pairs, whole.dcd_pairs);
      expect_same_counters(blocked.counters, whole.counters);
    }
  }
}

TEST(PairBlocks, SmallBlocksFindExactlyWhatOnePieceFinds) {
  // A skirt pressing into a closed body: under `auto` the open group's cone method, the closed
  // group's `bvh` and the pair traversal between the groups all run in blocks.
  expect_blocks_change_nothing(test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5}));
  // A sheet wrapped through itself: one open component, the cone methods' own blocks.
  expect_blocks_change_nothing(test::wrap_sheet_scene(10, 120, {0.30, 0.36}));
}

TEST(PairBlocks, BlockSizeZeroIsRefused) {
  const OpenScene s = test::wrap_sheet_scene(4, 20, {0.30, 0.36});
  EXPECT_THROW(
      (void)make_method("bvh", s.mesh, s.topo, MethodOptions{.block_pairs = 0}), InvalidInput);
}

}  // namespace
}  // namespace skelcd::culling
