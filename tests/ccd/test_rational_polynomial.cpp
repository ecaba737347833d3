// The exact polynomial machinery under the rational CCD reference: gcd, square-free part, root
// isolation on [0,1], signs at algebraic roots — checked against hand-computed answers.

#include "ccd/detail/rational_polynomial.hpp"

#include <gtest/gtest.h>

namespace skelcd::ccd::detail {
namespace {

RationalPolynomial poly(std::initializer_list<mpq_class> c) { return RationalPolynomial(std::vector<mpq_class>(c)); }

TEST(RationalPolynomial, ArithmeticAndTrim) {
  const auto p = poly({1, 2, 3});  // 1 + 2t + 3t^2
  const auto q = poly({-1, 0, -3});
  EXPECT_EQ((p + q).degree(), 1);
  EXPECT_EQ((p + q)(mpq_class(5)), 10);
  EXPECT_TRUE((p - p).is_zero());
  EXPECT_EQ((p * q).degree(), 4);
  EXPECT_EQ((p * q)(mpq_class(1, 2)), p(mpq_class(1, 2)) * q(mpq_class(1, 2)));
  EXPECT_EQ(p.derivative()(mpq_class(1)), 8);
}

TEST(RationalPolynomial, GcdAndSquareFree) {
  // (t - 1/3)^2 (t - 1/2) and (t - 1/3)(t - 2): gcd t - 1/3.
  const auto a = poly({mpq_class(-1, 3), 1}) * poly({mpq_class(-1, 3), 1}) * poly({mpq_class(-1, 2), 1});
  const auto b = poly({mpq_class(-1, 3), 1}) * poly({-2, 1});
  const auto g = gcd(a, b);
  ASSERT_EQ(g.degree(), 1);
  EXPECT_EQ(g(mpq_class(1, 3)), 0);
  const auto s = square_free(a);
  EXPECT_EQ(s.degree(), 2);
  EXPECT_EQ(s(mpq_class(1, 3)), 0);
  EXPECT_EQ(s(mpq_class(1, 2)), 0);
  EXPECT_TRUE(gcd(RationalPolynomial{}, RationalPolynomial{}).is_zero());
}

TEST(RationalPolynomial, IsolatesRationalAndIrrationalRootsInOrder) {
  // t (t - 1)(2t^2 - 1)(t - 3/4): roots 0, 1/sqrt2, 3/4, 1 in [0,1]; -1/sqrt2 outside.
  const auto f = poly({0, 1}) * poly({-1, 1}) * poly({-1, 0, 2}) * poly({mpq_class(-3, 4), 1});
  const auto roots = isolate_roots_in_unit_interval(square_free(f));
  ASSERT_EQ(roots.size(), 4u);
  EXPECT_TRUE(roots[0].rational);
  EXPECT_EQ(roots[0].lo, 0);
  EXPECT_FALSE(roots[1].rational);
  EXPECT_LT(roots[1].lo * roots[1].lo * 2, 1);  // lo < 1/sqrt2 < hi
  EXPECT_GT(roots[1].hi * roots[1].hi * 2, 1);
  EXPECT_LE(roots[1].hi, mpq_class(3, 4));
  EXPECT_TRUE(roots[2].lo == mpq_class(3, 4) || (roots[2].lo < mpq_class(3, 4) && mpq_class(3, 4) < roots[2].hi));
  EXPECT_TRUE(roots[3].rational);
  EXPECT_EQ(roots[3].lo, 1);
}

TEST(RationalPolynomial, NoRootsOutsideTheInterval) {
  EXPECT_TRUE(isolate_roots_in_unit_interval(poly({1, 0, 1})).empty());       // t^2 + 1
  EXPECT_TRUE(isolate_roots_in_unit_interval(poly({-2, 1})).empty());         // t - 2
  EXPECT_TRUE(isolate_roots_in_unit_interval(poly({mpq_class(1, 7)})).empty());  // constant
}

TEST(RationalPolynomial, SignAtAnAlgebraicRoot) {
  const auto f = poly({-1, 0, 2});  // root 1/sqrt2 ~ 0.70710678
  const auto roots = isolate_roots_in_unit_interval(f);
  ASSERT_EQ(roots.size(), 1u);
  RootPoint r(f, roots[0]);
  EXPECT_EQ(r.sign(poly({mpq_class(-7071, 10000), 1})), 1);   // t - 0.7071 > 0
  EXPECT_EQ(r.sign(poly({mpq_class(-7072, 10000), 1})), -1);  // t - 0.7072 < 0
  EXPECT_EQ(r.sign(poly({-1, 0, 2}) * poly({5, 1})), 0);       // a multiple of f vanishes
  EXPECT_EQ(r.sign(poly({1, 0, -4})), -1);                     // 1 - 4t^2 = -1 at the root
  EXPECT_EQ(r.sign(RationalPolynomial{}), 0);
  r.refine(mpq_class(1, 1'000'000'000));
  EXPECT_LE(r.hi() - r.lo(), mpq_class(1, 1'000'000'000));
  EXPECT_LT(r.lo() * r.lo() * 2, 1);
  EXPECT_GT(r.hi() * r.hi() * 2, 1);
}

TEST(RationalPolynomial, SignAtARationalPoint) {
  RootPoint r(mpq_class(1, 3));
  EXPECT_EQ(r.sign(poly({-1, 3})), 0);
  EXPECT_EQ(r.sign(poly({-1, 4})), 1);
  EXPECT_EQ(r.sign(poly({1, -4})), -1);
}

}  // namespace
}  // namespace skelcd::ccd::detail
