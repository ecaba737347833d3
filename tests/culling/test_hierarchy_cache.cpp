// HierarchyCache: a parallel run's methods build each hierarchy once and copy it. A copy must be
// the tree the caller would have built (same nodes, order and wide nodes), a tree is shared only
// between callers that would have built the same one, a failing build fails every caller
// waiting for it, and a closed cache holds nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "culling/candidates.hpp"
#include "culling/feature_topology.hpp"
#include "culling/hierarchy_cache.hpp"
#include "culling/method.hpp"
#include "culling/traversal.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/welded_character.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

/// Same binary nodes, triangle order and wide nodes (children, counts, nodes, lanes).
template <int N>
void expect_same_tree(const Bvh<N>& a, const Bvh<N>& b) {
  ASSERT_EQ(a.nodes().size(), b.nodes().size());
  for (std::size_t n = 0; n < a.nodes().size(); ++n) {
    ASSERT_EQ(a.nodes()[n].begin, b.nodes()[n].begin) << "node " << n;
    ASSERT_EQ(a.nodes()[n].end, b.nodes()[n].end) << "node " << n;
    ASSERT_EQ(a.nodes()[n].right, b.nodes()[n].right) << "node " << n;
  }
  ASSERT_TRUE(std::equal(
      a.triangle_order().begin(),
      a.triangle_order().end(),
      b.triangle_order().begin(),
      b.triangle_order().end()));
  ASSERT_EQ(a.wide_nodes().size(), b.wide_nodes().size());
  for (std::size_t n = 0; n < a.wide_nodes().size(); ++n) {
    const auto& wa = a.wide_nodes()[n];
    const auto& wb = b.wide_nodes()[n];
    ASSERT_EQ(wa.num_children, wb.num_children) << "wide node " << n;
    ASSERT_EQ(0, std::memcmp(wa.child, wb.child, sizeof wa.child)) << "wide node " << n;
    ASSERT_EQ(0, std::memcmp(wa.count, wb.count, sizeof wa.count)) << "wide node " << n;
    ASSERT_EQ(0, std::memcmp(wa.node, wb.node, sizeof wa.node)) << "wide node " << n;
  }
  EXPECT_EQ(a.depth(), b.depth());
  EXPECT_EQ(a.leaf_size(), b.leaf_size());
  EXPECT_EQ(a.node_bounds().size(), b.node_bounds().size());
}

/// Runs ask(0) … ask(n − 1) on n threads that start asking together (each waits for all).
template <class Ask>
void at_once(std::size_t n, Ask&& ask) {
  std::vector<std::thread> threads;
  std::atomic<std::size_t> ready{0};
  for (std::size_t i = 0; i < n; ++i) {
    threads.emplace_back([&, i] {
      ++ready;
      while (ready.load() < n) std::this_thread::yield();
      ask(i);
    });
  }
  for (auto& t : threads) t.join();
}

TEST(HierarchyCache, CallersOfOneTreeShareOneBuildAndGetTheTreeTheirOwnBuildGives) {
  const test::WeldedCharacter fox("Fox.glb");
  const auto& triangles = fox.topology.welded_triangles;
  const BvhOptions options{.leaf_size = 1, .node_volumes = false};
  const Bvh<3> own(triangles, fox.rest, options);

  // Four threads ask at once: one builds, three wait for it and copy.
  HierarchyCache cache;
  std::vector<Bvh<3>> got(4);
  at_once(got.size(), [&](std::size_t i) {
    got[i] = cache.get<3>(triangles, fox.rest, nullptr, options);
  });
  EXPECT_EQ(cache.builds(), 1u);
  EXPECT_EQ(cache.reuses(), 3u);
  for (const auto& tree : got) expect_same_tree(tree, own);
  // build_hierarchy without a cache is the plain build.
  expect_same_tree(build_hierarchy<3>(nullptr, triangles, fox.rest, nullptr, options), own);
}

