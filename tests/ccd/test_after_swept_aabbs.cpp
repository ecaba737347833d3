// The after-AABB entries of the CCD queries (ccd/after_swept_aabbs.hpp): on every query whose swept
// boxes overlap they answer exactly what vertex_face_ccd / edge_edge_ccd answer, bit for bit; with
// a distance or another accuracy they are the full queries; and on a query outside their
// precondition they still never miss a contact.

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "ccd/after_swept_aabbs.hpp"
#include "ccd/exact_ccd.hpp"
#include "ccd/filters.hpp"
#include "tests/ccd/hard_cases.hpp"
#include "tests/ccd/random_queries.hpp"

namespace skelcd::ccd {
namespace {

::testing::AssertionResult same(const CcdResult& a, const CcdResult& b) {
  if (a.hit == b.hit && a.status == b.status &&
      std::bit_cast<std::uint64_t>(a.toi_lower) == std::bit_cast<std::uint64_t>(b.toi_lower) &&
      std::bit_cast<std::uint64_t>(a.toi_upper) == std::bit_cast<std::uint64_t>(b.toi_upper)) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure()
         << "hit " << a.hit << " vs " << b.hit << ", toi [" << a.toi_lower << ", " << a.toi_upper
         << "] vs [" << b.toi_lower << ", " << b.toi_upper << "]";
}

struct Checked {
  int overlapping = 0;  // queries inside the precondition
  int hits = 0;
};

// Each query with each option set: after == full whenever the swept boxes overlap or the entry
// falls back to the full query.
template <typename Query>
void check(const Query& q, const std::vector<CcdOptions>& options_list, Checked& checked) {
  const bool overlapping = !swept_aabbs_disjoint(q, 0.0);
  for (const CcdOptions& options : options_list) {
    const bool falls_back = options.min_separation != 0.0;
    if (!overlapping && !falls_back) continue;
    CcdResult full, after;
    if constexpr (std::is_same_v<Query, VertexFaceQuery>) {
      full = vertex_face_ccd(q, Accuracy::conservative, options);
      after = vertex_face_ccd_after_swept_aabbs(q, Accuracy::conservative, options);
    } else {
      full = edge_edge_ccd(q, Accuracy::conservative, options);
      after = edge_edge_ccd_after_swept_aabbs(q, Accuracy::conservative, options);
    }
    ASSERT_TRUE(same(after, full));
    checked.overlapping += overlapping;
    checked.hits += full.hit;
  }
}

const std::vector<CcdOptions>& option_sets() {
  static const std::vector<CcdOptions> sets = {
      CcdOptions{},
      CcdOptions{.toi_tolerance = 1e-3},
      CcdOptions{.relative_distance_tolerance = 1e-6},
      CcdOptions{.min_separation = 1e-3},
  };
  return sets;
}

TEST(AfterSweptAabbs, SameAnswerAsTheFullQueryOnRandomQueries) {
  test::RandomQueryGenerator generator(41);
  Checked checked;
  for (int n = 0; n < 5000; ++n) {
    const test::RandomQuery q = generator.next();
    if (q.vertex_face) {
      check(q.vf(), option_sets(), checked);
    } else {
      check(q.ee(), option_sets(), checked);
    }
    if (HasFatalFailure()) return;
  }
  // The mix reaches the later stages and finds contacts, or the equality proves little.
  EXPECT_GT(checked.overlapping, 15000);
  EXPECT_GT(checked.hits, 5000);
}

TEST(AfterSweptAabbs, SameAnswerAsTheFullQueryOnTheHardCases) {
  Checked checked;
  for (const test::HardCase& c : test::hard_cases(7, 4)) {
    if (c.vertex_face) {
      check(c.vf(), option_sets(), checked);
    } else {
      check(c.ee(), option_sets(), checked);
    }
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(checked.hits, 2000);
}

TEST(AfterSweptAabbs, OtherAccuraciesAreTheFullQuery) {
  test::RandomQueryGenerator generator(43);
  for (int n = 0; n < 300; ++n) {
    const test::RandomQuery q = generator.next();
    for (const Accuracy accuracy : {Accuracy::exact, Accuracy::fast}) {
      if (q.vertex_face) {
        ASSERT_TRUE(same(
            vertex_face_ccd_after_swept_aabbs(q.vf(), accuracy, {}),
            vertex_face_ccd(q.vf(), accuracy, {})));
      } else {
        ASSERT_TRUE(same(
            edge_edge_ccd_after_swept_aabbs(q.ee(), accuracy, {}),
            edge_edge_ccd(q.ee(), accuracy, {})));
      }
    }
  }
}

TEST(AfterSweptAabbs, OnAnyQueryNoContactIsMissed) {
  // The conservative guarantee, whether the query meets the precondition or not (skipping a stage
  // that only rejects cannot lose a contact): every exact contact is a hit.
  test::RandomQueryGenerator generator(47);
  int contacts = 0;
  for (int n = 0; n < 2000; ++n) {
    const test::RandomQuery q = generator.next();
    const bool hit = q.vertex_face
                         ? vertex_face_ccd_after_swept_aabbs(q.vf(), Accuracy::conservative, {}).hit
                         : edge_edge_ccd_after_swept_aabbs(q.ee(), Accuracy::conservative, {}).hit;
    const bool exact = q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::exact, {}).hit
                                     : edge_edge_ccd(q.ee(), Accuracy::exact, {}).hit;
    EXPECT_TRUE(hit || !exact) << n << " " << q.kind;
    contacts += exact;
  }
  EXPECT_GT(contacts, 100);
}

}  // namespace
}  // namespace skelcd::ccd
