// Sign of a cubic on [0,1] and the moving-orientation cubic: every certain answer is checked with
// exact rationals, and every stated error bound is checked against the exact coefficients, on
// inputs chosen to hurt (cancellation after a 1e6 translation, 1e-6 / 1e6 scales, roots near and
// at the interval ends, underflow).

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/rational_polynomial.hpp"
#include "ccd/detail/trilinear_cubic.hpp"
#include "ccd/filters.hpp"
#include "ccd/polynomial_sign.hpp"

namespace skelcd::ccd {
namespace {

using detail::RationalPolynomial;
using V = Eigen::Vector3d;

// Exact sign of f on [0,1]: +1 / -1 when f has no root there, 0 otherwise.
int exact_sign_on_unit(const RationalPolynomial& f) {
  if (f.is_zero()) return 0;
  if (!detail::isolate_roots_in_unit_interval(detail::square_free(f)).empty()) return 0;
  return f.sign_at(mpq_class(1, 2));
}

RationalPolynomial power(const std::array<double, 4>& c) {
  return RationalPolynomial({mpq_class(c[0]), mpq_class(c[1]), mpq_class(c[2]), mpq_class(c[3])});
}

// Exact Bernstein coefficients of an exact cubic.
std::array<mpq_class, 4> bernstein(const RationalPolynomial& f) {
  std::array<mpq_class, 4> c{0, 0, 0, 0};
  for (std::size_t i = 0; i < f.coefficients().size(); ++i) c[i] = f.coefficients()[i];
  return {c[0], c[0] + c[1] / 3, c[0] + (2 * c[1] + c[2]) / 3, c[0] + c[1] + c[2] + c[3]};
}

::testing::AssertionResult within(const std::array<double, 4>& b, double error, const std::array<mpq_class, 4>& exact) {
  for (std::size_t i = 0; i < 4; ++i) {
    const mpq_class diff = abs(mpq_class(b[i]) - exact[i]);
    if (diff > mpq_class(error)) {
      return ::testing::AssertionFailure() << "coefficient " << i << " off by " << diff.get_d() << " > bound " << error;
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(CubicSign, CertainAnswersAreRight) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int certain = 0;
  int clearly_signed = 0;
  int clearly_signed_certain = 0;
  for (int n = 0; n < 20000; ++n) {
    std::array<double, 4> c{u(rng), u(rng), u(rng), u(rng)};
    if (n % 4 == 1) c[0] = -(c[1] + c[2] + c[3]);          // root exactly at t = 1 (up to rounding)
    if (n % 4 == 2) c[0] = std::ldexp(c[0], -50);          // root right next to t = 0
    if (n % 4 == 3) c[0] = -(c[1] / 2 + c[2] / 4 + c[3] / 8);  // root at t = 1/2 (up to rounding)
    const double scale = std::ldexp(1.0, static_cast<int>(n % 61) - 30);
    for (auto& x : c) x *= scale;
    const PowerCubic f{c, 0.0};
    const PolynomialSign s = cubic_sign(f);
    const int truth = exact_sign_on_unit(power(c));
    if (s != PolynomialSign::uncertain) {
      ++certain;
      ASSERT_EQ(static_cast<int>(s), truth) << "case " << n;
    }
    if (n % 4 == 0 && truth != 0) {
      // Away from roots the classifier should usually decide.
      const auto bc = bernstein(power(c));
      const mpq_class m = std::min({abs(bc[0]), abs(bc[3])});
      if (m > mpq_class(std::abs(c[0]) + std::abs(c[3])) / 8) {
        ++clearly_signed;
        clearly_signed_certain += s != PolynomialSign::uncertain ? 1 : 0;
      }
    }
  }
  EXPECT_GT(certain, 3000);
  EXPECT_GT(clearly_signed_certain, clearly_signed * 9 / 10);
}

TEST(CubicSign, ExactlyZeroOrNonFiniteIsUncertain) {
  EXPECT_EQ(cubic_sign(PowerCubic{{0, 0, 0, 0}, 0}), PolynomialSign::uncertain);
  EXPECT_EQ(cubic_sign(PowerCubic{{1, std::numeric_limits<double>::quiet_NaN(), 0, 0}, 0}), PolynomialSign::uncertain);
  EXPECT_EQ(cubic_sign(BernsteinCubic{{1, 1, 1, std::numeric_limits<double>::infinity()}, 0}), PolynomialSign::uncertain);
  EXPECT_EQ(cubic_sign(PowerCubic{{1, 0, 0, 0}, 0}), PolynomialSign::positive);
  EXPECT_EQ(cubic_sign(PowerCubic{{-1, 0, 0, 0}, 0.2}), PolynomialSign::negative);  // bound x4: 0.8
  EXPECT_EQ(cubic_sign(PowerCubic{{-1, 0, 0, 0}, 1.0}), PolynomialSign::uncertain);
}

TEST(CubicSign, SubdivisionDecidesWhatTheHullCannot) {
  // f(t) = (t - 1/2)^2 + 1/100 > 0, but its Bernstein coefficients are not all positive.
  const PowerCubic f{{0.26, -1.0, 1.0, 0.0}, 0.0};
  EXPECT_EQ(cubic_sign(f, 0), PolynomialSign::uncertain);
  EXPECT_EQ(cubic_sign(f, 4), PolynomialSign::positive);
}

TEST(CubicSign, ConversionsCarryTheirErrorBounds) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int n = 0; n < 5000; ++n) {
    const double scale = std::ldexp(1.0, static_cast<int>(n % 41) - 20);
    const std::array<double, 4> c{u(rng) * scale, u(rng) * scale, u(rng) * scale, u(rng) * scale};
    const auto exact = power(c);
    // power -> Bernstein
    const BernsteinCubic b = to_bernstein(PowerCubic{c, 0.0});
    ASSERT_TRUE(within(b.coefficients, b.error, bernstein(exact))) << n;
    // Bernstein -> power, against the exact power form of the rounded Bernstein coefficients.
    const PowerCubic back = to_power(BernsteinCubic{b.coefficients, 0.0});
    const auto& bb = b.coefficients;
    const mpq_class b0(bb[0]), b1(bb[1]), b2(bb[2]), b3(bb[3]);
    const std::array<mpq_class, 4> exact_power{b0, 3 * (b1 - b0), 3 * (b0 - 2 * b1 + b2), b3 - 3 * b2 + 3 * b1 - b0};
    ASSERT_TRUE(within(back.coefficients, back.error, exact_power)) << n;
    // Values at 0, 1/3, 2/3, 1 (rounded, with their error) -> Bernstein.
    std::array<double, 4> values;
    double value_error = 0;
    for (int i = 0; i < 4; ++i) {
      const mpq_class t(i, 3);
      const mpq_class v = exact(t);
      values[static_cast<std::size_t>(i)] = v.get_d();
      value_error = std::max(value_error, mpq_class(abs(mpq_class(values[static_cast<std::size_t>(i)]) - v)).get_d() * 2);
    }
    const BernsteinCubic from_values = bernstein_from_values(values, value_error);
    ASSERT_TRUE(within(from_values.coefficients, from_values.error, bernstein(exact))) << n;
  }
}

// Exact Bernstein coefficients of (a(t) - q(t)) . ((b(t) - a(t)) x (c(t) - a(t))).
std::array<mpq_class, 4> exact_orientation(const MovingOrientationQuery& q) {
  using detail::PolynomialVector;
  const auto moving = [](const V& p0, const V& p1) {
    PolynomialVector r;
    for (int k = 0; k < 3; ++k) {
      r[static_cast<std::size_t>(k)] = RationalPolynomial::linear(mpq_class(p0[k]), mpq_class(p1[k]) - mpq_class(p0[k]));
    }
    return r;
  };
  const auto a = moving(q.a_t0, q.a_t1), b = moving(q.b_t0, q.b_t1), c = moving(q.c_t0, q.c_t1),
             o = moving(q.q_t0, q.q_t1);
  return bernstein(detail::dot(a - o, detail::cross(b - a, c - a)));
}

TEST(MovingOrientationCubic, CoefficientsWithinTheStatedBound) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto point = [&] {
    const double x = u(rng), y = u(rng), z = u(rng);
    return V(x, y, z);
  };
  int positive = 0, negative = 0;
  for (int n = 0; n < 4000; ++n) {
    MovingOrientationQuery q{point(), point(), point(), point(), point(), point(), point(), point()};
    if (n % 3 == 1) {
      // The observer in the triangle's plane at both ends (coplanar up to rounding).
      q.q_t0 = q.a_t0 + 0.3 * (q.b_t0 - q.a_t0) + 0.2 * (q.c_t0 - q.a_t0);
      q.q_t1 = q.a_t1 + 0.6 * (q.b_t1 - q.a_t1) + 0.1 * (q.c_t1 - q.a_t1);
    }
    const double scale = (n % 5 == 0) ? 1e-6 : (n % 5 == 1) ? 1e6 : 1.0;
    const V shift = (n % 7 == 0) ? V(1e6, -1e6, 1e6) : V::Zero();
    for (V* p : {&q.a_t0, &q.b_t0, &q.c_t0, &q.q_t0, &q.a_t1, &q.b_t1, &q.c_t1, &q.q_t1}) *p = *p * scale + shift;
    const BernsteinCubic f = moving_orientation_cubic(q);
    ASSERT_TRUE(within(f.coefficients, f.error, exact_orientation(q))) << n;
    const PolynomialSign s = cubic_sign(f);
    if (s != PolynomialSign::uncertain) {
      const auto& e = exact_orientation(q);
      RationalPolynomial exact_power({e[0], 3 * (e[1] - e[0]), 3 * (e[0] - 2 * e[1] + e[2]), e[3] - 3 * e[2] + 3 * e[1] - e[0]});
      ASSERT_EQ(static_cast<int>(s), exact_sign_on_unit(exact_power)) << n;
      (s == PolynomialSign::positive ? positive : negative) += 1;
    }
    // |n(t)| <= the bound at a few exact times.
    const double bound = moving_normal_bound(q);
    for (const double t : {0.0, 0.25, 0.5, 1.0}) {
      const V b = (1 - t) * q.b_t0 + t * q.b_t1, a = (1 - t) * q.a_t0 + t * q.a_t1, c = (1 - t) * q.c_t0 + t * q.c_t1;
      ASSERT_LE((b - a).cross(c - a).norm(), bound * (1 + 1e-12)) << n;
    }
  }
  EXPECT_GT(positive, 250);
  EXPECT_GT(negative, 250);
}

TEST(MovingOrientationCubic, SignMeansFrontOrBack) {
  // Observer above the xy triangle (normal +z): f = (a - q) . n < 0 ("in front").
  const V a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), q(0.2, 0.2, 1);
  EXPECT_EQ(cubic_sign(moving_orientation_cubic({a, b, c, q, a, b, c, q})), PolynomialSign::negative);
  EXPECT_EQ(cubic_sign(moving_orientation_cubic({a, b, c, -q, a, b, c, -q})), PolynomialSign::positive);
  // Passing through the plane: uncertain.
  EXPECT_EQ(cubic_sign(moving_orientation_cubic({a, b, c, q, a, b, c, -q})), PolynomialSign::uncertain);
}