TEST(HierarchyCache, TreesAreSharedOnlyBetweenCallersThatWouldBuildTheSameOne) {
  const test::WeldedCharacter fox("Fox.glb");
  const auto& triangles = fox.topology.welded_triangles;
  const BvhOptions options{.leaf_size = 1, .node_volumes = false};
  HierarchyCache cache;
  (void)cache.get<3>(triangles, fox.rest, nullptr, options);
  ASSERT_EQ(cache.builds(), 1u);

  // Each of these differs from the first in one input and gets a tree of its own, equal to its
  // own build.
  skinning::Positions moved = fox.rest;
  moved(7, 1) = std::nextafter(moved(7, 1), 1e300);  // one coordinate, one bit
  skinning::Triangles flipped = triangles;
  std::swap(flipped(3, 1), flipped(3, 2));  // one triangle's orientation
  std::vector<std::int32_t> half;
  for (std::int32_t f = 0; f < static_cast<std::int32_t>(triangles.rows()); f += 2)
    half.push_back(f);
  std::vector<std::int32_t> all(static_cast<std::size_t>(triangles.rows()));
  for (std::size_t f = 0; f < all.size(); ++f) all[f] = static_cast<std::int32_t>(f);

  std::size_t builds = 1;
  const auto fresh = [&](const char* what, auto&& get, auto&& own) {
    SCOPED_TRACE(what);
    expect_same_tree(get(), own());
    EXPECT_EQ(cache.builds(), ++builds);
    EXPECT_EQ(cache.reuses(), 0u);
  };
  fresh(
      "one coordinate",
      [&] { return cache.get<3>(triangles, moved, nullptr, options); },
      [&] { return Bvh<3>(triangles, moved, options); });
  fresh(
      "one triangle",
      [&] { return cache.get<3>(flipped, fox.rest, nullptr, options); },
      [&] { return Bvh<3>(flipped, fox.rest, options); });
  fresh(
      "a subset",
      [&] { return cache.get<3>(triangles, fox.rest, &half, options); },
      [&] { return Bvh<3>(triangles, fox.rest, half, options); });
  fresh(  // every triangle listed: the same tree, but not the same call
      "the whole as a subset",
      [&] { return cache.get<3>(triangles, fox.rest, &all, options); },
      [&] { return Bvh<3>(triangles, fox.rest, all, options); });
  fresh(
      "leaf size",
      [&] {
        return cache.get<3>(
            triangles, fox.rest, nullptr, BvhOptions{.leaf_size = 4, .node_volumes = false});
      },
      [&] {
        return Bvh<3>(triangles, fox.rest, BvhOptions{.leaf_size = 4, .node_volumes = false});
      });
  fresh(
      "node volumes",
      [&] { return cache.get<3>(triangles, fox.rest, nullptr, BvhOptions{}); },
      [&] { return Bvh<3>(triangles, fox.rest, BvhOptions{}); });
  fresh(
      "median split",
      [&] {
        return cache.get<3>(
            triangles,
            fox.rest,
            nullptr,
            BvhOptions{.node_volumes = false, .split = BvhSplit::median});
      },
      [&] {
        return Bvh<3>(
            triangles, fox.rest, BvhOptions{.node_volumes = false, .split = BvhSplit::median});
      });
  fresh(
      "16-DOP",
      [&] { return cache.get<8>(triangles, fox.rest, nullptr, options); },
      [&] { return Bvh<8>(triangles, fox.rest, options); });

  // Asked again, each is a copy.
  expect_same_tree(
      cache.get<3>(triangles, fox.rest, &half, options),
      Bvh<3>(triangles, fox.rest, half, options));
  expect_same_tree(
      cache.get<8>(triangles, fox.rest, nullptr, options), Bvh<8>(triangles, fox.rest, options));
  EXPECT_EQ(cache.builds(), builds);
  EXPECT_EQ(cache.reuses(), 2u);
}

