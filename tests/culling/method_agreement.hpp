#pragma once
// Shared checks of the tests that run brute, bvh and kdop side by side (test_characters.cpp,
// test_generated_rigs.cpp).

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "culling/method.hpp"

namespace skelcd::culling::agreement {

/// True when every contact of `a` names a feature pair that `b` also reports.
inline bool same_pairs_subset(const std::vector<CcdContact>& a, const std::vector<CcdContact>& b) {
  return std::all_of(a.begin(), a.end(), [&](const CcdContact& c) {
    return std::any_of(b.begin(), b.end(), [&](const CcdContact& d) { return c.same_pair(d); });
  });
}

/// DCD at `x` by the three methods: bvh and kdop must report brute's intersecting pairs, and bvh
/// must run brute's triangle tests. Returns brute's result.
inline FrameResult expect_same_dcd(
    CullingMethod& brute,
    CullingMethod& bvh,
    CullingMethod& kdop,
    const skinning::Positions& x,
    const std::string& what) {
  FrameResult db, dv, dk;
  brute.detect_dcd(x, db);
  bvh.detect_dcd(x, dv);
  kdop.detect_dcd(x, dk);
  EXPECT_EQ(dv.dcd_pairs, db.dcd_pairs) << what;
  EXPECT_EQ(dk.dcd_pairs, db.dcd_pairs) << what;
  EXPECT_EQ(dv.counters.tt_tests, db.counters.tt_tests) << what;
  return db;
}

}  // namespace skelcd::culling::agreement
