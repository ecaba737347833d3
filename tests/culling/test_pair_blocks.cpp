// Bounded memory: every method with a traversal tests its triangle pairs in blocks of
// MethodOptions::block_pairs (culling/pair_blocks.hpp). Cut into many small blocks, a query finds
// exactly what it finds in one piece: the same contacts with the same times, the same DCD pairs,
// the same work counters. With threads for its tests, a block is tested while the traversal
// produces the next (PairBlocks::drain_overlapped), and again the query finds exactly that.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "ccd/triangle_triangle.hpp"
#include "culling/feature_topology.hpp"
#include "culling/method.hpp"
#include "culling/pair_blocks.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using test::OpenScene;

constexpr std::size_t kSmallBlock = 16;
constexpr std::size_t kOnePiece = std::numeric_limits<std::size_t>::max();

/// Every method that traverses (brute force has no blocks; rvbc/dynamic need a rig).
const std::vector<std::string> kBlockedMethods = {
    "bvh", "kdop", "normal-cone", "dual-cone", "enhanced-dual-cone", "auto"};

/// The query of `method` on s at `sample` (CCD to the next sample, or DCD), its elementary tests
/// on `threads` threads (in an arena of that many, as the runner gives a query alone).
FrameResult run(
    const std::string& method,
    const OpenScene& s,
    std::size_t block_pairs,
    bool continuous,
    std::size_t sample,
    std::int32_t threads = 1) {
  MethodOptions options{.block_pairs = block_pairs};
  options.elementary.threads = threads;
  auto m = make_method(method, s.mesh, s.topo, options);
  FrameResult out;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    if (continuous) {
      m->detect_ccd(s.frames[sample], s.frames[sample + 1], out);
    } else {
      m->detect_dcd(s.frames[sample], out);
    }
  });
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

/// Two threads against one, each method, CCD and DCD: the same findings (kind, ids, times of
/// impact, in order) and counters.
void expect_threads_change_nothing(
    const OpenScene& s,
    const std::vector<std::string>& methods,
    std::size_t block_pairs,
    std::size_t sample) {
  for (const auto& method : methods) {
    for (const bool continuous : {false, true}) {
      SCOPED_TRACE(s.name + ", " + method + (continuous ? ", CCD" : ", DCD"));
      const FrameResult one = run(method, s, block_pairs, continuous, sample, 1);
      const FrameResult two = run(method, s, block_pairs, continuous, sample, 2);
      // Three blocks or more, so that two or more are tested beside an installment.
      EXPECT_GT(one.counters.candidate_pairs, static_cast<std::int64_t>(2 * block_pairs));
      EXPECT_FALSE(continuous ? one.contacts.empty() : one.dcd_pairs.empty());
      EXPECT_EQ(two.contacts, one.contacts);
      EXPECT_EQ(two.dcd_pairs, one.dcd_pairs);
      expect_same_counters(two.counters, one.counters);
    }
  }
}

TEST(PairBlocks, BlocksTestedBesideTheTraversalFindExactlyWhatOneThreadFinds) {
  // The methods whose traversal runs in installments (drain_overlapped): `bvh`, `kdop` and the
  // groups of `auto`; the cone methods push their pairs and test on one thread (compared too).
  const std::vector<std::string> methods = {"bvh", "kdop", "auto", "enhanced-dual-cone"};
  expect_threads_change_nothing(test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.5}), methods, 64, 0);
  expect_threads_change_nothing(test::wrap_sheet_scene(10, 120, {0.30, 0.36}), methods, 64, 0);
  // A real step: the cloth-funnel's 18,484 triangles pinched and folded, in blocks of the size
  // the methods use (kCcdBlockPairs).
  expect_threads_change_nothing(
      test::cloth_funnel_scene(test::asset("cloth-funnel/frames")),
      {"bvh", "kdop", "auto"},
      kCcdBlockPairs,
      0);
}

