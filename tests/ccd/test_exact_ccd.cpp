// The exact rational reference against answers known by construction (tests/ccd/hard_cases.hpp)
// and a few inputs that are not doubles.

#include "ccd/exact_ccd.hpp"

#include <map>

#include <gtest/gtest.h>

#include "tests/ccd/hard_cases.hpp"

namespace skelcd::ccd {
namespace {

ExactCcdResult exact(const test::HardCase& c, const mpq_class& width = mpq_class(1, 1'000'000)) {
  return c.vertex_face ? vertex_face_ccd_rational(to_rational(c.vf()), width)
                       : edge_edge_ccd_rational(to_rational(c.ee()), width);
}

TEST(ExactCcd, AgreesWithEveryAnalyticAnswer) {
  const auto cases = test::hard_cases(7, 2);
  int checked = 0;
  int with_time = 0;
  std::map<std::string, int> per_family;
  for (const auto& c : cases) {
    if (!c.analytic_hit) continue;
    const auto r = exact(c);
    ASSERT_EQ(r.hit, *c.analytic_hit) << c.family << " / " << c.variant;
    ++checked;
    ++per_family[c.family];
    if (r.hit && c.analytic_toi) {
      EXPECT_LE(r.toi_lo, *c.analytic_toi) << c.family << " / " << c.variant;
      EXPECT_GE(r.toi_hi, *c.analytic_toi) << c.family << " / " << c.variant;
      EXPECT_LE(r.toi_hi - r.toi_lo, mpq_class(1, 1'000'000));
      ++with_time;
    }
  }
  // Every family keeps analytic answers under at least the exact transforms.
  EXPECT_EQ(per_family.size(), 17u);
  EXPECT_GT(checked, 1000);
  EXPECT_GT(with_time, 300);
}

TEST(ExactCcd, RationalTimeIsFoundExactly) {
  // Vertex falls from z = 1 to z = -2 through the face: contact at exactly t = 1/3.
  test::HardCase c;
  c.vertex_face = true;
  using V = Eigen::Vector3d;
  c.points = {V(0.25, 0.25, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.25, 0.25, -2), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  const auto r = exact(c);
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.toi_lo, mpq_class(1, 3));
  EXPECT_EQ(r.toi_hi, mpq_class(1, 3));
  const auto d = vertex_face_ccd_exact(to_rational(c.vf()));
  EXPECT_TRUE(d.hit);
  EXPECT_LE(d.toi_lower, 1.0 / 3.0);
  EXPECT_GE(d.toi_upper, 1.0 / 3.0);
  EXPECT_LT(d.toi_upper - d.toi_lower, 1e-15);
}

TEST(ExactCcd, IrrationalTimeIsBracketed) {
  // Triangle (0,0,0), (1,0,0), (0,1,2t) has the plane z = 2t y; the vertex (x, t, 1) is in it when
  // 2t^2 = 1, at t* = 1/sqrt(2). There the triangle projects onto x + y <= 1, so x = 1/4 is inside
  // (1/4 + 1/sqrt2 < 1) and x = 3/10 is outside (3/10 + 1/sqrt2 > 1).
  RationalVertexFaceQuery q{{mpq_class(1, 4), 0, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                            {mpq_class(1, 4), 1, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 2}};
  const auto r = vertex_face_ccd_rational(q, mpq_class(1, 1 << 30));
  ASSERT_TRUE(r.hit);
  EXPECT_LT(r.toi_lo * r.toi_lo * 2, 1);
  EXPECT_GT(r.toi_hi * r.toi_hi * 2, 1);
  EXPECT_LE(r.toi_hi - r.toi_lo, mpq_class(1, 1 << 30));
  q.v_t0[0] = q.v_t1[0] = mpq_class(3, 10);
  EXPECT_FALSE(vertex_face_ccd_rational(q).hit);
}

TEST(ExactCcd, DecimalInputsThatAreNotDoubles) {
  // Vertex at x = 1/10 exactly against a triangle edge at x = 1/10: the double 0.1 would be a
  // different number, the rational one touches.
  const mpq_class tenth(1, 10);
  RationalVertexFaceQuery q{{tenth, 0, 1},  {tenth, -1, 0}, {tenth, 1, 0}, {1, 0, 0},
                            {tenth, 0, -1}, {tenth, -1, 0}, {tenth, 1, 0}, {1, 0, 0}};
  const auto r = vertex_face_ccd_rational(q);
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.toi_lo, mpq_class(1, 2));
  // Moved by 1/10^30 to the outside: a miss no double could express.
  q.v_t0[0] = tenth - mpq_class(1) / mpq_class("1000000000000000000000000000000");
  q.v_t1[0] = q.v_t0[0];
  EXPECT_FALSE(vertex_face_ccd_rational(q).hit);
}

TEST(ExactCcd, DirectedRounding) {
  const mpq_class third(1, 3);
  EXPECT_LT(mpq_class(round_down(third)), third);
  EXPECT_GT(mpq_class(round_up(third)), third);
  EXPECT_EQ(std::nextafter(round_down(third), 1.0), round_up(third));
  EXPECT_EQ(round_down(mpq_class(1, 4)), 0.25);
  EXPECT_EQ(round_up(mpq_class(1, 4)), 0.25);
  EXPECT_EQ(round_to_nearest(third), 1.0 / 3.0);
  EXPECT_EQ(round_to_nearest(mpq_class(1, 10)), 0.1);
  EXPECT_EQ(round_to_nearest(mpq_class(-7, 10)), -0.7);
  // Ties to even: 1 + 2^-53 is halfway between 1 and 1 + 2^-52.
  const mpq_class tie = mpq_class(1) + mpq_class(1) / mpq_class(mpz_class(1) << 53);
  EXPECT_EQ(round_to_nearest(tie), 1.0);
  EXPECT_TRUE(std::isinf(round_to_nearest(mpq_class(mpz_class(1) << 1100))));
}

}  // namespace
}  // namespace skelcd::ccd
