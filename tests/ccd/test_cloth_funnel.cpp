// The cloth-funnel step (real simulation queries with published ground truth, assets/cloth-funnel):
// exact equals the truth, conservative misses none of it.

#include <iostream>

#include <gtest/gtest.h>

#include "tests/ccd/cloth_funnel.hpp"

namespace skelcd::ccd {
namespace {

class ClothFunnel : public ::testing::TestWithParam<const char*> {};

TEST_P(ClothFunnel, ExactEqualsTheGroundTruth) {
  const auto queries = test::load_cloth_funnel(GetParam());
  ASSERT_EQ(queries.size(), std::string(GetParam()) == "vf" ? 92u : 263u);
  int hits = 0;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const auto& q = queries[i];
    const bool hit = q.vertex_face ? vertex_face_ccd_rational(q.rational_vf()).hit
                                   : edge_edge_ccd_rational(q.rational_ee()).hit;
    EXPECT_EQ(hit, q.truth) << GetParam() << " query " << i;
    hits += hit ? 1 : 0;
  }
  EXPECT_EQ(hits, std::string(GetParam()) == "vf" ? 27 : 107);
}

TEST_P(ClothFunnel, ConservativeHasNoFalseNegative) {
  const auto queries = test::load_cloth_funnel(GetParam());
  int false_positives = 0;
  int misses = 0;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const auto& q = queries[i];
    // The values are dyadic rationals: the doubles are exact.
    const auto r = q.vertex_face ? vertex_face_ccd(q.vf()) : edge_edge_ccd(q.ee());
    EXPECT_TRUE(r.hit || !q.truth) << GetParam() << " query " << i;
    if (!q.truth) {
      ++misses;
      false_positives += r.hit ? 1 : 0;
    }
  }
  std::cout << "  cloth-funnel " << GetParam() << ": conservative false positives " << false_positives << " of "
            << misses << " misses\n";
}

INSTANTIATE_TEST_SUITE_P(Step227, ClothFunnel, ::testing::Values("vf", "ee"));

TEST(ClothFunnelFile, ConvertsToTheQueryFormat) {
  const auto text = test::to_query_file(test::load_cloth_funnel("vf"));
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 93);  // comment + 92 queries
  EXPECT_NE(text.find("vf 3589935/67108864 0 -10177395/16777216"), std::string::npos);
}

}  // namespace
}  // namespace skelcd::ccd
