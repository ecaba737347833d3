// Dop<N> (AABB, 16-DOP): outward rounding proven against exact rationals, inflation, overlap.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "culling/dop.hpp"
#include "tests/culling/exact_dop.hpp"

namespace skelcd::culling {
namespace {

TEST(NextUpDown, MatchNextafterAcrossSignsAndMagnitudes) {
  const double inf = std::numeric_limits<double>::infinity();
  const double values[] = {
      0.0,
      -0.0,
      1.0,
      -1.0,
      1e-310,
      -1e-310,
      3.5e300,
      -3.5e300,
      std::numeric_limits<double>::denorm_min(),
      -std::numeric_limits<double>::denorm_min(),
      std::numeric_limits<double>::min(),
      -std::numeric_limits<double>::min(),
      std::numeric_limits<double>::max(),
      std::numeric_limits<double>::lowest(),
      0.1,
      -0.1,
      1e6,
      -1e-6};
  for (const double v : values) {
    EXPECT_EQ(next_up(v), std::nextafter(v, inf)) << v;
    EXPECT_EQ(next_down(v), std::nextafter(v, -inf)) << v;
  }
}

/// Bounds to round: zeros, float and double subnormals, the float range's ends and beyond, and
/// 20,000 random values over 280 binary orders of magnitude.
std::vector<double> bounds_to_round() {
  const float fmax = std::numeric_limits<float>::max();
  const float fmin = std::numeric_limits<float>::min();
  std::vector<double> values = {
      0.0,
      -0.0,
      1.0,
      -1.0,
      0.1,
      -0.1,
      1.0 + 1e-8,
      1.0 - 1e-8,
      -1.0 - 1e-8,
      1e-40,  // a float subnormal
      -1e-40,
      1e-310,  // a double subnormal
      -1e-310,
      static_cast<double>(fmin),
      -static_cast<double>(fmin),
      static_cast<double>(fmax),
      -static_cast<double>(fmax),
      next_up(static_cast<double>(fmax)),
      next_down(-static_cast<double>(fmax)),
      1e39,
      -1e39,
      3.5e300,
      -3.5e300};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-140, 140);
  for (int i = 0; i < 20000; ++i) values.push_back(std::ldexp(mantissa(rng), exponent(rng)));
  return values;
}

// The traversals' float volumes (culling/bvh.hpp) round each bound outwards to the nearest float
// that is not subnormal: below x for a low end, above for a high end, and no farther than needed.
TEST(FloatBounds, RoundOutwardsToTheNearestNormalFloat) {
  const float fmax = std::numeric_limits<float>::max();
  const float fmin = std::numeric_limits<float>::min();
  const std::vector<double> values = bounds_to_round();
  for (const double x : values) {
    const float lo = float_below(x);
    const float hi = float_above(x);
    ASSERT_LE(static_cast<double>(lo), x) << x;
    ASSERT_GE(static_cast<double>(hi), x) << x;
    // Never subnormal (sound where subnormals are flushed to zero).
    ASSERT_TRUE(lo == 0.0f || std::isinf(lo) || std::abs(lo) >= fmin) << x;
    ASSERT_TRUE(hi == 0.0f || std::isinf(hi) || std::abs(hi) >= fmin) << x;
    // The nearest such float: the next one inwards passes x, unless x is subnormal-small.
    if (std::abs(x) >= static_cast<double>(fmin) && std::abs(x) <= static_cast<double>(fmax)) {
      ASSERT_GT(static_cast<double>(std::nextafter(lo, std::numeric_limits<float>::infinity())), x)
          << x;
      ASSERT_LT(static_cast<double>(std::nextafter(hi, -std::numeric_limits<float>::infinity())), x)
          << x;
    }
    if (static_cast<double>(static_cast<float>(x)) == x &&
        std::abs(x) >= static_cast<double>(fmin)) {
      ASSERT_EQ(static_cast<double>(lo), x);  // a float already: kept
      ASSERT_EQ(static_cast<double>(hi), x);
    }
  }
  EXPECT_EQ(float_above(1e39), std::numeric_limits<float>::infinity());
  EXPECT_EQ(float_below(1e39), fmax);
  EXPECT_EQ(float_above(1e-310), fmin);
  EXPECT_EQ(float_below(1e-310), 0.0f);
  EXPECT_EQ(float_below(-1e-310), -fmin);
}

// A refit rounds whole volumes four bounds at a time (round_outwards, SSE2 where there): the same
// bits as float_below and float_above one by one, for AABBs and 16-DOPs.
template <int N>
void check_round_outwards(const std::vector<double>& values) {
  constexpr auto kN = static_cast<std::size_t>(N);
  for (std::size_t i = 0; i + 2 * kN <= values.size(); i += 2 * kN - 1) {
    Dop<N> v;
    for (std::size_t k = 0; k < kN; ++k) {
      v.lo[k] = values[i + k];
      v.hi[k] = values[i + kN + k];
    }
    std::array<float, kN> lo;
    std::array<float, kN> hi;
    round_outwards(v, lo, hi);
    for (std::size_t k = 0; k < kN; ++k) {
      ASSERT_EQ(
          std::bit_cast<std::uint32_t>(lo[k]), std::bit_cast<std::uint32_t>(float_below(v.lo[k])))
          << v.lo[k];
      ASSERT_EQ(
          std::bit_cast<std::uint32_t>(hi[k]), std::bit_cast<std::uint32_t>(float_above(v.hi[k])))
          << v.hi[k];
    }
  }
}

TEST(FloatBounds, RoundingAWholeVolumeGivesTheSameBitsAsOneBoundAtATime) {
  const std::vector<double> values = bounds_to_round();
  check_round_outwards<3>(values);
  check_round_outwards<8>(values);
}

TEST(Dop, AabbOfPointIsThePointExactly) {
  const Aabb b = Aabb::of_point(0.1, -2.5e-7, 3e5);
  EXPECT_EQ(b.lo, (std::array<double, 3>{0.1, -2.5e-7, 3e5}));
  EXPECT_EQ(b.hi, b.lo);
}

TEST(Dop, KdopOfPointContainsExactProjectionsAndIsAtMostOneUlpWide) {
  // Coordinates from 1e-6 to 1e6 with mixed signs: the diagonal sums round in every direction.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-6, 6);
  int rounded = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x = mantissa(rng) * std::pow(10.0, exponent(rng));
    const double y = mantissa(rng) * std::pow(10.0, exponent(rng));
    const double z = mantissa(rng) * std::pow(10.0, exponent(rng));
    const Kdop16 d = Kdop16::of_point(x, y, z);
    ASSERT_TRUE(test::contains_exactly<8>(d, x, y, z)) << x << " " << y << " " << z;
    for (std::size_t k = 0; k < 8; ++k) {
      EXPECT_LE(d.hi[k], next_up(d.lo[k]));
      if (d.hi[k] != d.lo[k]) ++rounded;
    }
  }
  // The test exercised inexact sums (else it would prove nothing about rounding).
  EXPECT_GT(rounded, 10000);
}