// Shared objects (HierarchyCache::shared: `dynamic`'s rim-first FeatureTopology in a parallel
// run): four threads asking at once for one key run one build and hold the same object; another
// key builds its own; a failing build fails every caller of its key; once closed, each caller
// builds its own and the cache keeps nothing.
TEST(HierarchyCache, CallersOfOneKeyShareOneObjectAndOneBuild) {
  HierarchyCache cache;
  std::atomic<int> built{0};
  const auto build = [&built] {
    ++built;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the others ask meanwhile
    return std::make_shared<const std::vector<int>>(std::vector<int>{1, 2, 3});
  };
  std::vector<std::shared_ptr<const std::vector<int>>> got(4);
  at_once(got.size(), [&](std::size_t i) {
    got[i] = cache.shared<std::vector<int>>("numbers", build);
  });
  EXPECT_EQ(built.load(), 1);
  EXPECT_EQ(cache.builds(), 1u);
  EXPECT_EQ(cache.reuses(), 3u);
  for (const auto& g : got) {
    ASSERT_NE(g, nullptr);
    EXPECT_EQ(g.get(), got[0].get());
    EXPECT_EQ(*g, (std::vector<int>{1, 2, 3}));
  }
  const auto other = cache.shared<std::vector<int>>("other numbers", build);
  EXPECT_NE(other.get(), got[0].get());
  EXPECT_EQ(built.load(), 2);

  const auto fail = []() -> std::shared_ptr<const std::vector<int>> {
    throw InvalidInput("no numbers here");
  };
  for (int i = 0; i < 2; ++i) {
    EXPECT_THROW_MESSAGE(
        (void)cache.shared<std::vector<int>>("failing", fail), InvalidInput, "no numbers here");
  }
  EXPECT_EQ(cache.builds(), 3u);
  EXPECT_EQ(cache.reuses(), 4u);

  cache.close();
  const auto after = cache.shared<std::vector<int>>("numbers", build);
  const auto again = cache.shared<std::vector<int>>("numbers", build);
  EXPECT_EQ(built.load(), 4);
  EXPECT_NE(after.get(), again.get());
  EXPECT_NE(after.get(), got[0].get());
  EXPECT_EQ(cache.builds(), 3u);
  EXPECT_EQ(cache.reuses(), 4u);
}

TEST(HierarchyCache, AFailingBuildFailsEveryCallerWithItsMessage) {
  const test::WeldedCharacter fox("Fox.glb");
  skinning::Triangles bad = fox.topology.welded_triangles;
  bad(5, 2) = static_cast<std::int32_t>(fox.rest.rows());  // one past the last vertex
  HierarchyCache cache;
  for (int i = 0; i < 2; ++i) {
    EXPECT_THROW_MESSAGE(
        (void)cache.get<3>(bad, fox.rest, nullptr, BvhOptions{}),
        InvalidInput,
        "triangle 5 corner 2");
  }
  EXPECT_EQ(cache.builds(), 1u);
  EXPECT_EQ(cache.reuses(), 1u);
  // The good triangles still build.
  expect_same_tree(
      cache.get<3>(fox.topology.welded_triangles, fox.rest, nullptr, BvhOptions{}),
      Bvh<3>(fox.topology.welded_triangles, fox.rest, BvhOptions{}));
}

TEST(HierarchyCache, AClosedCacheBuildsForEachCallerAndKeepsNothing) {
  const test::WeldedCharacter fox("Fox.glb");
  const auto& triangles = fox.topology.welded_triangles;
  HierarchyCache cache;
  (void)cache.get<3>(triangles, fox.rest, nullptr, BvhOptions{});
  cache.close();
  for (int i = 0; i < 2; ++i) {
    expect_same_tree(
        cache.get<3>(triangles, fox.rest, nullptr, BvhOptions{}),
        Bvh<3>(triangles, fox.rest, BvhOptions{}));
  }
  EXPECT_EQ(cache.builds(), 1u);  // the one before close(); the others neither kept nor shared
  EXPECT_EQ(cache.reuses(), 0u);
}