TEST(Filters, SweptAabbs) {
  const VertexFaceQuery q{V(0, 0, 2), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                          V(0, 0, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  EXPECT_TRUE(swept_aabbs_disjoint(q));
  EXPECT_TRUE(swept_aabbs_disjoint(q, 0.999));
  EXPECT_FALSE(swept_aabbs_disjoint(q, 1.0));  // exactly min_separation apart counts as touching
  const EdgeEdgeQuery e{V(0, 0, 0), V(1, 0, 0), V(2, 0, 0), V(3, 0, 0),
                        V(0, 0, 0), V(1, 0, 0), V(1, 0, 0), V(2, 0, 0)};
  EXPECT_FALSE(swept_aabbs_disjoint(e));
}

TEST(Filters, CoplanarityFilter) {
  // Gliding 1/2 above the face: never coplanar.
  const VertexFaceQuery glide{V(0.2, 0.2, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                              V(0.3, 0.2, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  EXPECT_TRUE(coplanarity_filter_rejects(glide));
  EXPECT_TRUE(coplanarity_filter_rejects(glide, 0.4));
  EXPECT_FALSE(coplanarity_filter_rejects(glide, 0.6));
  // Crossing the plane: not rejected.
  const VertexFaceQuery cross{V(2, 2, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                              V(2, 2, -0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  EXPECT_FALSE(coplanarity_filter_rejects(cross));
  // Skew edges that stay apart vertically; then crossing.
  const EdgeEdgeQuery ee{V(0, 0, 1), V(1, 0, 1), V(0.5, -1, 0), V(0.5, 1, 0),
                         V(0, 0, 0.5), V(1, 0, 0.5), V(0.5, -1, 0), V(0.5, 1, 0)};
  EXPECT_TRUE(coplanarity_filter_rejects(ee));
  EdgeEdgeQuery through = ee;
  through.ea0_t1.z() = through.ea1_t1.z() = -0.5;
  EXPECT_FALSE(coplanarity_filter_rejects(through));
}

// The reference: the product as the hardware computes it (a multiplication into the subnormal
// range, rounded to nearest even), which the bounds were written with.
template <int K>
void expect_subnormal_products_bit_for_bit(std::mt19937_64& rng) {
  volatile double tiny = detail::power_of_two(-K);  // volatile: multiplied at run time
  constexpr double kLimit = detail::power_of_two(K - 1022);
  constexpr double kUnits = detail::power_of_two(1074 - K);
  std::vector<double> ys = {
      0.0,
      1.0,
      1.5,
      2.0,
      3.0,
      kLimit,
      std::nextafter(kLimit, 0.0),
      std::nextafter(kLimit, 1e300),
      2 * kLimit,
      1e300,
      std::numeric_limits<double>::infinity()};
  // Products exactly halfway between two subnormals (ties: to even) and next to them.
  for (double n = 0; n < 64; ++n) {
    const double half = (n + 0.5) / kUnits;
    ys.insert(ys.end(), {half, std::nextafter(half, 0.0), std::nextafter(half, 1e300)});
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    ys.push_back(1.0 + std::ldexp(unit(rng), static_cast<int>(rng() % 60)));  // 1 + m: up to 2^60
  }
  for (const double y : ys) {
    const double expected = tiny * y;
    EXPECT_EQ(
        std::bit_cast<std::uint64_t>(detail::times_subnormal_power_of_two<K>(y)),
        std::bit_cast<std::uint64_t>(expected))
        << "K = " << K << ", y = " << y;
  }
  const double nan =
      detail::times_subnormal_power_of_two<K>(std::numeric_limits<double>::quiet_NaN());
  EXPECT_TRUE(std::isnan(nan));
}

TEST(FloatBounds, SubnormalProductsBitForBit) {
  std::mt19937_64 rng(17);
  expect_subnormal_products_bit_for_bit<1068>(rng);  // the algebraic filter's underflow term
  expect_subnormal_products_bit_for_bit<1070>(rng);  // the trilinear cubic's
  expect_subnormal_products_bit_for_bit<1023>(rng);
  expect_subnormal_products_bit_for_bit<1074>(rng);
}

// The trilinear cubic as first written: each of the eight dets computed on its own, the underflow
// term a plain product. The coefficients and the bound must not change by a bit when the cross
// products are shared and the underflow term avoids a subnormal product.
BernsteinCubic reference_trilinear(
    const detail::DifferenceTriple& t0, const detail::DifferenceTriple& t1) {
  struct DetPerm {
    double det, perm;
  };
  const auto det_perm = [](const V& x, const V& y, const V& z) {
    const double cx = y[1] * z[2] - y[2] * z[1];
    const double cy = y[2] * z[0] - y[0] * z[2];
    const double cz = y[0] * z[1] - y[1] * z[0];
    const V ay = y.cwiseAbs();
    const V az = z.cwiseAbs();
    const double px = ay[1] * az[2] + ay[2] * az[1];
    const double py = ay[2] * az[0] + ay[0] * az[2];
    const double pz = ay[0] * az[1] + ay[1] * az[0];
    return DetPerm{
        x[0] * cx + x[1] * cy + x[2] * cz,
        std::abs(x[0]) * px + std::abs(x[1]) * py + std::abs(x[2]) * pz};
  };
  const DetPerm d000 = det_perm(t0.x, t0.y, t0.z), d100 = det_perm(t1.x, t0.y, t0.z),
                d010 = det_perm(t0.x, t1.y, t0.z), d001 = det_perm(t0.x, t0.y, t1.z),
                d011 = det_perm(t0.x, t1.y, t1.z), d101 = det_perm(t1.x, t0.y, t1.z),
                d110 = det_perm(t1.x, t1.y, t0.z), d111 = det_perm(t1.x, t1.y, t1.z);
  BernsteinCubic f;
  f.coefficients = {
      d000.det,
      (d100.det + d010.det + d001.det) / 3.0,
      (d011.det + d101.det + d110.det) / 3.0,
      d111.det};
  const double perm = std::max(
      {d000.perm,
       (d100.perm + d010.perm + d001.perm) / 3.0,
       (d011.perm + d101.perm + d110.perm) / 3.0,
       d111.perm});
  const double relative = detail::rounding_bound(11, perm);
  const double mx = std::max(t0.x.cwiseAbs().maxCoeff(), t1.x.cwiseAbs().maxCoeff());
  volatile double unit = detail::kUnderflowUnit;
  const double underflow = 16 * unit * (1.0 + mx);
  f.error = detail::add_up(relative, underflow);
  return f;
}

TEST(MovingOrientationCubic, SameBitsAsEachDetOnItsOwn) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto point = [&] { return V(u(rng), u(rng), u(rng)); };
  for (int n = 0; n < 20000; ++n) {
    MovingOrientationQuery q{
        point(), point(), point(), point(), point(), point(), point(), point()};
    if (n % 3 == 1) q.q_t1 = q.a_t1 + 0.5 * (q.b_t1 - q.a_t1);  // coplanar at t1, up to rounding
    if (n % 11 == 2) q.b_t0 = q.a_t0;                           // a collapsed side
    const double scale = (n % 5 == 0) ? 1e-6 : (n % 5 == 1) ? 1e6 : (n % 5 == 2) ? 1e-160 : 1.0;
    for (V* p : {&q.a_t0, &q.b_t0, &q.c_t0, &q.q_t0, &q.a_t1, &q.b_t1, &q.c_t1, &q.q_t1})
      *p *= scale;
    const detail::DifferenceTriple t0{q.a_t0 - q.q_t0, q.b_t0 - q.a_t0, q.c_t0 - q.a_t0};
    const detail::DifferenceTriple t1{q.a_t1 - q.q_t1, q.b_t1 - q.a_t1, q.c_t1 - q.a_t1};
    const BernsteinCubic expected = reference_trilinear(t0, t1);
    const BernsteinCubic f = moving_orientation_cubic(q);
    for (std::size_t i = 0; i < 4; ++i) {
      ASSERT_EQ(
          std::bit_cast<std::uint64_t>(f.coefficients[i]),
          std::bit_cast<std::uint64_t>(expected.coefficients[i]))
          << n << " coefficient " << i;
    }
    ASSERT_EQ(std::bit_cast<std::uint64_t>(f.error), std::bit_cast<std::uint64_t>(expected.error))
        << n;
  }
}

TEST(MovingOrientationSign, TheSameAnswerAsTheCubicsSign) {
  // The screened sign against cubic_sign of the full cubic, at every subdivision depth radial
  // view uses, on queries that reach both paths: clear signs (decided by the cheap bound),
  // observers in the plane at one end or both (the exact bound and subdivisions), degenerate
  // triangles, scales whose permanents overflow or underflow, and non-finite coordinates.
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto point = [&] { return V(u(rng), u(rng), u(rng)); };
  int certain = 0, uncertain = 0;
  for (int n = 0; n < 40000; ++n) {
    MovingOrientationQuery q{
        point(), point(), point(), point(), point(), point(), point(), point()};
    if (n % 2 == 0) {
      // Small motions: mostly one side throughout.
      q.a_t1 = q.a_t0 + 0.05 * point();
      q.b_t1 = q.b_t0 + 0.05 * point();
      q.c_t1 = q.c_t0 + 0.05 * point();
      q.q_t1 = q.q_t0 + 0.05 * point();
    }
    if (n % 3 == 1) q.q_t1 = q.a_t1 + 0.5 * (q.b_t1 - q.a_t1);  // coplanar at t1, up to rounding
    if (n % 4 == 2) {
      // Nearly coplanar at both ends: the sign rests on the last bits.
      q.q_t0 = q.a_t0 + 0.25 * (q.b_t0 - q.a_t0) + 0.5 * (q.c_t0 - q.a_t0) + 1e-13 * point();
      q.q_t1 = q.a_t1 + 0.5 * (q.b_t1 - q.a_t1) + 0.25 * (q.c_t1 - q.a_t1) + 1e-13 * point();
    }
    if (n % 11 == 2) q.b_t0 = q.a_t0;  // a collapsed side
    const double scales[] = {1.0, 1e-6, 1e6, 1e-160, 1e100, 1e-310, 1e154};
    const double scale = scales[n % 7];
    const V shift = (n % 13 == 0) ? V(1e6, -1e6, 1e6) : V::Zero();
    for (V* p : {&q.a_t0, &q.b_t0, &q.c_t0, &q.q_t0, &q.a_t1, &q.b_t1, &q.c_t1, &q.q_t1})
      *p = *p * scale + shift;
    if (n % 101 == 7) q.c_t1[1] = std::numeric_limits<double>::quiet_NaN();
    if (n % 103 == 9) q.q_t0[2] = std::numeric_limits<double>::infinity();
    for (const int depth : {0, 2, 4}) {
      const PolynomialSign expected = cubic_sign(moving_orientation_cubic(q), depth);
      ASSERT_EQ(moving_orientation_sign(q, depth), expected) << n << " depth " << depth;
      if (depth == 4) (expected == PolynomialSign::uncertain ? uncertain : certain) += 1;
    }
  }
  // Both kinds of answer were compared, many times.
  EXPECT_GT(certain, 5000);
  EXPECT_GT(uncertain, 5000);
}

}  // namespace
}  // namespace skelcd::ccd