TEST(Dop, InflatedVolumesOverlapWheneverPointsAreWithinTheDistance) {
  // Two points at Euclidean distance <= d: their volumes inflated by d/2 must overlap on every
  // axis, including the diagonal ones whose axis vector is longer than 1.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    Eigen::Vector3d dir(u(rng), u(rng), u(rng));
    dir.normalize();
    const double d = 1e-3 * (1.0 + u(rng));
    const Eigen::Vector3d q = p + 0.999999 * d * dir;
    Aabb a = Aabb::of_point(p);
    Aabb b = Aabb::of_point(q);
    Kdop16 ka = Kdop16::of_point(p);
    Kdop16 kb = Kdop16::of_point(q);
    a.inflate(0.5 * d);
    b.inflate(0.5 * d);
    ka.inflate(0.5 * d);
    kb.inflate(0.5 * d);
    ASSERT_TRUE(a.overlaps(b));
    ASSERT_TRUE(ka.overlaps(kb));
  }
}

TEST(Dop, InflationDoesNotOverlapPointsClearlyFartherApart) {
  Aabb a = Aabb::of_point(0, 0, 0);
  Aabb b = Aabb::of_point(1.0, 0, 0);
  a.inflate(0.49);
  b.inflate(0.49);
  EXPECT_FALSE(a.overlaps(b));
  a.inflate(0.02);
  b.inflate(0.02);
  EXPECT_TRUE(a.overlaps(b));
  // Along the diagonal x+y, points at distance 1 apart differ by sqrt(2) in projection.
  Kdop16 c = Kdop16::of_point(0, 0, 0);
  Kdop16 e = Kdop16::of_point(std::sqrt(0.5), std::sqrt(0.5), 0);
  c.inflate(0.49);
  e.inflate(0.49);
  EXPECT_FALSE(c.overlaps(e));
}

TEST(Dop, OverlapIsClosedAndMergeContains) {
  const Aabb a = Aabb::of_point(0, 0, 0);
  Aabb b = Aabb::of_point(1, 1, 1);
  EXPECT_FALSE(a.overlaps(b));
  Aabb m = a;
  m.merge(b);
  EXPECT_TRUE(m.contains(a));
  EXPECT_TRUE(m.contains(b));
  EXPECT_FALSE(a.contains(m));
  // Touching at one corner counts as overlap.
  EXPECT_TRUE(m.overlaps(Aabb::of_point(1, 1, 1)));
  EXPECT_TRUE(Aabb::of_point(1, 1, 1).overlaps(m));
  // The empty volume is merge's identity and overlaps nothing.
  Aabb e = Aabb::empty();
  EXPECT_FALSE(e.overlaps(m));
  e.merge(b);
  EXPECT_EQ(e.lo, b.lo);
  EXPECT_EQ(e.hi, b.hi);
}

}  // namespace
}  // namespace skelcd::culling