TEST(HierarchyCache, APrebuiltTreeIsTheOneTheCallersGetAndIsBuiltOnce) {
  const test::WeldedCharacter fox("Fox.glb");
  const auto& triangles = fox.topology.welded_triangles;
  const BvhOptions options{.leaf_size = 1, .node_volumes = false};
  HierarchyCache cache;
  cache.prebuild<3>(triangles, fox.rest, nullptr, options);
  EXPECT_EQ(cache.builds(), 1u);
  cache.prebuild<3>(triangles, fox.rest, nullptr, options);  // asked for already: nothing
  EXPECT_EQ(cache.builds(), 1u);
  expect_same_tree(
      cache.get<3>(triangles, fox.rest, nullptr, options), Bvh<3>(triangles, fox.rest, options));
  EXPECT_EQ(cache.builds(), 1u);
  EXPECT_EQ(cache.reuses(), 1u);

  // A failing build is not reported by prebuild; each caller that asks gets its message.
  skinning::Triangles bad = triangles;
  bad(5, 2) = static_cast<std::int32_t>(fox.rest.rows());
  cache.prebuild<3>(bad, fox.rest, nullptr, options);
  EXPECT_EQ(cache.builds(), 2u);
  EXPECT_THROW_MESSAGE(
      (void)cache.get<3>(bad, fox.rest, nullptr, options), InvalidInput, "triangle 5 corner 2");

  // Closed: nothing is built or kept.
  cache.close();
  cache.prebuild<3>(triangles, fox.rest, nullptr, BvhOptions{});
  EXPECT_EQ(cache.builds(), 2u);
}

TEST(HierarchyCache, BvhMethodsTakeThePrebuiltTreeAndShareOneSlotAdjacency) {
  const test::WeldedCharacter fox("Fox.glb");
  const skinning::Mesh& mesh = *fox.loaded.mesh;
  auto cache = std::make_shared<HierarchyCache>();
  prebuild_bvh_hierarchy(*cache, mesh, fox.topology, BvhOptions{});
  ASSERT_EQ(cache->builds(), 1u);
  MethodOptions options;
  options.hierarchies = cache;
  options.features = std::make_shared<const FeatureTopology>(mesh, fox.topology);
  // The baseline's `bvh` and two workers' (one FeatureTopology, as in a parallel check): one
  // tree (prebuilt, then copied three times) and one slot adjacency (built by the first, shared).
  std::vector<std::unique_ptr<CullingMethod>> methods;
  for (int i = 0; i < 3; ++i) methods.push_back(make_method("bvh", mesh, fox.topology, options));
  EXPECT_EQ(cache->builds(), 2u);
  EXPECT_EQ(cache->reuses(), 3u + 2u);
  // The same DCD pairs as a method built without the cache, at a posed sample.
  MethodOptions plain;
  plain.features = options.features;
  const auto alone = make_method("bvh", mesh, fox.topology, plain);
  const skinning::Positions x = fox.sample(3);
  FrameResult expected;
  alone->detect_dcd(x, expected);
  for (const auto& m : methods) {
    FrameResult got;
    m->detect_dcd(x, got);
    EXPECT_EQ(got.dcd_pairs, expected.dcd_pairs);
    EXPECT_EQ(got.counters.bv_tests, expected.counters.bv_tests);
  }
}

/// The triangle pairs whose boxes meet at the welded positions `x` through `tree` refit there,
/// and the volume tests it took.
std::pair<std::vector<TrianglePair>, std::int64_t> pairs_at(
    Bvh<3>& tree, const FeatureTopology& topology, const skinning::Positions& x) {
  FeatureBounds<3> bounds;
  bounds.static_triangles(topology, x);
  tree.refit(bounds.triangles);
  TraversalScratch scratch;
  scratch.reserve_self(tree);
  std::vector<TrianglePair> pairs;
  std::int64_t bv_tests = 0;
  self_traverse<3>(tree, bounds.triangles, scratch, pairs, bv_tests);
  return {pairs, bv_tests};
}

