// ccd::triangles_intersect (and triangles_intersect_with_planes) against the implementation it
// replaced (tests/ccd/triangle_triangle_reference.cpp) on real DCD queries: every pair `bvh`'s
// DCD hands to its triangle test on posed frames of the bundled characters and the cloth-funnel
// step — each pair as recorded (with the corners the two share) and with its triangles swapped;
// where the recorded map names a corner of b twice (a triangle whose welded corners repeat a
// vertex: the old code read that as a shared edge and could be wrong), against the brute force
// (tests/ccd/triangle_triangle_brute.cpp) instead, counting the answers that changed. The
// cloth-ball step lives outside the repository: bench/ccd/bm_triangle_triangle checks it (and exits
// 1 on a difference) where ../shared/assets holds it. The synthetic cases are in tests/ccd/
// test_triangle_triangle_equivalence.cpp.

#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <string>

#include "ccd/triangle_triangle.hpp"
#include "tests/ccd/triangle_triangle_brute.hpp"
#include "tests/ccd/triangle_triangle_reference.hpp"
#include "tests/culling/real_triangle_queries.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using ccd::reference::triangles_intersect_reference;

struct RealSet {
  const char* name;
  std::filesystem::path path;
  int samples;
};

void expect_same_answers(const RealSet& set) {
  const auto recorded = test::record_dcd_queries(set.path, set.samples);
  ASSERT_GT(recorded.queries.size(), 1000u) << set.name;
  std::int64_t hits = 0, unsettled = 0, disagreements = 0;
  std::int64_t repeated = 0, repeated_tested = 0, repeated_changed = 0;
  for (std::size_t i = 0; i < recorded.queries.size(); ++i) {
    const auto& r = recorded.queries[i];
    const ccd::TriangleTriangleQuery& q = r.query;
    const ccd::TriangleTriangleQuery swapped{q.b0, q.b1, q.b2, q.a0, q.a1, q.a2};
    ccd::SharedCorners inverse = ccd::kNoSharedCorners;
    for (std::size_t k = 0; k < 3; ++k) {
      if (r.shared[k] >= 0)
        inverse[static_cast<std::size_t>(r.shared[k])] = static_cast<std::int8_t>(k);
    }
    const auto& s = r.shared;
    const bool repeats =
        (s[0] >= 0 && (s[0] == s[1] || s[0] == s[2])) || (s[1] >= 0 && s[1] == s[2]);
    bool expected, expected_swapped;
    if (repeats) {
      expected = expected_swapped = ccd::test::brute_intersect(q, r.shared);
      ++repeated;
      repeated_tested += r.fan_settled ? 0 : 1;
      repeated_changed += triangles_intersect_reference(q, r.shared) != expected ? 1 : 0;
    } else {
      expected = triangles_intersect_reference(q, r.shared);
      expected_swapped = triangles_intersect_reference(swapped, inverse);
    }
    // Also the entry the traversing methods' DCD calls, with planes computed once per instant.
    const auto plane_a = ccd::triangle_plane(q.a0, q.a1, q.a2);
    const auto plane_b = ccd::triangle_plane(q.b0, q.b1, q.b2);
    const bool same =
        ccd::triangles_intersect(q, r.shared) == expected &&
        ccd::triangles_intersect_with_planes(q, r.shared, plane_a, plane_b) == expected &&
        ccd::triangles_intersect(swapped, inverse) == expected_swapped &&
        ccd::triangles_intersect_with_planes(swapped, inverse, plane_b, plane_a) ==
            expected_swapped;
    if (!same && ++disagreements <= 5) ADD_FAILURE() << set.name << ": query " << i << " differs";
    hits += expected ? 1 : 0;
    unsettled += r.fan_settled ? 0 : 1;
  }
  EXPECT_EQ(disagreements, 0) << set.name;
  // The recorder saw what the DCD tests: its unsettled pairs are the DCD's tests, its hits (each
  // pair once per sample) the DCD's pairs.
  EXPECT_EQ(unsettled, recorded.production_tests) << set.name;
  EXPECT_EQ(hits, recorded.intersecting_pairs) << set.name;
  std::cout << "  " << set.name << ": " << recorded.queries.size() << " queries ("
            << recorded.production_tests << " tested by the DCD), " << hits << " intersecting; "
            << repeated << " name a corner twice (" << repeated_tested << " tested), "
            << repeated_changed << " answered otherwise by the old code\n";
}

TEST(TriangleTriangleReal, RobotExpressive) {
  expect_same_answers(
      {"RobotExpressive", skelcd::test::asset("characters/RobotExpressive.glb"), 4});
}

TEST(TriangleTriangleReal, CesiumMan) {
  expect_same_answers({"CesiumMan", skelcd::test::asset("characters/CesiumMan.glb"), 4});
}

TEST(TriangleTriangleReal, Stormtrooper) {
  expect_same_answers(
      {"stormtrooper", skelcd::test::asset("characters/stormtrooper/stormtrooper.dae"), 4});
}

TEST(TriangleTriangleReal, ClothFunnelStep) {
  expect_same_answers({"cloth-funnel", skelcd::test::asset("cloth-funnel/frames"), 2});
}

}  // namespace
}  // namespace skelcd::culling