// drain_overlapped itself: a DCD of a wrapped sheet whose pairs come from a given list in
// installments, and whose triangle test is one of the test's own.
std::atomic<int> g_tests_run{0};
std::atomic<bool> g_tests_throw{false};

bool counting_test(const ccd::TriangleTriangleQuery&, const ccd::SharedCorners&) {
  ++g_tests_run;
  if (g_tests_throw) throw std::runtime_error("test failed");
  return false;
}

/// Every pair of triangles a < b of the sheet whose ids differ by 1 to 8: each one a DCD candidate
/// that reaches the test (the sheet has no parts to exclude, and a custom test sees every pair).
std::vector<TrianglePair> some_pairs(std::int32_t num_triangles) {
  std::vector<TrianglePair> pairs;
  for (std::int32_t a = 0; a < num_triangles; ++a) {
    for (std::int32_t d = 1; d <= 8 && a + d < num_triangles; ++d) pairs.push_back({a, a + d});
  }
  return pairs;
}

/// A DCD over `pairs` through drain_overlapped with blocks of 64 on `threads`; `step_throws_at`:
/// the installment that throws (0: none). Returns the installments made.
int overlapped_dcd(
    const OpenScene& s,
    const FeatureTopology& features,
    const std::vector<TrianglePair>& pairs,
    std::int32_t threads,
    int step_throws_at,
    FrameResult& out) {
  ElementaryTests tests;
  tests.triangles = &counting_test;
  tests.threads = threads;
  PairBlocks<3> blocks(64, 64);
  std::size_t next = 0;
  int installments = 0;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    blocks.start_dcd(features, s.frames[0], tests, out);
    blocks.drain_overlapped([&](std::vector<TrianglePair>& block, std::size_t max_pairs) {
      if (++installments == step_throws_at) throw std::invalid_argument("installment failed");
      const std::size_t first = block.size();
      while (next < pairs.size() && block.size() - first < max_pairs)
        block.push_back(pairs[next++]);
      return next == pairs.size();
    });
    blocks.finish();
  });
  return installments;
}

TEST(PairBlocks, OverlappedDrainTestsEveryPairOnceAndPassesOnErrors) {
  const OpenScene s = test::wrap_sheet_scene(10, 120, {0.30, 0.36});
  const FeatureTopology features(s.mesh, s.topo);
  const std::vector<TrianglePair> pairs = some_pairs(features.num_triangles());
  ASSERT_GT(pairs.size(), 20u * 64u);
  for (const std::int32_t threads : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    // Every pair tested once, whatever runs beside what.
    g_tests_run = 0;
    g_tests_throw = false;
    FrameResult out;
    const int installments = overlapped_dcd(s, features, pairs, threads, 0, out);
    EXPECT_EQ(g_tests_run.load(), static_cast<int>(pairs.size()));
    EXPECT_EQ(out.counters.candidate_pairs, static_cast<std::int64_t>(pairs.size()));
    EXPECT_GE(installments, static_cast<int>(pairs.size() / 64));
    // An installment that throws: its exception, after the block being tested is done.
    FrameResult failed;
    EXPECT_THROW(
        (void)overlapped_dcd(s, features, pairs, threads, 5, failed), std::invalid_argument);
    // Tests that throw: theirs, after the installment running beside them is done.
    g_tests_throw = true;
    FrameResult failed_tests;
    EXPECT_THROW(
        (void)overlapped_dcd(s, features, pairs, threads, 0, failed_tests), std::runtime_error);
    g_tests_throw = false;
  }
}

TEST(PairBlocks, BlockSizeZeroIsRefused) {
  const OpenScene s = test::wrap_sheet_scene(4, 20, {0.30, 0.36});
  EXPECT_THROW(
      (void)make_method("bvh", s.mesh, s.topo, MethodOptions{.block_pairs = 0}), InvalidInput);
}

}  // namespace
}  // namespace skelcd::culling