TEST(HierarchyCache, AHandOverCacheLendsItsOneTreeToTheNextCallerOnceTheLastLetGo) {
  // A serial check: the baseline's `bvh` lends the tree, refits it at its pose and lets go; the
  // runner's method is lent that very object, and its queries see what a fresh build gives.
  const test::WeldedCharacter fox("Fox.glb");
  const FeatureTopology topology(*fox.loaded.mesh, fox.topology);
  const auto& triangles = fox.topology.welded_triangles;
  const BvhOptions options{.leaf_size = 1, .node_volumes = false};
  Bvh<3> own(triangles, fox.rest, options);
  HierarchyCache cache(HierarchyCache::Sharing::hand_over);

  auto first = cache.lend<3>(triangles, fox.rest, options);
  EXPECT_EQ(cache.builds(), 1u);
  expect_same_tree(*first, own);
  // Held still: the next caller builds its own, which the cache does not keep.
  {
    const auto second = cache.lend<3>(triangles, fox.rest, options);
    EXPECT_NE(second.get(), first.get());
    expect_same_tree(*second, own);
    EXPECT_EQ(cache.builds(), 1u);
    EXPECT_EQ(cache.reuses(), 0u);
  }
  // get() on a hand-over cache: the caller's own build, nothing kept or shared.
  expect_same_tree(cache.get<3>(triangles, fox.rest, nullptr, options), own);
  EXPECT_EQ(cache.builds(), 1u);

  // Refit at one pose and let go: the next caller gets that object, and refit at another pose
  // it finds what a fresh tree finds there, with the same volume tests.
  (void)pairs_at(*first, topology, fox.sample(3));
  const Bvh<3>* const lent = first.get();
  first.reset();
  auto next = cache.lend<3>(triangles, fox.rest, options);
  EXPECT_EQ(next.get(), lent);
  EXPECT_EQ(cache.reuses(), 1u);
  const auto [pairs, tests] = pairs_at(*next, topology, fox.sample(11));
  const auto [fresh_pairs, fresh_tests] = pairs_at(own, topology, fox.sample(11));
  EXPECT_EQ(pairs, fresh_pairs);
  EXPECT_EQ(tests, fresh_tests);
  EXPECT_GT(pairs.size(), static_cast<std::size_t>(triangles.rows()));  // not a trivial walk
  next.reset();

  // A caller of other inputs frees the tree no one holds: one tree at a time.
  skinning::Positions moved = fox.rest;
  moved(7, 1) = std::nextafter(moved(7, 1), 1e300);
  const std::weak_ptr<Bvh<3>> held = cache.lend<3>(triangles, fox.rest, options);
  EXPECT_EQ(cache.reuses(), 2u);
  EXPECT_FALSE(held.expired());  // the cache's
  expect_same_tree(*cache.lend<3>(triangles, moved, options), Bvh<3>(triangles, moved, options));
  EXPECT_TRUE(held.expired());
  EXPECT_EQ(cache.builds(), 2u);

  // The last caller next: what it builds is not kept; the tree held is still lent.
  cache.keep_no_more();
  const std::weak_ptr<Bvh<8>> other = cache.lend<8>(triangles, fox.rest, options);
  EXPECT_TRUE(other.expired());
  EXPECT_EQ(cache.builds(), 2u);
  EXPECT_EQ(cache.reuses(), 2u);  // the 16-DOP tree freed the moved one: nothing left to lend
  (void)cache.lend<3>(triangles, moved, options);
  EXPECT_EQ(cache.builds(), 2u);
  EXPECT_EQ(cache.reuses(), 2u);

  // Objects are not shared: each caller builds its own.
  int built = 0;
  const auto build = [&] {
    ++built;
    return std::make_shared<const int>(built);
  };
  EXPECT_NE(cache.shared<int>("key", build), cache.shared<int>("key", build));
  EXPECT_EQ(built, 2);
}

TEST(HierarchyCache, AHandOverCacheKeepsNothingOnceClosed) {
  const test::WeldedCharacter fox("Fox.glb");
  const auto& triangles = fox.topology.welded_triangles;
  const BvhOptions options{.leaf_size = 1, .node_volumes = false};
  HierarchyCache cache(HierarchyCache::Sharing::hand_over);
  const std::weak_ptr<Bvh<3>> kept = cache.lend<3>(triangles, fox.rest, options);
  EXPECT_FALSE(kept.expired());
  cache.close();
  EXPECT_TRUE(kept.expired());
  const std::weak_ptr<Bvh<3>> after = cache.lend<3>(triangles, fox.rest, options);
  EXPECT_TRUE(after.expired());
  EXPECT_EQ(cache.builds(), 1u);
  EXPECT_EQ(cache.reuses(), 0u);
}

}  // namespace
}  // namespace skelcd::culling
